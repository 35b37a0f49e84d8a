"""Scene loading: built-in names, gi's JSON scene files, Mitsuba 3 XML scenes, or a glTF
file's default scene.

The JSON format is documented in ``docs/scene-format.md``; the Rust core validates every
field. Mesh files named by a scene are resolved relative to it and read by
:mod:`gi.meshes` (OBJ with MTL, PLY, glTF/GLB, STL), environment images by
:mod:`gi.environment` (OpenImageIO). Mitsuba scenes are translated by
:mod:`gi.mitsuba` (``docs/mitsuba.md``). A ``.gltf``/``.glb`` file loaded as a scene keeps
its nodes that share a mesh as instances of one mesh (:func:`load_gltf_scene`); named as a
mesh file by a JSON scene it is one mesh of world-space triangles (:func:`gi.gltf.load_gltf`).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from gi._gi import GiError, OutOfMemoryError, Scene, builtin_scenes
from gi._placement import first_bad_placement
from gi.environment import load_environment
from gi.gltf import DEFAULT_MATERIAL_NAME, GltfError, default_material, read_gltf
from gi.meshes import MeshEntry, _entry, _unit_rows, load_failure, load_mesh, report
from gi.meshes import scene_error as _scene_error
from gi.mitsuba import load_mitsuba
from gi.textures import TextureError, TextureSet


class SceneWarning(UserWarning):
    """A scene that renders, but not as meant: no lights (the image is black), no objects;
    ``file`` and ``field`` say where."""

    def __init__(self, file: str, field: str, reason: str):
        super().__init__(f"{file}: {field}: {reason}")
        self.file = file
        self.field = field
        self.reason = reason


#: Material texture fields and whether they hold colours (sRGB-decoded from integer files).
TEXTURE_FIELDS = {
    "diffuse_texture": True,
    "specular_texture": True,
    "roughness_texture": False,
    "normal_texture": False,
    "alpha_texture": False,
    "emission_texture": True,
}


def load_scene(source: str | Path) -> Scene:
    """Loads a built-in scene by name (see :func:`gi.builtin_scenes`), a JSON scene file, a
    Mitsuba 3 XML scene (``.xml``) or a glTF file's default scene (``.gltf``, ``.glb``:
    :func:`load_gltf_scene`).

    Raises :class:`gi.SceneError` (with ``file``, ``field`` and ``reason`` attributes) for a
    missing or malformed file, an unknown field or element, a missing or unreadable mesh,
    non-finite geometry, a degenerate camera or a negative intensity. What a file holds that
    gi does not render (textures, emission, vertex colours) gives a :class:`gi.AssetWarning`.
    """
    path = Path(source)
    file = str(path)
    names = [n for n, _ in builtin_scenes()]
    try:
        exists, is_file = path.exists(), path.is_file()
    except (OSError, ValueError) as e:  # a name too long, a NUL byte
        raise _scene_error(file, "(file)", f"cannot read: {e}") from e
    if not exists and str(source) in names:
        return Scene.builtin(str(source))
    if not is_file:
        hint = f" (built-in scenes: {', '.join(names)})" if path.suffix == "" else ""
        raise _scene_error(file, "(file)", f"no such scene file{hint}")
    if path.suffix.lower() == ".xml":
        return load_mitsuba(path)
    if path.suffix.lower() in (".gltf", ".glb"):
        return load_gltf_scene(path)
    try:
        text = path.read_text(encoding="utf-8")
        desc = json.loads(text)
    except (OSError, UnicodeDecodeError) as e:
        raise _scene_error(file, "(file)", f"cannot read: {e}") from e
    except json.JSONDecodeError as e:
        raise _scene_error(
            file, f"(line {e.lineno}, column {e.colno})", f"invalid JSON: {e.msg}"
        ) from e
    except RecursionError as e:
        raise _scene_error(file, "(root)", "invalid JSON: nested too deeply") from e
    except MemoryError as e:
        raise _scene_error(file, "(file)", "too large to parse") from e
    return scene_from_desc(desc, file, path.parent, text)


def scene_from_desc(
    desc: dict[str, Any], source: str, base_dir: Path, text: str | None = None
) -> Scene:
    """A scene from a parsed scene description (the JSON format of ``load_scene``), its mesh,
    texture and environment files relative to ``base_dir``; ``source`` names it in
    errors. ``text``: the description as read (used unless texture names are rewritten)."""
    textures = TextureSet(base_dir)
    meshes, lights = _load_meshes(desc, base_dir, source, textures)
    if lights and isinstance(desc.get("lights", []), list):
        # Lights from mesh files (glTF KHR_lights_punctual) follow the scene's own.
        desc["lights"] = [*desc.get("lights", []), *lights]
        text = None
    images = load_environment(desc, base_dir, source)
    if _load_material_textures(desc, base_dir, source, textures) or text is None:
        text = json.dumps(desc)
    return Scene.from_json(text, source, meshes, images, textures=textures.arrays)


def _load_material_textures(desc: Any, base_dir: Path, file: str, textures: TextureSet) -> bool:
    """Reads the images the scene's materials name (relative to ``base_dir``) and renames
    the fields to the loaded textures; whether anything was renamed."""
    mats = desc.get("materials") if isinstance(desc, dict) else None
    changed = False
    for name, mat in (mats or {}).items() if isinstance(mats, dict) else []:
        if not isinstance(mat, dict):
            continue
        for field, colour in TEXTURE_FIELDS.items():
            value = mat.get(field)
            if not isinstance(value, str):
                continue  # the core reports a mistyped field
            try:
                mat[field] = textures.add(base_dir / value, colour)
            except (TextureError, OSError, ValueError) as e:
                raise _scene_error(file, f"materials.{name}.{field}", str(e)) from e
            changed = True
    return changed


def _load_meshes(
    desc: Any, base_dir: Path, file: str, textures: TextureSet
) -> tuple[dict[str, MeshEntry], list[dict[str, Any]]]:
    """The mesh files the objects name, and the lights those files hold placed by each
    object's transform (an object that uses a file twice places its lights twice)."""
    meshes: dict[str, MeshEntry] = {}
    file_lights: dict[str, list[dict[str, Any]]] = {}
    placed: list[dict[str, Any]] = []
    objects = desc.get("objects", []) if isinstance(desc, dict) else []
    for i, obj in enumerate(objects if isinstance(objects, list) else []):
        shape = obj.get("shape") if isinstance(obj, dict) else None
        if not isinstance(shape, dict) or shape.get("type") != "mesh":
            continue
        name = shape.get("file")
        if not isinstance(name, str):
            continue  # the core reports a missing or mistyped `file`
        if name not in meshes:
            found: list[dict[str, Any]] = []
            field = f"objects[{i}].shape.file"
            meshes[name] = load_mesh(base_dir / name, file, field, textures, found)
            file_lights[name] = found
        if file_lights[name]:
            matrix = _object_matrix(obj.get("transform"))
            if matrix is not None:  # else the core reports the transform
                placed += [_place_light(light, matrix) for light in file_lights[name]]
    return meshes, placed


