"""Mitsuba XML scenes: the subset that common benchmark scenes use, translated into gi's
scene description (see ``docs/mitsuba.md`` for the subset and the BSDF mapping).

One module per concern: :mod:`.elements` (XML with line numbers), :mod:`.values`
(property values and errors), :mod:`.transforms`, :mod:`.bitmaps`, :mod:`.sensor`,
:mod:`.bsdfs` (one function per BSDF type), :mod:`.shapes`, :mod:`.emitters`, and
:mod:`.translator`, which walks the scene and ties them together.

Every shape becomes an object: an instance of a mesh in its local frame, placed by a
``matrix`` transform, so that shapes that load the same file with the same options, equal
built-in shapes (``rectangle``, ``cube``, ``disk``, ``sphere``), and the shapes of a
``<shapegroup>`` placed by ``<shape type="instance">`` share one mesh. BSDFs become
materials. An element gi cannot render is a :class:`gi.SceneError` whose ``field`` names
the element and its line (``<bsdf type="roughdielectric"> (line 12)``); a property it
ignores is an :class:`gi.AssetWarning`.
"""

from gi.mitsuba.bsdfs import IOR_NAMES
from gi.mitsuba.elements import Element, parse_xml
from gi.mitsuba.metals import METALS
from gi.mitsuba.shapes import DISK_SEGMENTS, _cube, _disk
from gi.mitsuba.transforms import coordinate_system
from gi.mitsuba.translator import Translator, load_mitsuba

_Translator = Translator  # the name tests and scripts used before the split

__all__ = [
    "METALS",
    "DISK_SEGMENTS",
    "IOR_NAMES",
    "Element",
    "Translator",
    "_Translator",
    "_cube",
    "_disk",
    "coordinate_system",
    "load_mitsuba",
    "parse_xml",
]
