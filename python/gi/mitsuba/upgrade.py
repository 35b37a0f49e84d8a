"""The version upgrade of files older than Mitsuba 2: what Mitsuba 3's parser does to them
before reading (``upgrade_tree`` in its former ``src/core/xml.cpp``; ``upgrade_from_v1`` in
``src/core/parser.cpp`` since 3.6), applied to the element tree in place:

1. every ``name`` attribute (except a ``<default>``'s) from camelCase to snake_case: an
   underscore between a lower-case letter and the upper-case one after it, that upper-case
   run lower-cased (``toWorld`` → ``to_world``, ``intIOR`` → ``int_ior``, ``fovAxis`` →
   ``fov_axis``, ``sampleCount`` → ``sample_count``);
2. ``<lookAt>`` → ``<lookat>`` (Mitsuba 3.0–3.5 did this; 3.6+ refuses such files);
3. a ``diffuse`` BSDF's ``diffuse_reflectance`` → ``reflectance``;
4. ``uoffset``/``voffset``/``uscale``/``vscale`` floats → a ``to_uv`` transform (scale
   after translate), as Mitsuba 3.6+ builds it.

Mitsuba 3.0–3.5 also renamed ids that start with ``_`` (reserved there); gi reserves none,
so they are kept. Files of version 2 and later, and files without a version, are read as
written."""

from __future__ import annotations

from gi.mitsuba.elements import Element

UV_NAMES = ("uoffset", "voffset", "uscale", "vscale")


def version(root: Element) -> tuple[int, ...] | None:
    """The root's ``version`` as numbers (None when absent or not numbers)."""
    text = root.attrs.get("version")
    if text is None:
        return None
    try:
        return tuple(int(p) for p in text.strip().split("."))
    except ValueError:
        return None


def camel_to_snake(name: str) -> str:
    """Mitsuba's camelCase → underscore_case (ASCII letters only, as ``std::islower``)."""
    out = []
    i = 0
    while i < len(name):
        c = name[i]
        if (
            i > 0
            and name[i - 1].islower()
            and name[i - 1].isascii()
            and c.isupper()
            and c.isascii()
        ):
            out.append("_" + c.lower())
            while i + 1 < len(name) and name[i + 1].isupper() and name[i + 1].isascii():
                i += 1
                out.append(name[i].lower())
        else:
            out.append(c)
        i += 1
    return "".join(out)


def upgrade(root: Element) -> bool:
    """Upgrades a tree older than 2.0.0 in place; returns whether it did."""
    v = version(root)
    if v is None or v >= (2, 0, 0):
        return False
    _walk(root)
    return True


def _walk(el: Element) -> None:
    if el.tag == "lookAt":
        el.tag = "lookat"
    if "name" in el.attrs and el.tag != "default":
        el.attrs["name"] = camel_to_snake(el.attrs["name"])
    for c in el.children:
        _walk(c)
    if el.tag == "bsdf" and el.attrs.get("type") == "diffuse":
        for c in el.children:
            if c.attrs.get("name") == "diffuse_reflectance":
                c.attrs["name"] = "reflectance"
    _uv_transform(el)


def _uv_transform(el: Element) -> None:
    """uoffset/voffset/uscale/vscale floats → ``<transform name="to_uv">``."""
    found = {
        c.attrs["name"]: c
        for c in el.children
        if c.tag == "float" and c.attrs.get("name") in UV_NAMES
    }
    if not found:
        return
    line = min(c.line for c in found.values())
    el.children = [c for c in el.children if c not in found.values()]

    def value(key: str, default: str) -> str:
        return found[key].attrs.get("value", default) if key in found else default

    ops = [
        Element("translate", {"x": value("uoffset", "0"), "y": value("voffset", "0")}, line),
        Element("scale", {"x": value("uscale", "1"), "y": value("vscale", "1")}, line),
    ]
    el.children.append(Element("transform", {"name": "to_uv"}, line, ops))