def _object_matrix(transform: Any) -> np.ndarray | None:
    """An object's transform as the core builds it (scale, rotate about x, y, z in degrees,
    translate; or its ``matrix`` rows); None if it is malformed."""
    if transform is None:
        return np.eye(4)
    if isinstance(transform, dict) and "matrix" in transform:
        try:
            rows = np.asarray(transform["matrix"], dtype=np.float64)
        except (TypeError, ValueError):
            return None
        if rows.shape not in ((3, 4), (4, 4)) or not np.isfinite(rows).all():
            return None
        m = np.eye(4)
        m[:3] = rows[:3]
        return m
    try:
        t = np.asarray(transform.get("translate", [0, 0, 0]), dtype=np.float64).reshape(3)
        rx, ry, rz = (math.radians(float(a)) for a in transform.get("rotate", [0, 0, 0]))
        s = np.broadcast_to(np.asarray(transform.get("scale", 1), dtype=np.float64), (3,))
    except (AttributeError, TypeError, ValueError):
        return None

    def rot(axis: int, a: float) -> np.ndarray:
        c, sn = math.cos(a), math.sin(a)
        i, j = (axis + 1) % 3, (axis + 2) % 3
        r = np.eye(3)
        r[i, i], r[i, j], r[j, i], r[j, j] = c, -sn, sn, c
        return r

    m = np.eye(4)
    m[:3, :3] = rot(2, rz) @ rot(1, ry) @ rot(0, rx) @ np.diag(s)
    m[:3, 3] = t
    return m


