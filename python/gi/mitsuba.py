"""Mitsuba 3 XML scenes: the subset that common benchmark scenes use, translated into gi's
scene description (see ``docs/mitsuba.md`` for the subset and the BSDF mapping).

Every shape becomes an object: an instance of a mesh in its local frame, placed by a
``matrix`` transform, so that shapes that load the same file with the same options, equal
built-in shapes (``rectangle``, ``cube``, ``disk``, ``sphere``), and the shapes of a
``<shapegroup>`` placed by ``<shape type="instance">`` share one mesh. BSDFs become
uber-BSDF materials. An element gi cannot render is a :class:`gi.SceneError` whose
``field`` names the element and its line (``<bsdf type="roughdielectric"> (line 12)``); a
property it ignores is an :class:`gi.AssetWarning`.
"""

from __future__ import annotations

import json
import math
import re
import xml.parsers.expat
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from gi._gi import Scene, SceneError
from gi._placement import first_bad_placement
from gi.meshes import MeshEntry, load_mesh, report, scene_error
from gi.textures import TextureError, TextureSet

# Interior/exterior indices Mitsuba knows by name (its `ior` table, the common ones).
IOR_NAMES = {
    "vacuum": 1.0,
    "helium": 1.00004,
    "hydrogen": 1.00013,
    "air": 1.000277,
    "carbon dioxide": 1.00045,
    "water": 1.333,
    "acetone": 1.36,
    "ethanol": 1.361,
    "carbon tetrachloride": 1.461,
    "glycerol": 1.4729,
    "benzene": 1.501,
    "silicone oil": 1.52045,
    "bromine": 1.661,
    "water ice": 1.31,
    "fused quartz": 1.458,
    "pyrex": 1.47,
    "acrylic glass": 1.49,
    "polypropylene": 1.49,
    "bk7": 1.5046,
    "sodium chloride": 1.544,
    "amber": 1.55,
    "pet": 1.575,
    "diamond": 2.419,
}

# Normal-incidence reflectance (linear sRGB) of Mitsuba's named conductors.
CONDUCTOR_F0 = {
    "none": (1.0, 1.0, 1.0),
    "Ag": (0.972, 0.960, 0.915),
    "Al": (0.913, 0.922, 0.924),
    "Au": (1.000, 0.766, 0.336),
    "Cr": (0.550, 0.556, 0.554),
    "Cu": (0.955, 0.638, 0.538),
    "Fe": (0.562, 0.565, 0.578),
    "Ni": (0.660, 0.609, 0.526),
    "Pt": (0.673, 0.637, 0.585),
    "Ti": (0.542, 0.497, 0.449),
}

_IGNORED = {"integrator", "sampler", "rfilter"}  # render settings: gi.render chooses these


def coordinate_system(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing the unit vector ``n`` to an orthonormal basis, as Mitsuba
    3's ``coordinate_system`` builds them (Duff et al. 2017, "Building an orthonormal basis,
    revisited"): what its ``<lookat>`` takes as ``up`` when none is given."""
    sign = math.copysign(1.0, n[2])
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = np.array([1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0]])
    t = np.array([b, sign + n[1] * n[1] * a, -n[1]])
    return s, t


@dataclass
class Element:
    """One XML element with the line it starts on."""

    tag: str
    attrs: dict[str, str]
    line: int
    children: list[Element] = field(default_factory=list)

    @property
    def label(self) -> str:
        kind = self.attrs.get("type")
        name = self.attrs.get("name")
        inner = f' type="{kind}"' if kind else f' name="{name}"' if name else ""
        return f"<{self.tag}{inner}> (line {self.line})"


