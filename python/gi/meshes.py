"""Mesh files into the arrays the core takes: glTF by gi's own reader (:mod:`gi.gltf`), OBJ,
PLY and STL by trimesh, MTL materials by :func:`parse_mtl`.

Normals are taken only where a file stores them; the core shades the rest flat (or as the
object's ``smooth`` asks), so no normals are computed here and trimesh never needs scipy.
Texture maps are read into a :class:`gi.textures.TextureSet` (see ``docs/scene-format.md``);
what a file holds that gi does not render (vertex colours, some maps) is reported once per
file and field as an :class:`AssetWarning`. Emission (MTL ``Ke``/``map_Ke``, glTF's emissive
factor, texture and strength) becomes the materials' ``emission``; glTF punctual lights are
returned for the scene to place (:func:`load_mesh`'s ``lights``).
"""

from __future__ import annotations

import json
import math
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from gi._gi import GiError, OutOfMemoryError, SceneError
from gi.gltf import GltfError, load_gltf
from gi.textures import TextureError, TextureSet, height_to_normal

# (vertices, faces, normals, materials JSON, face materials, uvs[, tangents]): `gi._gi.pyi`
MeshEntry = tuple[Any, ...]


class AssetWarning(UserWarning):
    """A mesh or scene file holds something gi does not render (some texture maps, vertex
    colours, light ranges...); ``file`` and ``field`` say what."""

    def __init__(self, file: str, field: str, reason: str):
        super().__init__(f"{file}: {field}: {reason}")
        self.file = file
        self.field = field
        self.reason = reason


def scene_error(file: str, field: str, reason: str) -> SceneError:
    """A :class:`gi.SceneError` with ``file``, ``field`` and ``reason``; a field that names
    no field (``(file)``, ``(root)``: the whole file) is left out of the message."""
    where = f"{file}: " if field in ("(file)", "(root)") else f"{file}: {field}: "
    err = SceneError(f"{where}{reason}")
    err.file = file  # type: ignore[attr-defined]
    err.field = field  # type: ignore[attr-defined]
    err.reason = reason  # type: ignore[attr-defined]
    return err


def report(file: Path | str, notes: dict[str, str]) -> None:
    """One :class:`AssetWarning` per field of ``notes`` (field -> what gi does instead)."""
    for field, reason in notes.items():
        warnings.warn(AssetWarning(str(file), field, reason), stacklevel=5)


def _unit_rows(n: np.ndarray) -> np.ndarray:
    with np.errstate(all="ignore"):
        n = n / np.linalg.norm(n, axis=1, keepdims=True)
    return np.nan_to_num(n, nan=0.0, posinf=0.0, neginf=0.0)


# MTL texture maps gi reads (key -> role); others (map_Ka, disp, decal, refl) are
# reported. `bump`/`map_bump` hold a height map or a normal map (told apart by content).
_MTL_MAPS = {
    "map_kd": "diffuse",
    "map_ks": "specular",
    "map_ns": "shininess",
    "map_pr": "roughness",
    "map_d": "alpha",
    "map_ke": "emission",
    "map_bump": "bump",
    "bump": "bump",
    "norm": "normal",
}
_MTL_TEXTURES = ("bump", "norm", "disp", "decal", "refl")


def _map_file(args: list[str]) -> tuple[str, float]:
    """The file name of an MTL map statement (after options such as ``-bm 1.0``) and its
    bump multiplier."""
    bm, i = 1.0, 0
    takes = {"-bm": 1, "-blendu": 1, "-blendv": 1, "-boost": 1, "-cc": 1, "-clamp": 1}
    takes |= {"-imfchan": 1, "-texres": 1, "-type": 1, "-mm": 2, "-o": 3, "-s": 3, "-t": 3}
    while i < len(args) and args[i].startswith("-") and args[i].lower() in takes:
        n = takes[args[i].lower()]
        if args[i].lower() == "-bm" and i + 1 < len(args):
            try:
                bm = float(args[i + 1])
            except ValueError:
                pass
        i += 1 + n
    return " ".join(args[i:]), bm


