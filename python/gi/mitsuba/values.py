"""Reading property values: attributes with ``$name`` defaults substituted, numbers,
vectors, the named properties of a plugin, floats, strings, booleans and colours; and the
errors that name the file, the element and its line."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np

from gi._gi import SceneError
from gi.meshes import scene_error
from gi.mitsuba import spectra
from gi.mitsuba.elements import Element
from gi.textures import TextureSet

# Value tags that name a property of their parent plugin.
PROPERTY_TAGS = (
    "float",
    "integer",
    "boolean",
    "string",
    "rgb",
    "srgb",
    "spectrum",
    "point",
    "vector",
    "transform",
    "texture",
)


# Plugins nested in another that gi reads where they belong (checked there).
NESTED_TAGS = frozenset({"ref", "bsdf", "emitter", "film", "sampler", "rfilter"})

# Properties Mitsuba reads as unbounded spectra (a conductor's complex index).
UNBOUNDED = frozenset({"eta", "k"})


class Reader:
    """The file being read: its defaults, ids, the notes (warnings) gathered so far and its
    textures; the value accessors every plugin translator uses."""

    def __init__(self, path: Path):
        self.path = path
        self.file = str(path)
        self.defaults: dict[str, str] = {}
        self.ids: dict[str, Element] = {}
        self.notes: dict[str, str] = {}
        self.textures = TextureSet(path.parent)

    def error(self, el: Element, reason: str) -> SceneError:
        return scene_error(el.file or self.file, el.label, reason)

    def file_path(self, el: Element, name: str) -> Path:
        """A file an element names: relative to the file the element comes from (an
        included file's folder first, as Mitsuba's resolver), else to the scene file."""
        main = self.path.parent / name
        if el.file is not None:
            near = Path(el.file).parent / name
            if near.exists() or not main.exists():
                return near
        return main

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

    def props(self, el: Element) -> dict[str, Element]:
        """The named property children of a plugin element. A child that is neither a
        property nor a nested plugin gi reads (a Mitsuba 0.x `<blackbody>`, a `<medium>`...)
        is a SceneError: ignoring it could change the picture."""
        out = {}
        for c in el.children:
            if c.tag in PROPERTY_TAGS or (c.tag == "ref" and "name" in c.attrs):
                out[self.attr(c, "name")] = c
            elif c.tag not in NESTED_TAGS:
                raise self.error(c, f"unsupported element <{c.tag}> in <{el.tag}>")
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

    def color(
        self, props: dict[str, Element], name: str, default: float, emitter: bool = False
    ) -> np.ndarray:
        """An rgb/srgb/spectrum/float property or a bitmap texture (its mean colour), in
        linear sRGB as Mitsuba's RGB variants read it: `emitter` for an emitter's radiance
        or intensity (spectra not weighted by D65, not bounded), `eta`/`k` unbounded, other
        spectra reflectances (clamped to [0, 1]); see :mod:`gi.mitsuba.spectra`."""
        from gi.mitsuba.bitmaps import bitmap_mean

        p = props.get(name)
        if p is None:
            return np.full(3, default)
        if p.tag == "texture":
            return bitmap_mean(self, p)
        if p.tag == "ref":
            return bitmap_mean(self, self.resolve(p))
        if p.tag == "spectrum":
            return self.spectrum(p, emitter, unbounded=name in UNBOUNDED)
        if p.tag not in ("rgb", "srgb", "float", "integer"):
            raise self.error(p, f"`{name}` must be an rgb, spectrum, float or texture")
        v = self.numbers(p, self.attr(p, "value"))
        if len(v) not in (1, 3):
            raise self.error(p, "expected 1 or 3 numbers")
        rgb = np.array(v * 3 if len(v) == 1 else v)
        if p.tag == "srgb":  # Mitsuba 0.x: a gamma-encoded sRGB colour
            rgb = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
        return rgb

    def spectrum(self, p: Element, emitter: bool, unbounded: bool) -> np.ndarray:
        """``<spectrum value="...">`` (one value or wavelength:value pairs) or
        ``<spectrum filename="...">`` in linear sRGB."""
        if p.attrs.get("type") == "blackbody":
            return self.blackbody(p, emitter, unbounded)
        if "type" in p.attrs:
            raise self.error(p, f"spectrum plugins (type={p.attrs['type']!r}) are not supported")
        has_value, has_file = "value" in p.attrs, "filename" in p.attrs
        if has_value == has_file:
            raise self.error(p, "a <spectrum> takes either `value` or `filename`")
        try:
            if has_file:
                w, v = spectra.read_spd(self.file_path(p, self.attr(p, "filename")))
            else:
                text = self.attr(p, "value")
                if ":" not in text:
                    value = self.numbers(p, text, 1)[0]
                    return spectra.uniform_to_srgb(value, emitter)
                w, v = spectra.parse_pairs(text)
        except (OSError, ValueError) as e:
            raise self.error(p, f"invalid spectrum: {e}") from None
        return spectra.pairs_to_srgb(w, v, emitter, unbounded)

    def blackbody(self, p: Element, emitter: bool, unbounded: bool) -> np.ndarray:
        """``<spectrum type="blackbody">`` in linear sRGB (:func:`spectra.blackbody_pairs`)."""
        props = self.props(p)
        self.refuse_unknown(props, {"temperature", "wavelength_min", "wavelength_max"})
        if "temperature" not in props:
            raise self.error(p, "a blackbody spectrum needs a `temperature`")
        try:
            w, v = spectra.blackbody_pairs(
                self.float(p, props, "temperature", 0.0),
                self.float(p, props, "wavelength_min", 360.0),
                self.float(p, props, "wavelength_max", 830.0),
            )
        except ValueError as e:
            raise self.error(p, f"invalid blackbody spectrum: {e}") from None
        return spectra.pairs_to_srgb(w, v, emitter, unbounded)

    def refuse_unknown(
        self, props: dict[str, Element], known: set[str], cosmetic: frozenset[str] = frozenset()
    ) -> None:
        """A property gi does not read is a :class:`gi.SceneError` naming the file, the
        property and its line: it may change the picture. Those in `cosmetic` (output and
        sampling settings that do not change the rendered radiance) are accepted."""
        for key, p in props.items():
            if key not in known and key not in cosmetic:
                raise self.error(
                    p, f"property `{key}` is not supported (it may change the picture)"
                )

    def resolve(self, ref: Element) -> Element:
        key = self.attr(ref, "id")
        if key not in self.ids:
            raise self.error(ref, f"no element with id `{key}`")
        return self.ids[key]
