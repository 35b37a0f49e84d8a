"""Scene loading: built-in names, gi's JSON scene files, or Mitsuba 3 XML scenes.

The JSON format is documented in ``docs/scene-format.md``; the Rust core validates every
field. Mesh files named by a scene are resolved relative to it and read by
:mod:`gi.meshes` (OBJ with MTL, PLY, glTF/GLB, STL), environment images by
:mod:`gi.environment` (OpenImageIO). Mitsuba scenes are translated by
:mod:`gi.mitsuba` (``docs/mitsuba.md``).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from gi._gi import Scene, builtin_scenes
from gi.environment import load_environment
from gi.meshes import MeshEntry, load_mesh
from gi.meshes import scene_error as _scene_error
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
    """Loads a built-in scene by name (see :func:`gi.builtin_scenes`), a JSON scene file or a
    Mitsuba 3 XML scene (``.xml``).

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
        from gi.mitsuba import load_mitsuba

        return load_mitsuba(path)
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
    translate); None if it is malformed."""
    if transform is None:
        return np.eye(4)
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