def parse_mtl(path: Path, notes: dict[str, str]) -> dict[str, dict[str, Any]]:
    """An MTL file's materials as uber-BSDF descriptions, keyed by name; texture maps as
    ``_maps`` (role -> (file, bump multiplier)). ``Ke`` is the emitted radiance
    (W·sr⁻¹·m⁻², from both faces: MTL has no front face for emission). Unsupported fields
    (some maps, dissolve ``d``/``Tr`` without a map) are added to ``notes``."""
    out: dict[str, dict[str, Any]] = {}
    try:
        lines = path.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError as e:
        notes[f"mtllib {path.name}"] = f"cannot read ({e.strerror}); materials are missing"
        return out
    cur: dict[str, Any] | None = None
    name = ""
    for line in lines:
        parts = line.split()
        if len(parts) < 2 or parts[0].startswith("#"):
            continue
        key, args = parts[0].lower(), parts[1:]
        if key == "newmtl":
            name = " ".join(args)
            cur = out.setdefault(name, {"diffuse": [0.8, 0.8, 0.8]})
            continue
        if cur is None:
            continue
        where = f"{path.name}: newmtl {name}: {parts[0]}"
        if key in _MTL_MAPS:
            file, bm = _map_file(args)
            if file:
                cur.setdefault("_maps", {})[_MTL_MAPS[key]] = (path.parent / file, bm, where)
            continue
        try:
            vals = [float(x) for x in args[:3]] if not key.startswith("map_") else []
        except ValueError:
            notes[where] = "not a number; ignored"
            continue
        rgb = [min(max(v, 0.0), 1.0) for v in (vals * 3)[:3]] if vals else []
        if key == "kd":
            cur["diffuse"] = rgb
        elif key == "ks":
            cur["specular"] = rgb
        elif key == "ns" and "roughness" not in cur:
            # Blinn-Phong exponent to GGX: alpha = sqrt(2 / (n + 2)); roughness = sqrt(alpha).
            cur["_ns"] = math.sqrt(math.sqrt(2.0 / (max(vals[0], 0.0) + 2.0)))
            cur["_nsexp"] = max(vals[0], 0.0)
        elif key == "pr":
            cur["roughness"] = min(max(vals[0], 0.0), 1.0)
            cur["_pr"] = True
        elif key == "ke":
            cur["_ke"] = [max(v, 0.0) for v in (vals * 3)[:3]]
        elif key in ("d", "tr") and (vals[0] < 1.0 if key == "d" else vals[0] > 0.0):
            notes[where] = "dissolve (transparency) is not supported; the surface is opaque"
        elif key.startswith("map_") or key in _MTL_TEXTURES:
            notes[where] = "this texture map is not supported; it is ignored"
    for desc in out.values():
        ke = desc.pop("_ke", None)
        if ke is None and "emission" in desc.get("_maps", {}):
            ke = [1.0, 1.0, 1.0]  # map_Ke alone: the map is the radiance
        if ke is not None and max(ke) > 0:
            desc["emission"] = ke
            desc["two_sided"] = True
        ns = desc.pop("_ns", None)
        if max(desc.get("specular", [0.0])) > 0:
            desc.setdefault("roughness", ns if ns is not None else 0.0)
        else:
            desc.pop("specular", None)
            desc.pop("roughness", None)
    return out


def _shininess_to_roughness(exponent: np.ndarray) -> np.ndarray:
    """Blinn-Phong exponent to GGX roughness, as for a constant ``Ns``."""
    return np.sqrt(np.sqrt(2.0 / (np.maximum(exponent, 0.0) + 2.0)))


def apply_mtl_maps(
    desc: dict[str, Any], textures: TextureSet, notes: dict[str, str]
) -> dict[str, Any]:
    """An MTL material description with its maps read into ``textures`` (a map that cannot
    be read is reported and left out); the private keys of :func:`parse_mtl` removed."""
    out = {k: v for k, v in desc.items() if not k.startswith("_")}
    has_spec = "specular" in out
    for role, (file, bm, where) in desc.get("_maps", {}).items():
        try:
            if role == "diffuse":
                out["diffuse_texture"] = textures.add(file, True)
            elif role == "emission" and "emission" in out:
                out["emission_texture"] = textures.add(file, True)
            elif role == "specular" and has_spec:
                out["specular_texture"] = textures.add(file, True)
            elif role == "shininess" and has_spec:
                key = textures.add(file, False)
                img = textures.arrays[key]
                rough = _shininess_to_roughness(desc.get("_nsexp", 0.0) * img[..., 0])
                baked = np.repeat(rough[..., None], 4, axis=2).astype(np.float32)
                out["roughness_texture"] = textures.add_array(f"{key}#roughness", baked)
                out["roughness"] = 1.0
            elif role == "roughness" and has_spec:
                out["roughness_texture"] = textures.add(file, False)
                if not desc.get("_pr"):
                    out["roughness"] = 1.0
            elif role == "alpha":
                key = textures.add(file, False)
                if textures.channels(key) in (1, 3):  # coverage is the grey value
                    img = textures.arrays[key].copy()
                    img[..., 3] = img[..., 0]
                    key = textures.add_array(f"{key}#coverage", img)
                out["alpha_texture"] = key
                out["alpha_cutoff"] = 0.5
            elif role in ("bump", "normal"):
                key = textures.add(file, False)
                img = textures.arrays[key]
                looks_normal = textures.channels(key) >= 3 and (
                    img[..., 2].mean() > 0.7 and abs(img[..., :2].mean() - 0.5) < 0.15
                )
                if role == "bump" and not looks_normal:
                    baked = height_to_normal(img[..., 0].astype(np.float64), bm)
                    key = textures.add_array(f"{key}#normal{bm}", baked)
                out["normal_texture"] = key
        except (TextureError, OSError) as e:
            notes[where] = f"cannot read the map ({e}); it is ignored"
    return out


