"""Scene loading: built-in names, gi's JSON scene files, or Mitsuba 3 XML scenes.

The JSON format is documented in ``docs/scene-format.md``; the Rust core validates every
field. Mesh files named by a scene are resolved relative to it and read by
:mod:`gi.meshes` (OBJ with MTL, PLY, glTF/GLB, STL), environment images by
:mod:`gi.environment` (OpenImageIO). Mitsuba scenes are translated by
:mod:`gi.mitsuba` (``docs/mitsuba.md``).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

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
    meshes = _load_meshes(desc, base_dir, source, textures)
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
) -> dict[str, MeshEntry]:
    meshes: dict[str, MeshEntry] = {}
    objects = desc.get("objects", []) if isinstance(desc, dict) else []
    for i, obj in enumerate(objects if isinstance(objects, list) else []):
        shape = obj.get("shape") if isinstance(obj, dict) else None
        if not isinstance(shape, dict) or shape.get("type") != "mesh":
            continue
        name = shape.get("file")
        if not isinstance(name, str) or name in meshes:
            continue  # the core reports a missing or mistyped `file`
        meshes[name] = load_mesh(base_dir / name, file, f"objects[{i}].shape.file", textures)
    return meshes