def _place_light(light: dict[str, Any], matrix: np.ndarray) -> dict[str, Any]:
    """A light in a mesh file's coordinates moved into the scene by its object's matrix."""
    out = dict(light)
    if "position" in out:
        out["position"] = (matrix[:3, :3] @ np.asarray(out["position"]) + matrix[:3, 3]).tolist()
    if "direction" in out:
        d = matrix[:3, :3] @ np.asarray(out["direction"], dtype=np.float64)
        with np.errstate(all="ignore"):
            out["direction"] = np.nan_to_num(d / np.linalg.norm(d)).tolist()
    return out


def load_gltf_scene(path: str | Path) -> Scene:
    """A glTF file's default scene (see :func:`gltf_scene_description`)."""
    path = Path(path)
    desc, meshes, textures = gltf_scene_description(path)
    return Scene.from_json(json.dumps(desc), str(path), meshes, {}, textures=textures.arrays)


def gltf_scene_description(
    path: Path,
) -> tuple[dict[str, Any], dict[str, MeshEntry], TextureSet]:
    """A glTF file's default scene as a gi scene description, its mesh arrays and textures.

    Each primitive of a glTF mesh becomes one gi mesh in the mesh's own frame (keyed
    ``file#meshes[m].primitives[p]``), and each node that uses the mesh one object per
    primitive placed by the node's world matrix (a ``matrix`` transform, named
    ``nodes[n]`` or ``nodes[n].primitives[p]``; ``nodes[n].instances[k]`` first for the
    placements of ``EXT_mesh_gpu_instancing``): nodes that share a glTF mesh share its gi
    meshes. Materials (with textures and emission), ``KHR_lights_punctual`` lights and the
    warnings are those of :func:`gi.gltf.load_gltf`; a primitive without a material gets
    glTF's default one. The camera is the default scene's first perspective camera (its
    ``aspectRatio`` sets the width against a height of 512 pixels); without one, a 40°
    camera on +z looks at the centre of the scene's box from where the box fits.

    Every failure is typed: :class:`gi.SceneError` naming the file's field (``nodes[3]``)
    or the file, :class:`gi.OutOfMemoryError`."""
    file = str(path)
    try:
        return _gltf_scene_description(path)
    except (GiError, Warning):  # a warning the caller turned into an error stays one
        raise
    except GltfError as e:
        raise _scene_error(file, e.field, e.reason) from e
    except MemoryError as e:
        raise OutOfMemoryError(f"{file}: the glTF scene is too large: {e}") from e
    except Exception as e:  # content the reader accepted but numpy could not convert
        raise _scene_error(file, "(file)", load_failure(path, e)) from e