def _mtllibs(path: Path) -> list[Path]:
    with open(path, "rb") as f:
        text = f.read()
    libs = re.findall(rb"^[ \t]*mtllib[ \t]+(.+?)[ \t]*\r?$", text, flags=re.MULTILINE)
    return [path.parent / lib.decode("utf-8", errors="replace") for lib in libs]


def _obj_colours(path: Path) -> bool:
    """Whether an OBJ stores vertex colours (``v x y z r g b``)."""
    with open(path, "rb") as f:
        text = f.read()
    return re.search(rb"^v[ \t]+(\S+[ \t]+){5}\S+", text, flags=re.MULTILINE) is not None


def load_mesh(
    path: Path,
    scene_file: str,
    field: str,
    textures: TextureSet | None = None,
    lights: list[dict[str, Any]] | None = None,
) -> MeshEntry:
    """Loads a mesh file into the arrays the core takes (see ``Scene.from_json``); the
    textures its materials use go into ``textures``, the lights it holds (glTF
    ``KHR_lights_punctual``, in the file's coordinates) into ``lights`` (without a list
    they are reported as ignored).

    Every failure is a typed error: :class:`gi.SceneError` naming the scene's field (a
    malformed file trimesh or numpy choke on included), :class:`gi.OutOfMemoryError`."""
    try:
        is_file = path.is_file()
    except (OSError, ValueError) as e:  # a name too long, a NUL byte
        raise scene_error(scene_file, field, f"cannot read mesh file {path}: {e}") from e
    if not is_file:
        raise scene_error(scene_file, field, f"mesh file not found: {path}")
    try:
        textures = TextureSet() if textures is None else textures
        if path.suffix.lower() in (".gltf", ".glb"):
            return _load_gltf(path, scene_file, field, textures, lights)
        return _load_trimesh(path, scene_file, field, textures)
    except GiError:
        raise
    except MemoryError as e:
        raise OutOfMemoryError(f"{scene_file}: {field}: mesh {path} is too large: {e}") from e
    except Exception as e:  # content the loaders accepted but numpy could not convert
        raise scene_error(scene_file, field, load_failure(path, e)) from e


def load_failure(path: Path, e: BaseException) -> str:
    """What a mesh reader's exception means to the user: the file is unreadable, truncated
    or malformed (the reader's own words follow in brackets)."""
    if isinstance(e, OSError) and not isinstance(e, GiError):
        return f"cannot read mesh file {path}: {e.strerror or e}"
    kind = path.suffix.lstrip(".").upper() or "mesh"
    return (
        f"{path} is not a valid {kind} file: it is truncated or malformed (the reader"
        f" stopped with {type(e).__name__}: {e})"
    )


def _entry(
    path: Path,
    scene_file: str,
    field: str,
    verts: np.ndarray,
    faces: np.ndarray,
    normals: np.ndarray | None,
    materials: list[tuple[str, dict[str, Any]]],
    face_mats: np.ndarray | None,
    uvs: np.ndarray | None = None,
    tangents: np.ndarray | None = None,
) -> MeshEntry:
    if len(faces) == 0:
        raise scene_error(scene_file, field, f"mesh file has no triangles: {path}")
    if faces.min() < 0 or faces.max() >= len(verts):
        bad = int(np.flatnonzero(((faces < 0) | (faces >= len(verts))).any(axis=1))[0])
        raise scene_error(
            scene_file,
            field,
            f"{path}: face {bad} indexes a vertex out of range (the mesh has {len(verts)})",
        )
    if not np.isfinite(verts).all():
        bad = int(np.flatnonzero(~np.isfinite(verts).all(axis=1))[0])
        raise scene_error(
            scene_file, field, f"{path}: vertex {bad} is not finite (NaN or infinity)"
        )
    if materials and face_mats is not None and (face_mats < 0).any():
        # Parts the file gives no (known) material get the format's default one.
        materials = [*materials, (f"{path.name}:(default)", {})]
        face_mats = np.where(face_mats < 0, len(materials) - 1, face_mats)
    has_mats = bool(materials) and face_mats is not None
    return (
        np.ascontiguousarray(verts, dtype=np.float32),
        np.ascontiguousarray(faces, dtype=np.uint32),
        None if normals is None else np.ascontiguousarray(normals, dtype=np.float32),
        json.dumps(materials) if has_mats else None,
        np.ascontiguousarray(face_mats, dtype=np.uint32) if has_mats else None,
        None if uvs is None else np.ascontiguousarray(uvs, dtype=np.float32),
        *([] if tangents is None else [np.ascontiguousarray(tangents, dtype=np.float32)]),
    )