def parse_xml(text: bytes, file: str) -> Element:
    """Parses XML into :class:`Element` trees (expat, for line numbers)."""
    parser = xml.parsers.expat.ParserCreate()
    root: list[Element] = []
    stack: list[Element] = []

    def start(tag: str, attrs: dict[str, str]) -> None:
        el = Element(tag, attrs, parser.CurrentLineNumber)
        (stack[-1].children if stack else root).append(el)
        stack.append(el)

    def end(_tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(text, True)
    except xml.parsers.expat.ExpatError as e:
        raise scene_error(file, f"(line {e.lineno}, column {e.offset})", f"invalid XML: {e}") from e
    return root[0]


class _Translator:
    def __init__(self, path: Path):
        self.path = path
        self.file = str(path)
        self.defaults: dict[str, str] = {}
        self.ids: dict[str, Element] = {}
        self.materials: dict[str, dict[str, Any]] = {}
        self.material_of: dict[int, str] = {}  # id(bsdf element) -> material name
        self.meshes: dict[str, MeshEntry] = {}
        # Mesh files read so far (shape kind and file name -> vertices, faces, normals, UVs).
        self.files: dict[str, tuple[Any, Any, Any, Any]] = {}
        self.objects: list[dict[str, Any]] = []
        self.lights: list[dict[str, Any]] = []
        self.camera: dict[str, Any] | None = None
        self.notes: dict[str, str] = {}
        self.textures = TextureSet(path.parent)
        self.environment: dict[str, Any] | None = None
        self.env_images: dict[str, np.ndarray] = {}

    # -- errors and attribute access ------------------------------------------------------

    def error(self, el: Element, reason: str) -> SceneError:
        return scene_error(self.file, el.label, reason)

    def attr(self, el: Element, key: str, default: str | None = None) -> str:
        value = el.attrs.get(key, default)
        if value is None:
            raise self.error(el, f"missing attribute `{key}`")

        def sub(m: re.Match[str]) -> str:
            if m.group(1) not in self.defaults:
                raise self.error(el, f"no <default> for parameter ${m.group(1)}")
            return self.defaults[m.group(1)]

        return re.sub(r"\$([A-Za-z_][A-Za-z0-9_]*)", sub, value)

    def numbers(self, el: Element, text: str, count: int | None = None) -> list[float]:
        try:
            vals = [float(x) for x in text.replace(",", " ").split()]
        except ValueError:
            raise self.error(el, f"expected numbers, got {text!r}") from None
        if count is not None and len(vals) != count:
            raise self.error(el, f"expected {count} numbers, got {text!r}")
        if not all(math.isfinite(v) for v in vals):
            raise self.error(el, "values must be finite")
        return vals

    def vec3(self, el: Element) -> np.ndarray:
        if "value" in el.attrs:
            v = self.numbers(el, self.attr(el, "value"))
            if len(v) == 1:
                v = v * 3
            if len(v) != 3:
                raise self.error(el, "expected 1 or 3 numbers")
            return np.array(v)
        return np.array([self.numbers(el, self.attr(el, k, "0"), 1)[0] for k in ("x", "y", "z")])

    # -- properties -----------------------------------------------------------------------

    def props(self, el: Element) -> dict[str, Element]:
        """The named property children of a plugin element."""
        out = {}
        for c in el.children:
            if c.tag in ("float", "integer", "boolean", "string", "rgb", "spectrum", "point"):
                out[self.attr(c, "name")] = c
            elif c.tag in ("vector", "transform", "texture"):
                out[self.attr(c, "name")] = c
            elif c.tag == "ref" and "name" in c.attrs:
                out[self.attr(c, "name")] = c
        return out

    def float(self, el: Element, props: dict[str, Element], name: str, default: float) -> float:
        p = props.get(name)
        if p is None:
            return default
        if p.tag not in ("float", "integer"):
            raise self.error(p, f"`{name}` must be a float")
        return self.numbers(p, self.attr(p, "value"), 1)[0]

    def string(self, props: dict[str, Element], name: str, default: str) -> str:
        p = props.get(name)
        return default if p is None else self.attr(p, "value")

    def boolean(self, props: dict[str, Element], name: str, default: bool) -> bool:
        p = props.get(name)
        if p is None:
            return default
        value = self.attr(p, "value").strip().lower()
        if value not in ("true", "false"):
            raise self.error(p, "expected true or false")
        return value == "true"

    def color(self, props: dict[str, Element], name: str, default: float) -> np.ndarray:
        """An rgb/spectrum/float property or a bitmap texture (its mean colour)."""
        p = props.get(name)
        if p is None:
            return np.full(3, default)
        if p.tag == "texture":
            return self.bitmap_mean(p)
        if p.tag == "ref":
            return self.bitmap_mean(self.resolve(p))
        text = self.attr(p, "value")
        if p.tag == "spectrum" and ":" in text:
            raise self.error(p, "sampled spectra are not supported (use rgb or one value)")
        if p.tag not in ("rgb", "spectrum", "float"):
            raise self.error(p, f"`{name}` must be an rgb, spectrum, float or texture")
        v = self.numbers(p, text)
        if len(v) not in (1, 3):
            raise self.error(p, "expected 1 or 3 numbers")
        return np.array(v * 3 if len(v) == 1 else v)

    def ior(self, props: dict[str, Element], name: str, default: float) -> float:
        p = props.get(name)
        if p is None:
            return default
        value = self.attr(p, "value").strip()
        if p.tag == "string" or value.lower() in IOR_NAMES:
            if value.lower() not in IOR_NAMES:
                raise self.error(p, f"unknown index of refraction {value!r}")
            return IOR_NAMES[value.lower()]
        return self.float(p, props, name, default)

    def use_bitmap(
        self, desc: dict[str, Any], props: dict[str, Element], name: str, to: str
    ) -> None:
        """Where property `name` is a bitmap, material field `to` reads it as a texture (its
        factor 1) instead of its mean colour."""
        p = props.get(name)
        if p is None or p.tag not in ("texture", "ref"):
            return
        tex = self.resolve(p) if p.tag == "ref" else p
        file = self.path.parent / self.string(self.props(tex), "filename", "")
        raw = self.boolean(self.props(tex), "raw", False)
        try:
            desc[f"{to}_texture"] = self.textures.add(file, not raw)
        except (TextureError, OSError) as e:
            raise self.error(tex, str(e)) from e
        desc[to] = np.ones(3)
        self.notes.pop(tex.label, None)
        wrap = self.string(self.props(tex), "wrap_mode", "repeat")
        if wrap != "repeat":
            self.notes[tex.label] = f"wrap_mode {wrap!r} is not supported; it repeats"

    def bitmap_mean(self, tex: Element) -> np.ndarray:
        if tex.tag != "texture" or tex.attrs.get("type") != "bitmap":
            raise self.error(tex, "only bitmap textures are supported")
        props = self.props(tex)
        file = self.path.parent / self.string(props, "filename", "")
        if not file.is_file():
            raise self.error(tex, f"texture file not found: {file}")
        from gi.io import read_image

        try:
            img = read_image(file)[..., :3].astype(np.float64)
        except OSError as e:
            raise self.error(tex, str(e)) from e
        if img.shape[-1] == 1:
            img = np.repeat(img, 3, axis=-1)
        raw = self.boolean(props, "raw", False)
        if not raw and file.suffix.lower() not in (".exr", ".hdr", ".pfm"):
            img = np.where(img <= 0.04045, img / 12.92, ((img + 0.055) / 1.055) ** 2.4)
        mean = img.reshape(-1, 3).mean(axis=0)
        self.notes[tex.label] = (
            f"textures are read as diffuse reflectance only; {file.name}'s mean colour "
            f"({mean[0]:.3f}, {mean[1]:.3f}, {mean[2]:.3f}) is used here"
        )
        return mean

    def note_unknown(self, props: dict[str, Element], known: set[str]) -> None:
        for key, p in props.items():
            if key not in known:
                self.notes[p.label] = "ignored"

    def resolve(self, ref: Element) -> Element:
        key = self.attr(ref, "id")
        if key not in self.ids:
            raise self.error(ref, f"no element with id `{key}`")
        return self.ids[key]

    # -- transforms -----------------------------------------------------------------------

    def transform(self, el: Element | None) -> np.ndarray:
        m = np.eye(4)
        if el is None:
            return m
        if el.tag != "transform":
            raise self.error(el, "expected a <transform>")
        for op in el.children:
            m = self.transform_op(op) @ m
        return m

    def transform_op(self, op: Element) -> np.ndarray:
        t = np.eye(4)
        if op.tag == "translate":
            t[:3, 3] = self.vec3(op)
        elif op.tag == "scale":
            if "value" in op.attrs:
                s = self.vec3(op)
            else:
                s = np.array([self.numbers(op, self.attr(op, k, "1"), 1)[0] for k in "xyz"])
            t[:3, :3] = np.diag(s)
        elif op.tag == "rotate":
            axis = self.vec3(op)
            angle = math.radians(self.numbers(op, self.attr(op, "angle"), 1)[0])
            n = np.linalg.norm(axis)
            if n == 0:
                raise self.error(op, "rotation axis must be non-zero")
            x, y, z = axis / n
            c, s = math.cos(angle), math.sin(angle)
            k = np.array([[0, -z, y], [z, 0, -x], [-y, x, 0]])
            t[:3, :3] = np.eye(3) + s * k + (1 - c) * (k @ k)
        elif op.tag == "matrix":
            v = self.numbers(op, self.attr(op, "value"))
            if len(v) == 16:
                t = np.array(v).reshape(4, 4)
            elif len(v) == 9:
                t[:3, :3] = np.array(v).reshape(3, 3)
            else:
                raise self.error(op, "expected 9 or 16 numbers")
        elif op.tag == "lookat":
            origin = np.array(self.numbers(op, self.attr(op, "origin"), 3))
            target = np.array(self.numbers(op, self.attr(op, "target"), 3))
            up = np.array(self.numbers(op, self.attr(op, "up", "0, 0, 0"), 3))
            d = target - origin
            if np.linalg.norm(d) == 0:
                raise self.error(op, "origin and target must differ")
            d /= np.linalg.norm(d)
            if not up.any():
                # No `up` (or a zero one): Mitsuba 3 takes one perpendicular to the view.
                up = coordinate_system(d)[0]
            left = np.cross(up, d)
            if np.linalg.norm(left) < 1e-9:
                raise self.error(op, "up must not be parallel to the viewing direction")
            left /= np.linalg.norm(left)
            t[:3, 0], t[:3, 1], t[:3, 2], t[:3, 3] = left, np.cross(d, left), d, origin
        else:
            raise self.error(op, "unknown transform operation")
        return t

    # -- scene elements -------------------------------------------------------------------

    def run(self, root: Element) -> None:
        if root.tag != "scene":
            raise self.error(root, "the root element must be <scene>")
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
        for el in root.children:
            if el.tag in ("default", *_IGNORED):
                continue
            if el.tag == "sensor":
                self.sensor(el)
            elif el.tag == "bsdf":
                self.bsdf(el)
            elif el.tag == "texture":
                continue  # read where a BSDF uses it
            elif el.tag == "shape":
                self.shape(el)
            elif el.tag == "shapegroup":
                self.check_group(el)  # placed where an instance refers to it
            elif el.tag == "emitter":
                self.emitter(el)
            else:
                raise self.error(el, "unsupported element")
        if self.camera is None:
            raise scene_error(self.file, "<sensor>", "the scene has no sensor")

    def sensor(self, el: Element) -> None:
        if el.attrs.get("type") != "perspective":
            raise self.error(el, "unsupported sensor (gi reads `perspective`)")
        if self.camera is not None:
            raise self.error(el, "gi renders one sensor; this is the second")
        props = self.props(el)
        width, height = 768, 576
        for c in el.children:
            if c.tag == "film":
                if c.attrs.get("type") not in ("hdrfilm", None):
                    raise self.error(c, "unsupported film (gi reads `hdrfilm`)")
                fp = self.props(c)
                width = int(self.float(c, fp, "width", width))
                height = int(self.float(c, fp, "height", height))
            elif c.tag not in ("sampler", "float", "integer", "string", "transform", "boolean"):
                raise self.error(c, "unsupported element in a sensor")
        for key in props:
            # `focus_distance` only matters to `thinlens`; `perspective` is a pinhole too.
            known = ("fov", "fov_axis", "to_world", "near_clip", "far_clip", "focus_distance")
            if key not in known:
                self.notes[props[key].label] = "ignored (gi's camera is a pinhole)"
        fov = self.float(el, props, "fov", 39.3077)  # Mitsuba's default: 35 mm equivalent
        axis = self.string(props, "fov_axis", "x").lower()
        aspect = width / max(height, 1)
        half = math.tan(math.radians(fov) / 2)
        if axis == "smaller":
            axis = "x" if width < height else "y"
        elif axis == "larger":
            axis = "x" if width > height else "y"
        if axis == "x":
            half /= aspect
        elif axis == "diagonal":
            half *= height / math.hypot(width, height)
        elif axis != "y":
            raise self.error(props["fov_axis"], f"unknown fov_axis {axis!r}")
        m = self.transform(props.get("to_world"))
        if np.linalg.det(m[:3, :3]) < 0:
            raise self.error(props["to_world"], "mirrored sensor transforms are not supported")
        pos, d, up = m[:3, 3], m[:3, 2], m[:3, 1]
        self.camera = {
            "position": pos.tolist(),
            "look_at": (pos + d / np.linalg.norm(d)).tolist(),
            "up": up.tolist(),
            "fov": math.degrees(2 * math.atan(half)),
            "width": width,
            "height": height,
        }

    def bsdf(self, el: Element, name: str | None = None) -> str:
        """Translates a BSDF (once) and returns its material name (its id, else `name`,
        else where it is)."""
        if id(el) in self.material_of:
            return self.material_of[id(el)]
        kind = el.attrs.get("type")
        props = self.props(el)
        if kind == "twosided":
            inner = [c for c in el.children if c.tag in ("bsdf", "ref")]
            if len(inner) != 1:
                raise self.error(el, "gi's opaque surfaces are two-sided: give one inner BSDF")
            target = self.resolve(inner[0]) if inner[0].tag == "ref" else inner[0]
            name = self.bsdf(target, el.attrs.get("id") or name)
            self.material_of[id(el)] = name
            return name
        desc: dict[str, Any]
        if kind == "diffuse":
            desc = {"diffuse": self.color(props, "reflectance", 0.5)}
            self.use_bitmap(desc, props, "reflectance", "diffuse")
        elif kind in ("conductor", "roughconductor"):
            metal = self.string(props, "material", "none")
            if "eta" in props or "k" in props:
                eta = self.color(props, "eta", 0.0)
                k = self.color(props, "k", 1.0)
                f0 = ((eta - 1) ** 2 + k**2) / ((eta + 1) ** 2 + k**2)
            elif metal in CONDUCTOR_F0:
                f0 = np.array(CONDUCTOR_F0[metal])
            else:
                raise self.error(props["material"], f"unknown conductor {metal!r}")
            desc = {
                "diffuse": np.zeros(3),
                "specular": f0 * self.color(props, "specular_reflectance", 1.0),
                "fresnel": metal != "none" or "eta" in props,
            }
        elif kind == "dielectric":
            ior = self.ior(props, "int_ior", 1.5046) / self.ior(props, "ext_ior", 1.000277)
            desc = {
                "diffuse": np.zeros(3),
                "transmission": self.color(props, "specular_transmittance", 1.0),
                "ior": min(max(ior, 1.0), 4.0),
            }
        elif kind in ("plastic", "roughplastic"):
            ior = self.ior(props, "int_ior", 1.49) / self.ior(props, "ext_ior", 1.000277)
            f0 = ((ior - 1) / (ior + 1)) ** 2
            desc = {
                "diffuse": self.color(props, "diffuse_reflectance", 0.5),
                "specular": f0 * self.color(props, "specular_reflectance", 1.0),
                "fresnel": True,
            }
            self.use_bitmap(desc, props, "diffuse_reflectance", "diffuse")
        else:
            raise self.error(el, "unsupported BSDF (see docs/mitsuba.md for the list)")
        if kind in ("roughconductor", "roughplastic"):
            if "alpha_u" in props or "alpha_v" in props:
                au = self.float(el, props, "alpha_u", 0.1)
                av = self.float(el, props, "alpha_v", 0.1)
                alpha = math.sqrt(au * av)
                self.notes[el.label] = "anisotropic roughness is not supported; sqrt(αu·αv)"
            else:
                alpha = self.float(el, props, "alpha", 0.1)
            desc["roughness"] = min(max(math.sqrt(max(alpha, 0.0)), 0.0), 1.0)
        for key in props:
            known = {"reflectance", "material", "eta", "k", "specular_reflectance"}
            known |= {"int_ior", "ext_ior", "specular_transmittance", "diffuse_reflectance"}
            known |= {"alpha", "alpha_u", "alpha_v", "distribution", "nonlinear"}
            if key not in known:
                self.notes[props[key].label] = "ignored"
        name = el.attrs.get("id") or name or f"bsdf@{el.line}"
        while name in self.materials:
            name += "'"
        self.materials[name] = {
            k: (np.clip(v, 0.0, 1.0).tolist() if isinstance(v, np.ndarray) else v)
            for k, v in desc.items()
        }
        self.material_of[id(el)] = name
        return name

    def shape(self, el: Element, parent: np.ndarray | None = None) -> None:
        """A shape as an object: its mesh (shared by equal shapes) placed by ``to_world``
        (after ``parent``, the instance's transform, for a shape of a shapegroup)."""
        kind = el.attrs.get("type")
        if kind == "instance":
            self.instance(el)
            return
        props = self.props(el)
        xf = self.transform(props.get("to_world"))
        if parent is not None:
            xf = parent @ xf
        key, smooth, local = self.shape_mesh(el, kind, props)
        material, emitter = None, None
        for c in el.children:
            target = self.resolve(c) if c.tag == "ref" else c
            if target.tag == "bsdf":
                material = self.bsdf(target)
            elif target.tag == "emitter":
                if target.attrs.get("type") != "area":
                    raise self.error(target, "a shape's emitter must be an `area` emitter")
                emitter = target
            elif c.tag == "ref":
                raise self.error(c, f"refers to a <{target.tag}>, not a <bsdf> or <emitter>")
        if material is None:  # Mitsuba's default BSDF
            material = self.bsdf(Element("bsdf", {"type": "diffuse"}, el.line))
        if emitter is not None:
            material = self.area_emitter(el, emitter, material)
        m = xf @ local
        self.check_matrix(props.get("to_world", el), m)
        obj: dict[str, Any] = {
            "shape": {"type": "mesh", "file": key},
            "material": material,
            "transform": {"matrix": m[:3].tolist()},
        }
        if smooth is not None:
            obj["smooth"] = smooth
        self.objects.append(obj)

    def shape_mesh(
        self, el: Element, kind: str | None, props: dict[str, Element]
    ) -> tuple[str, bool | None, np.ndarray]:
        """The key of a shape's mesh in ``self.meshes`` (added the first time: a file with
        its options, or a built-in shape in its local frame), its smoothing, and the matrix
        that places the built-in's parameters (a sphere's ``center`` and ``radius``)."""
        smooth: bool | None = None
        local = np.eye(4)
        build: Any
        if kind in ("obj", "ply"):
            file = self.string(props, "filename", "")
            key = f"{kind}:{file}"
            if key not in self.files:
                field = f"{el.label} filename"
                v, f, n, _m, _fm, uv = load_mesh(
                    self.path.parent / file, self.file, field, self.textures
                )
                self.files[key] = (v, f, n, uv)
            v, f, n, uv = self.files[key]
            # Like Mitsuba: `face_normals` shades flat; a file without normals, smooth.
            if self.boolean(props, "face_normals", False):
                smooth = False
            elif n is None:
                smooth = True

            def build() -> tuple[Any, Any, Any, Any]:
                return v, f, n, uv

        elif kind == "rectangle":
            key = "rectangle"

            def build() -> tuple[Any, Any, Any, Any]:
                v = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], np.float64)
                # The image upright seen from +z (v runs down the image).
                uv = np.stack([(v[:, 0] + 1) / 2, (1 - v[:, 1]) / 2], axis=1)
                return v, np.array([[0, 1, 2], [0, 2, 3]]), np.tile([0.0, 0.0, 1.0], (4, 1)), uv

        elif kind == "cube":
            key = "cube"

            def build() -> tuple[Any, Any, Any, Any]:
                return (*_cube(), None)

        elif kind == "disk":
            key = "disk"

            def build() -> tuple[Any, Any, Any, Any]:
                return (*_disk(), None)

        elif kind == "sphere":
            key = "sphere"
            r = self.float(el, props, "radius", 1.0)
            c = self.vec3(props["center"]) if "center" in props else np.zeros(3)
            local[:3, :3] *= r
            local[:3, 3] = c

            def build() -> tuple[Any, Any, Any, Any]:
                import trimesh

                ico = trimesh.creation.icosphere(subdivisions=4)
                n = np.asarray(ico.vertices, np.float64)
                return n, np.asarray(ico.faces, np.int64), n, None

        else:
            raise self.error(
                el, "unsupported shape (gi reads obj, ply, rectangle, cube, disk, sphere)"
            )
        known = {"filename", "face_normals", "flip_normals", "to_world", "center", "radius", "bsdf"}
        self.note_unknown(props, known)
        flip = self.boolean(props, "flip_normals", False)
        if flip:
            key += " (flip_normals)"
        if key not in self.meshes:
            v, f, n, uv = build()
            f = np.asarray(f, np.int64)
            if flip:
                f = f[:, [0, 2, 1]]
                n = None if n is None else -np.asarray(n)
            self.meshes[key] = (
                np.ascontiguousarray(v, np.float32),
                np.ascontiguousarray(f, np.uint32),
                None if n is None else np.ascontiguousarray(n, np.float32),
                None,
                None,
                None if uv is None else np.ascontiguousarray(uv, np.float32),
            )
        return key, smooth, local

    def check_matrix(self, el: Element, m: np.ndarray) -> None:
        """A shape's placement checked as the core checks a ``matrix`` transform, so that
        the error names the Mitsuba element."""
        bad = first_bad_placement(m[None])
        if bad is not None:
            raise self.error(el, f"the transform {bad[1]}")

    def check_group(self, group: Element) -> None:
        """A ``<shapegroup>`` holds shapes only: no instances (Mitsuba has no nested
        instancing; one of its own group would recurse) and no other shapegroup."""
        if "id" not in group.attrs:
            raise self.error(group, "a shapegroup needs an `id` for instances to refer to")
        for c in group.children:
            if c.tag == "shapegroup":
                raise self.error(c, "shapegroups cannot be nested")
            if c.tag != "shape":
                raise self.error(c, "a shapegroup holds shapes only")
            if c.attrs.get("type") == "instance":
                refs = [r.attrs.get("id") for r in c.children if r.tag == "ref"]
                if group.attrs["id"] in refs:
                    raise self.error(c, "an instance of its own shapegroup (recursive)")
                raise self.error(c, "a shapegroup cannot hold instances (nested instancing)")

    def instance(self, el: Element) -> None:
        """``<shape type="instance">``: the shapes of the ``<shapegroup>`` it refers to,
        each placed by the instance's ``to_world`` after its own."""
        props = self.props(el)
        groups = []
        for c in el.children:
            if c.tag == "ref":
                target = self.resolve(c)
                if target.tag != "shapegroup":
                    raise self.error(c, f"refers to a <{target.tag}>, not a <shapegroup>")
                groups.append(target)
            elif c.tag not in ("transform",):
                raise self.error(c, "an instance holds a <ref> to a shapegroup and `to_world`")
        if len(groups) != 1:
            raise self.error(el, "an instance refers to one <shapegroup> (<ref id=...>)")
        self.note_unknown(props, {"to_world"} | {r.attrs.get("name", "") for r in groups})
        xf = self.transform(props.get("to_world"))
        self.check_group(groups[0])
        for shape in groups[0].children:
            self.shape(shape, xf)

    def area_emitter(self, shape: Element, el: Element, material: str) -> str:
        """An `area` emitter on a shape: its BSDF's material with `emission` (`radiance`, a
        colour or a bitmap), one-sided (the shape's normal side) as Mitsuba's. Each emitting
        shape gets its own material, named after the shape's id or line."""
        props = self.props(el)
        self.note_unknown(props, {"radiance"})
        desc = dict(self.materials[material])
        p = props.get("radiance")
        if p is not None and p.tag in ("texture", "ref"):
            tex = self.resolve(p) if p.tag == "ref" else p
            desc["emission_texture"], desc["emission"] = self.emission_bitmap(tex)
        else:
            desc["emission"] = self.color(props, "radiance", 1.0).tolist()
        name = shape.attrs.get("id") or f"emitter@line{el.line}"
        while name in self.materials:
            name += "'"
        self.materials[name] = desc
        return name

    def emission_bitmap(self, tex: Element) -> tuple[str, list[float]]:
        """A bitmap `radiance`: the texture scaled to [0, 1] (gi's textures are) and the
        scale as the emission."""
        props = self.props(tex)
        if tex.tag != "texture" or tex.attrs.get("type") != "bitmap":
            raise self.error(tex, "only bitmap textures are supported")
        file = self.path.parent / self.string(props, "filename", "")
        raw = self.boolean(props, "raw", False)
        try:
            key = self.textures.add(file, not raw)
        except (TextureError, OSError) as e:
            raise self.error(tex, str(e)) from e
        img = self.textures.arrays[key]
        peak = float(img[..., :3].max()) if img.size else 0.0
        if peak > 1.0:
            scaled = img.copy()
            scaled[..., :3] /= peak
            key = self.textures.add_array(f"{key}#emission", scaled)
        wrap = self.string(props, "wrap_mode", "repeat")
        if wrap != "repeat":
            self.notes[tex.label] = f"wrap_mode {wrap!r} is not supported; it repeats"
        return key, [max(peak, 1.0)] * 3

    def emitter(self, el: Element) -> None:
        kind = el.attrs.get("type")
        if kind in ("envmap", "constant"):
            return self.env_emitter(el, kind)
        if kind == "directional":
            return self.directional(el)
        if kind == "area":
            raise self.error(el, "an area emitter belongs inside a <shape>")
        props = self.props(el)
        known = {"intensity", "to_world", "position", "cutoff_angle", "beam_width"}
        self.note_unknown(props, known)
        intensity = self.color(props, "intensity", 1.0)
        xf = self.transform(props.get("to_world"))
        if kind == "point":
            pos = self.vec3(props["position"]) if "position" in props else xf[:3, 3]
            self.lights.append(
                {"type": "point", "position": pos.tolist(), "intensity": intensity.tolist()}
            )
        elif kind == "spot":
            cutoff = self.float(el, props, "cutoff_angle", 20.0)
            beam = self.float(el, props, "beam_width", cutoff * 0.75)
            self.lights.append(
                {
                    "type": "spot",
                    "position": xf[:3, 3].tolist(),
                    "direction": xf[:3, 2].tolist(),
                    "intensity": intensity.tolist(),
                    "inner_angle": min(beam, cutoff),
                    "outer_angle": cutoff,
                }
            )
        else:
            raise self.error(
                el,
                "unsupported emitter (gi reads point, spot, directional, envmap, constant and "
                "area emitters)",
            )

    def directional(self, el: Element) -> None:
        """`directional`: `irradiance` (W/m²) travelling along `direction`, or along
        `to_world`'s +z."""
        props = self.props(el)
        self.note_unknown(props, {"irradiance", "direction", "to_world"})
        if "direction" in props:
            d = self.vec3(props["direction"])
        else:
            d = self.transform(props.get("to_world"))[:3, 2]
        if not np.linalg.norm(d) > 0:
            raise self.error(el, "the direction must be non-zero")
        self.lights.append(
            {
                "type": "directional",
                "direction": (d / np.linalg.norm(d)).tolist(),
                "irradiance": self.color(props, "irradiance", 1.0).tolist(),
            }
        )

    def env_emitter(self, el: Element, kind: str) -> None:
        """`envmap` (an equirectangular image, `scale`, a rotation about +y) or `constant`
        (`radiance`) → the scene's `environment` section."""
        if self.environment is not None:
            raise self.error(el, "a second environment emitter (gi takes one)")
        props = self.props(el)
        if kind == "constant":
            self.note_unknown(props, {"radiance"})
            radiance = self.color(props, "radiance", 1.0)
            self.environment = {"radiance": radiance.tolist()}
            return
        self.note_unknown(props, {"filename", "scale", "to_world"})
        if "filename" not in props:
            raise self.error(el, "an envmap needs a `filename`")
        name = self.string(props, "filename", "")
        from gi.environment import load_environment_image

        self.env_images[name] = load_environment_image(self.path.parent / name, self.file, el.label)
        m = self.transform(props.get("to_world"))[:3, :3]
        cols = m / np.linalg.norm(m, axis=0)
        # gi rotates environments about +y only: to_world must be such a rotation (any
        # uniform scale is irrelevant for directions).
        if not np.allclose(cols[:, 1], [0.0, 1.0, 0.0], atol=1e-5) or abs(cols[1, 0]) > 1e-5:
            raise self.error(
                props["to_world"], "only rotations about the y axis are supported for envmaps"
            )
        rotation = math.degrees(math.atan2(cols[0, 2], cols[0, 0]))
        self.environment = {
            "file": name,
            "intensity": self.float(el, props, "scale", 1.0),
            "rotation": rotation,
        }

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


