"""The XML layer: elements with the line each starts on, parsed by expat."""

from __future__ import annotations

import xml.parsers.expat
from dataclasses import dataclass, field

from gi.meshes import scene_error


@dataclass
class Element:
    """One XML element with the line it starts on."""

    tag: str
    attrs: dict[str, str]
    line: int
    children: list[Element] = field(default_factory=list)
    # The file the element comes from when it is not the scene file (an <include>).
    file: str | None = None

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
