"""Scene loading: built-in names, or JSON scene files whose mesh objects are loaded with trimesh.

The JSON format is documented in ``docs/scene-format.md``; the Rust core validates every
field. This module resolves mesh files (relative to the scene file), loads them with trimesh
(OBJ with MTL, PLY, glTF/GLB, STL) and hands their arrays to the core.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from gi._gi import Scene, SceneError, builtin_scenes

MeshEntry = tuple[Any, Any, Any, "str | None", Any]


def _scene_error(file: str, field: str, reason: str) -> SceneError:
    err = SceneError(f"{file}: {field}: {reason}")
    err.file = file  # type: ignore[attr-defined]
    err.field = field  # type: ignore[attr-defined]
    err.reason = reason  # type: ignore[attr-defined]
    return err


def load_scene(source: str | Path) -> Scene:
    """Loads a built-in scene by name (see :func:`gi.builtin_scenes`) or a JSON scene file.

    Raises :class:`gi.SceneError` (with ``file``, ``field`` and ``reason`` attributes) for a
    missing or malformed file, an unknown field, a missing or unreadable mesh, non-finite
    geometry, a degenerate camera or a negative intensity.
    """
    path = Path(source)
    names = [n for n, _ in builtin_scenes()]
    if not path.exists() and str(source) in names:
        return Scene.builtin(str(source))
    file = str(path)
    if not path.is_file():
        hint = f" (built-in scenes: {', '.join(names)})" if path.suffix == "" else ""
        raise _scene_error(file, "(file)", f"no such scene file{hint}")
    try:
        text = path.read_text(encoding="utf-8")
        desc = json.loads(text)
    except (OSError, UnicodeDecodeError) as e:
        raise _scene_error(file, "(file)", f"cannot read: {e}") from e
    except json.JSONDecodeError as e:
        raise _scene_error(
            file, f"(line {e.lineno}, column {e.colno})", f"invalid JSON: {e.msg}"
        ) from e
    return Scene.from_json(text, file, _load_meshes(desc, path.parent, file))


def scene_from_desc(desc: dict[str, Any], source: str, base_dir: Path) -> Scene:
    """A scene from a parsed scene description (the JSON format of ``load_scene``), its mesh
    files relative to ``base_dir``; ``source`` names it in errors."""
    return Scene.from_json(json.dumps(desc), source, _load_meshes(desc, base_dir, source))


def _load_meshes(desc: Any, base_dir: Path, file: str) -> dict[str, MeshEntry]:
    meshes: dict[str, MeshEntry] = {}
    objects = desc.get("objects", []) if isinstance(desc, dict) else []
    for i, obj in enumerate(objects if isinstance(objects, list) else []):
        shape = obj.get("shape") if isinstance(obj, dict) else None
        if not isinstance(shape, dict) or shape.get("type") != "mesh":
            continue
        name = shape.get("file")
        if not isinstance(name, str) or name in meshes:
            continue  # the core reports a missing or mistyped `file`
        meshes[name] = load_mesh(base_dir / name, file, f"objects[{i}].shape.file")
    return meshes


def _material_from_trimesh(mat: Any) -> dict[str, Any] | None:
    """Maps a trimesh material (MTL or glTF PBR) onto the uber BSDF's parameters."""

    def rgb(v: Any, scale: float) -> list[float]:
        a = np.asarray(v, dtype=np.float64).ravel()[:3] / scale
        return [float(x) for x in np.clip(a, 0.0, 1.0)]

    kind = type(mat).__name__
    if kind == "PBRMaterial":
        base = np.asarray(
            mat.baseColorFactor if mat.baseColorFactor is not None else [255, 255, 255, 255],
            dtype=np.float64,
        )[:3]
        base = base / 255.0 if base.max() > 1.0 else base
        metal = float(mat.metallicFactor if mat.metallicFactor is not None else 0.0)
        rough = float(mat.roughnessFactor if mat.roughnessFactor is not None else 1.0)
        spec = 0.04 * (1.0 - metal) + base * metal
        return {
            "diffuse": [float(x) for x in np.clip(base * (1.0 - metal), 0, 1)],
            "specular": [float(x) for x in np.clip(spec, 0, 1)],
            "roughness": min(max(rough, 0.0), 1.0),
            "fresnel": True,
        }
    if kind == "SimpleMaterial":
        out: dict[str, Any] = {"diffuse": rgb(mat.diffuse, 255.0)}
        spec = getattr(mat, "specular", None)
        if spec is not None and np.asarray(spec).max() > 0:
            out["specular"] = rgb(spec, 255.0)
            shininess = float(getattr(mat, "glossiness", None) or 0.0)
            # Blinn-Phong exponent to GGX: alpha = sqrt(2 / (n + 2)); roughness = sqrt(alpha).
            out["roughness"] = math.sqrt(math.sqrt(2.0 / (max(shininess, 0.0) + 2.0)))
        return out
    return None


def load_mesh(path: Path, scene_file: str, field: str) -> MeshEntry:
    """Loads a mesh file into the arrays the core takes (see ``Scene.from_json``)."""
    import trimesh

    if not path.is_file():
        raise _scene_error(scene_file, field, f"mesh file not found: {path}")
    try:
        loaded = trimesh.load(str(path), force="scene", process=False)
    except Exception as e:  # trimesh raises many types for bad files
        raise _scene_error(scene_file, field, f"cannot load mesh {path}: {e}") from e
    parts = []
    for node in loaded.graph.nodes_geometry:
        transform, geom_name = loaded.graph[node]
        geom = loaded.geometry[geom_name]
        if not isinstance(geom, trimesh.Trimesh) or len(geom.faces) == 0:
            continue
        parts.append((geom, transform))
    if not parts:
        raise _scene_error(scene_file, field, f"mesh file has no triangles: {path}")
    verts, faces, normals, face_mats = [], [], [], []
    materials: dict[str, dict[str, Any]] = {}
    offset = 0
    for geom, transform in parts:
        v = trimesh.transform_points(np.asarray(geom.vertices, dtype=np.float64), transform)
        if not np.isfinite(v).all():
            bad = int(np.flatnonzero(~np.isfinite(v).all(axis=1))[0])
            raise _scene_error(
                scene_file, field, f"{path}: vertex {bad} is not finite (NaN or infinity)"
            )
        rot = np.asarray(transform, dtype=np.float64)[:3, :3]
        with np.errstate(invalid="ignore", divide="ignore"):
            n = np.asarray(geom.vertex_normals, dtype=np.float64) @ np.linalg.inv(rot)
            n /= np.linalg.norm(n, axis=1, keepdims=True)
        n = np.nan_to_num(n)
        verts.append(v)
        normals.append(n)
        faces.append(np.asarray(geom.faces, dtype=np.int64) + offset)
        offset += len(v)
        mat = getattr(getattr(geom, "visual", None), "material", None)
        desc = _material_from_trimesh(mat) if mat is not None else None
        if desc is not None:
            name = f"{path.name}:{getattr(mat, 'name', None) or len(materials)}"
            materials.setdefault(name, desc)
            face_mats.append(np.full(len(geom.faces), list(materials).index(name), np.uint32))
        else:
            face_mats.append(None)
    has_all = materials and all(f is not None for f in face_mats)
    return (
        np.ascontiguousarray(np.concatenate(verts), dtype=np.float32),
        np.ascontiguousarray(np.concatenate(faces), dtype=np.uint32),
        np.ascontiguousarray(np.concatenate(normals), dtype=np.float32),
        json.dumps(materials) if has_all else None,
        np.concatenate(face_mats) if has_all else None,
    )
