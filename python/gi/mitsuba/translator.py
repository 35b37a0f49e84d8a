"""The translator: walks a ``<scene>`` and builds gi's scene description from its
sensor, BSDFs, shapes and emitters (each in its own module)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from gi._gi import Scene
from gi.meshes import MeshEntry, report, scene_error
from gi.mitsuba.bsdfs import bsdf
from gi.mitsuba.elements import Element, parse_xml
from gi.mitsuba.emitters import emitter
from gi.mitsuba.includes import expand_includes
from gi.mitsuba.sensor import check_clip, sensor
from gi.mitsuba.shapes import check_group, shape
from gi.mitsuba.upgrade import upgrade
from gi.mitsuba.values import Reader

# Render settings: gi.render's arguments choose these (the integrator's depth, the sampler's
# sample count, the pixel filter).
_IGNORED = {"integrator", "sampler", "rfilter"}


class Translator(Reader):
    """The scene being built: materials, meshes, objects, lights, camera, environment."""

    def __init__(self, path: Path):
        super().__init__(path)
        self.materials: dict[str, dict[str, Any]] = {}
        self.material_of: dict[int, str] = {}  # id(bsdf element) -> material name
        self.meshes: dict[str, MeshEntry] = {}
        # Mesh files read so far (shape kind and file name -> vertices, faces, normals, UVs).
        self.files: dict[str, tuple[Any, Any, Any, Any]] = {}
        self.objects: list[dict[str, Any]] = []
        self.lights: list[dict[str, Any]] = []
        self.camera: dict[str, Any] | None = None
        self.environment: dict[str, Any] | None = None
        self.env_images: dict[str, np.ndarray] = {}
        # Bump-mapped materials: height map and scale (baked per shape, gi.mitsuba.layers).
        self.bumps: dict[str, tuple[np.ndarray, float]] = {}
        # Normal-mapped materials: the map's RGBA (oriented per shape, gi.mitsuba.layers).
        self.normal_maps: dict[str, np.ndarray] = {}
        # The sensor element, its near and far clip distances and its properties.
        self.clip: tuple[Element, float, float, dict[str, Element]] | None = None

    def run(self, root: Element) -> None:
        if root.tag != "scene":
            raise self.error(root, "the root element must be <scene>")
        upgrade(root)
        expand_includes(self, root)
        self.collect(root)
        for el in root.children:
            if el.tag in ("default", *_IGNORED):
                continue
            if el.tag == "sensor":
                sensor(self, el)
            elif el.tag == "bsdf":
                bsdf(self, el)
            elif el.tag == "texture":
                continue  # read where a BSDF uses it
            elif el.tag == "shape":
                shape(self, el)
            elif el.tag == "shapegroup":
                check_group(self, el)  # placed where an instance refers to it
            elif el.tag == "emitter":
                if el.attrs.get("type") == "area" and "id" in el.attrs:
                    continue  # an area emitter shapes refer to (<ref id=...>)
                emitter(self, el)
            else:
                raise self.error(el, "unsupported element")
        if self.camera is None:
            raise scene_error(self.file, "<sensor>", "the scene has no sensor")
        check_clip(self)

    def collect(self, root: Element) -> None:
        """The scene's `<default>` parameters and every element with an `id`."""
        for el in root.children:
            if el.tag == "default":
                name = self.attr(el, "name")
                self.defaults.setdefault(name, self.attr(el, "value"))
        todo = list(root.children)
        while todo:
            el = todo.pop()
            todo.extend(el.children)
            if "id" in el.attrs and el.tag not in ("default", "ref"):
                if el.attrs["id"] in self.ids:
                    raise self.error(el, f"id `{el.attrs['id']}` is used twice")
                self.ids[el.attrs["id"]] = el

    def description(self) -> dict[str, Any]:
        desc = {
            "camera": self.camera,
            "lights": self.lights,
            "materials": self.materials,
            "objects": self.objects,
        }
        if self.environment is not None:
            desc["environment"] = self.environment
        return desc


def load_mitsuba(path: Path) -> Scene:
    """Reads a Mitsuba XML scene (see :mod:`gi.mitsuba`)."""
    try:
        text = path.read_bytes()
    except OSError as e:
        raise scene_error(str(path), "(file)", f"cannot read: {e}") from e
    t = Translator(path)
    t.run(parse_xml(text, str(path)))
    report(path, t.notes)
    return Scene.from_json(
        json.dumps(t.description()),
        str(path),
        t.meshes,
        t.env_images,
        textures=t.textures.arrays,
    )