def _cube() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mitsuba's cube: [-1, 1]³, outward faces with flat normals."""
    verts, faces, normals = [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            u, w = np.roll(np.eye(3), -axis, axis=0)[1:] * np.array([[1], [sign]])
            base = len(verts)
            for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                verts.append(n + a * u + b * w)
                normals.append(n)
            faces += [[base, base + 1, base + 2], [base, base + 2, base + 3]]
    return np.array(verts), np.array(faces), np.array(normals)


DISK_SEGMENTS = 128


def _disk() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mitsuba's disk: radius 1 in the xy plane facing +z, as a fan of
    :data:`DISK_SEGMENTS` triangles (area π·(1 − 4·10⁻⁴))."""
    phi = np.linspace(0.0, 2.0 * np.pi, DISK_SEGMENTS, endpoint=False)
    ring = np.stack([np.cos(phi), np.sin(phi), np.zeros_like(phi)], axis=1)
    verts = np.concatenate([np.zeros((1, 3)), ring])
    i = np.arange(DISK_SEGMENTS)
    faces = np.stack([np.zeros_like(i), 1 + i, 1 + (i + 1) % DISK_SEGMENTS], axis=1)
    return verts, faces, np.tile([0.0, 0.0, 1.0], (len(verts), 1))


def load_mitsuba(path: Path) -> Scene:
    """Reads a Mitsuba 3 XML scene (see the module doc)."""
    try:
        text = path.read_bytes()
    except OSError as e:
        raise scene_error(str(path), "(file)", f"cannot read: {e}") from e
    t = _Translator(path)
    t.run(parse_xml(text, str(path)))
    report(path, t.notes)
    return Scene.from_json(
        json.dumps(t.description()),
        str(path),
        t.meshes,
        t.env_images,
        textures=t.textures.arrays,
    )