def _gltf_scene_description(
    path: Path,
) -> tuple[dict[str, Any], dict[str, MeshEntry], TextureSet]:
    file = str(path)
    textures = TextureSet(path.parent)
    g = read_gltf(path, textures)
    report(path, g.warnings)
    materials = {name: desc for name, desc in g.materials}
    default = f"{path.name}:{DEFAULT_MATERIAL_NAME}"
    meshes: dict[str, MeshEntry] = {}
    objects: list[dict[str, Any]] = []
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    mats = np.array([inst.matrix for inst in g.instances]).reshape(-1, 4, 4)
    _check_node_matrices(file, [inst.node for inst in g.instances], mats)
    rows = mats[:, :3].tolist()
    keys = {
        (mi, p.index): f"{path.name}#meshes[{mi}].primitives[{p.index}]"
        for mi, prims in g.meshes.items()
        for p in prims
    }
    for inst, m in zip(g.instances, rows, strict=True):
        prims = g.meshes[inst.mesh]
        for prim in prims:
            key = keys[inst.mesh, prim.index]
            if key not in meshes:
                normals = None if prim.normals is None else _unit_rows(prim.normals)
                meshes[key] = _entry(
                    path,
                    file,
                    key,
                    prim.vertices,
                    prim.faces,
                    normals,
                    [],
                    None,
                    prim.uvs,
                    prim.tangents,
                )
            if prim.material < 0:
                materials.setdefault(default, default_material())
            name = f"nodes[{inst.node}]"
            if inst.instance is not None:
                name += f".instances[{inst.instance}]"
            objects.append(
                {
                    "name": name if len(prims) == 1 else f"{name}.primitives[{prim.index}]",
                    "shape": {"type": "mesh", "file": key},
                    "material": default if prim.material < 0 else g.materials[prim.material][0],
                    "transform": {"matrix": m},
                }
            )
    # The box of every mesh's box corners placed (a box around the placed vertices, for the
    # framing camera): O(1) per instance.
    mesh_ids = np.array([inst.mesh for inst in g.instances])
    for mi, prims in g.meshes.items():
        if not prims:
            continue
        v = np.concatenate([p.vertices for p in prims])
        a, b = v.min(axis=0), v.max(axis=0)
        corners = np.array([[(a, b)[k >> i & 1][i] for i in range(3)] for k in range(8)])
        sel = mats[mesh_ids == mi]
        placed = np.einsum("kj,nij->nki", corners, sel[:, :3, :3]) + sel[:, None, :3, 3]
        lo = np.minimum(lo, placed.min(axis=(0, 1)))
        hi = np.maximum(hi, placed.max(axis=(0, 1)))
    # A node reached twice (one node the child of two) would name two objects alike.
    seen: set[str] = set()
    for obj in objects:
        if obj["name"] in seen:
            del obj["name"]
        else:
            seen.add(obj["name"])
    desc: dict[str, Any] = {
        "camera": _gltf_camera(g.camera, lo, hi),
        "lights": g.lights,
        "materials": materials,
        "objects": objects,
    }
    return desc, meshes, textures


def _check_node_matrices(file: str, nodes: list[int], m: np.ndarray) -> None:
    """Nodes' world matrices (n, 4, 4) checked as the core checks a ``matrix`` transform,
    so that the error names the node."""
    bad = first_bad_placement(m)
    if bad is not None:
        raise _scene_error(file, f"nodes[{nodes[bad[0]]}]", f"the world transform {bad[1]}")


def _gltf_camera(cam: Any, lo: np.ndarray, hi: np.ndarray) -> dict[str, Any]:
    """The scene's camera from a glTF camera, else one framing the box ``lo``..``hi``."""
    if cam is not None:
        width = 512 if cam.aspect is None else max(1, round(512 * cam.aspect))
        return {
            "position": cam.position,
            "look_at": cam.look_at,
            "up": cam.up,
            "fov": min(max(cam.yfov, 1.0), 179.0),
            "width": width,
            "height": 512,
        }
    if not (lo <= hi).all():
        lo, hi = np.zeros(3), np.zeros(3)
    centre = (lo + hi) / 2
    radius = max(float(np.linalg.norm(hi - lo)) / 2, 1e-3)
    distance = radius / math.sin(math.radians(20.0))
    return {
        "position": (centre + [0.0, 0.0, distance]).tolist(),
        "look_at": centre.tolist(),
        "fov": 40.0,
    }