def _load_gltf(
    path: Path,
    scene_file: str,
    field: str,
    textures: TextureSet,
    lights: list[dict[str, Any]] | None,
) -> MeshEntry:
    try:
        m = load_gltf(path, textures)
    except GltfError as e:
        raise scene_error(scene_file, field, f"{path}: {e.field}: {e.reason}") from e
    except (OSError, ValueError, KeyError, IndexError, TypeError) as e:
        raise scene_error(scene_file, field, f"cannot load glTF {path}: {e!r}") from e
    if lights is not None:
        lights.extend(m.lights)
    elif m.lights:
        m.warnings["extensions.KHR_lights_punctual"] = "lights are read in gi scene files only"
    report(path, m.warnings)
    return _entry(
        path,
        scene_file,
        field,
        m.vertices,
        m.faces,
        m.normals,
        m.materials,
        m.face_materials,
        m.uvs,
        m.tangents,
    )


def _load_trimesh(path: Path, scene_file: str, field: str, textures: TextureSet) -> MeshEntry:
    import trimesh

    try:
        loaded = trimesh.load(str(path), force="scene", process=False)
    except Exception as e:  # trimesh raises many types for bad files
        raise scene_error(scene_file, field, load_failure(path, e)) from e
    notes: dict[str, str] = {}
    mtl: dict[str, dict[str, Any]] = {}
    is_obj = path.suffix.lower() == ".obj"
    if is_obj:
        for lib in _mtllibs(path):
            mtl.update(parse_mtl(lib, notes))
        if _obj_colours(path):
            notes["v (vertex colours)"] = "vertex colours are not supported"
    verts, faces, normals, face_mats, uvs = [], [], [], [], []
    materials: list[tuple[str, dict[str, Any]]] = []
    index: dict[str, int] = {}
    offset = 0
    for node in loaded.graph.nodes_geometry:
        transform, geom_name = loaded.graph[node]
        geom = loaded.geometry[geom_name]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        xf = np.asarray(transform, dtype=np.float64)
        lin = xf[:3, :3]
        with np.errstate(all="ignore"):
            det = np.linalg.det(lin) if np.isfinite(xf).all() else np.nan
        if not (np.isfinite(det) and abs(det) > 1e-30):
            raise scene_error(
                scene_file,
                field,
                f"{path}: a node transform is singular or not finite (e.g. a zero scale)",
            )
        f = np.asarray(geom.faces, dtype=np.int64)
        if np.linalg.det(lin) < 0:  # a mirroring transform turns the winding inside out
            f = f[:, [0, 2, 1]]
        v = np.asarray(geom.vertices, dtype=np.float64)
        verts.append(v @ lin.T + xf[:3, 3])
        # Only normals stored in the file: reading `vertex_normals` would compute them
        # (slowly without scipy) when the file has none.
        if "vertex_normals" in geom._cache:
            with np.errstate(all="ignore"):
                normal_xf = np.linalg.inv(lin).T
            normals.append(_unit_rows(np.asarray(geom.vertex_normals, np.float64) @ normal_xf.T))
        else:
            normals.append(None)
        faces.append(f + offset)
        offset += len(v)
        uv = getattr(geom.visual, "uv", None)
        if uv is not None and len(uv) == len(v):
            # OBJ's v runs up the image, gi's down.
            uv = np.nan_to_num(np.asarray(uv, np.float64)[:, :2])
            uvs.append(np.stack([uv[:, 0], 1.0 - uv[:, 1]], axis=1))
        else:
            uvs.append(np.zeros((len(v), 2)))
        kind = getattr(geom.visual, "kind", None)
        if kind in ("vertex", "face") and not is_obj:
            notes[f"{kind} colours"] = f"{kind} colours are not supported"
        mat = getattr(geom.visual, "material", None)
        name = getattr(mat, "name", None)
        if is_obj and name in mtl:
            if name not in index:
                index[name] = len(materials)
                desc = apply_mtl_maps(mtl[name], textures, notes)
                materials.append((f"{path.name}:{name}", desc))
            face_mats.append(np.full(len(f), index[name], np.int64))
        else:
            face_mats.append(np.full(len(f), -1, np.int64))
    report(path, notes)
    if not faces:
        raise scene_error(scene_file, field, f"mesh file has no triangles: {path}")
    any_normals = any(n is not None for n in normals)
    return _entry(
        path,
        scene_file,
        field,
        np.concatenate(verts),
        np.concatenate(faces),
        (
            np.concatenate(
                [
                    n if n is not None else np.zeros_like(v)
                    for n, v in zip(normals, verts, strict=True)
                ]
            )
            if any_normals
            else None
        ),
        materials,
        np.concatenate(face_mats),
        np.concatenate(uvs),
    )
