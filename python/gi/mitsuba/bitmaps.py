"""``bitmap`` textures: as a material's texture, as a mean colour where gi takes a
constant, and as an emission texture."""

from __future__ import annotations

from typing import Any

import numpy as np

from gi.mitsuba.elements import Element
from gi.mitsuba.values import Reader
from gi.textures import TextureError


def check_bitmap(r: Reader, tex: Element, filtered: bool = True) -> None:
    """A bitmap's properties: `filename`, `raw`, `wrap_mode` (repeat; others warn),
    `filter_type` (bilinear; `nearest` warns: gi filters bilinearly) and a `to_uv` that must
    be the identity (gi's materials have no texture transform). `filtered` False: the
    filter does not matter (a 0/1 opacity cut at 0.5 has the same edges either way)."""
    from gi.mitsuba.transforms import transform

    props = r.props(tex)
    r.refuse_unknown(props, {"filename", "raw", "wrap_mode", "filter_type", "to_uv"})
    if "to_uv" in props and not np.allclose(transform(r, props["to_uv"]), np.eye(4)):
        raise r.error(props["to_uv"], "a texture transform (`to_uv`) is not supported")
    if filtered and r.string(props, "filter_type", "bilinear") != "bilinear":
        r.notes[props["filter_type"].label] = "gi filters textures bilinearly (with mipmaps)"


def use_bitmap(
    r: Reader, desc: dict[str, Any], props: dict[str, Element], name: str, to: str
) -> None:
    """Where property `name` is a bitmap, material field `to` reads it as a texture (its
    factor 1) instead of its mean colour."""
    p = props.get(name)
    if p is None or p.tag not in ("texture", "ref"):
        return
    tex = r.resolve(p) if p.tag == "ref" else p
    check_bitmap(r, tex)
    file = r.file_path(tex, r.string(r.props(tex), "filename", ""))
    raw = r.boolean(r.props(tex), "raw", False)
    try:
        desc[f"{to}_texture"] = r.textures.add(file, not raw)
    except (TextureError, OSError) as e:
        raise r.error(tex, str(e)) from e
    desc[to] = np.ones(3)
    r.notes.pop(tex.label, None)
    wrap = r.string(r.props(tex), "wrap_mode", "repeat")
    if wrap != "repeat":
        r.notes[tex.label] = f"wrap_mode {wrap!r} is not supported; it repeats"


def bitmap_mean(r: Reader, tex: Element) -> np.ndarray:
    """A bitmap's mean colour (linear), with a note that the texture is read as one."""
    if tex.tag != "texture" or tex.attrs.get("type") != "bitmap":
        raise r.error(tex, "only bitmap textures are supported")
    check_bitmap(r, tex)
    props = r.props(tex)
    file = r.file_path(tex, r.string(props, "filename", ""))
    if not file.is_file():
        raise r.error(tex, f"texture file not found: {file}")
    from gi.io import read_image

    try:
        img = read_image(file)[..., :3].astype(np.float64)
    except OSError as e:
        raise r.error(tex, str(e)) from e
    if img.shape[-1] == 1:
        img = np.repeat(img, 3, axis=-1)
    raw = r.boolean(props, "raw", False)
    if not raw and file.suffix.lower() not in (".exr", ".hdr", ".pfm"):
        img = np.where(img <= 0.04045, img / 12.92, ((img + 0.055) / 1.055) ** 2.4)
    mean = img.reshape(-1, 3).mean(axis=0)
    r.notes[tex.label] = (
        f"textures are read as diffuse reflectance only; {file.name}'s mean colour "
        f"({mean[0]:.3f}, {mean[1]:.3f}, {mean[2]:.3f}) is used here"
    )
    return mean


def emission_bitmap(r: Reader, tex: Element) -> tuple[str, list[float]]:
    """A bitmap `radiance`: the texture scaled to [0, 1] (gi's textures are) and the scale
    as the emission."""
    props = r.props(tex)
    if tex.tag != "texture" or tex.attrs.get("type") != "bitmap":
        raise r.error(tex, "only bitmap textures are supported")
    check_bitmap(r, tex)
    file = r.file_path(tex, r.string(props, "filename", ""))
    raw = r.boolean(props, "raw", False)
    try:
        key = r.textures.add(file, not raw)
    except (TextureError, OSError) as e:
        raise r.error(tex, str(e)) from e
    img = r.textures.arrays[key]
    peak = float(img[..., :3].max()) if img.size else 0.0
    if peak > 1.0:
        scaled = img.copy()
        scaled[..., :3] /= peak
        key = r.textures.add_array(f"{key}#emission", scaled)
    wrap = r.string(props, "wrap_mode", "repeat")
    if wrap != "repeat":
        r.notes[tex.label] = f"wrap_mode {wrap!r} is not supported; it repeats"
    return key, [max(peak, 1.0)] * 3
