"""``<include filename="...">``: the top-level elements of another scene file, read in its
place (each upgraded by its own ``version``, as Mitsuba 3 does, and naming its own file in
errors), at any level: inside a ``<shape>`` its elements become the shape's (a BSDF, an
emitter), as Mitsuba 3 reads them. Relative paths inside it resolve against its folder
first, then the scene's."""

from __future__ import annotations

from gi.mitsuba.elements import Element, parse_xml
from gi.mitsuba.upgrade import upgrade
from gi.mitsuba.values import Reader

MAX_DEPTH = 16


def expand_includes(r: Reader, root: Element, depth: int = 0) -> None:
    """Replaces each ``<include>`` in `root` (at any depth) by the included scene's
    elements."""
    children: list[Element] = []
    for c in root.children:
        if c.tag != "include":
            expand_includes(r, c, depth)
            children.append(c)
            continue
        unknown = set(c.attrs) - {"filename", "name"}
        if unknown:
            raise r.error(c, f"unknown attribute `{sorted(unknown)[0]}`")
        if depth >= MAX_DEPTH:
            raise r.error(c, f"includes nested more than {MAX_DEPTH} deep (a cycle?)")
        path = r.file_path(c, r.attr(c, "filename"))
        try:
            text = path.read_bytes()
        except OSError as e:
            raise r.error(c, f"cannot read {path}: {e}") from None
        sub = parse_xml(text, str(path))
        if sub.tag != "scene":
            raise r.error(c, f"{path.name}'s root element is <{sub.tag}>, not <scene>")
        upgrade(sub)
        _mark(sub, str(path))
        expand_includes(r, sub, depth + 1)
        children.extend(sub.children)
    root.children = children


def _mark(el: Element, file: str) -> None:
    el.file = file
    for c in el.children:
        _mark(c, file)
