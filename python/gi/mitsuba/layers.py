"""BSDFs that wrap another: ``mask`` (an opacity → gi's alpha cut-out), ``normalmap`` (gi's
tangent-space ``normal_texture``) and ``bumpmap`` (a height map converted at load time into
a tangent-space normal map for each shape that uses it).

- ``mask``: the nested BSDF's material with ``alpha_texture`` (A = the opacity as Mitsuba
  evaluates it: the bitmap's value, or its luminance for colour images, sRGB-decoded unless
  ``raw``) and ``alpha_cutoff`` 0.5. Mitsuba's mask is stochastic (opacity 0.3 lets 70% of
  the light through); gi's is a cut-out, exact where the opacity is 0 or 1. A constant
  opacity other than 0 or 1 is refused; texels strictly between (more than 1% of them) are
  named by an AssetWarning.
- ``normalmap``: the texture (RGB = (n + 1)/2 in the frame +x along u, +y up the image, as
  gi's ``normal_texture`` and Mitsuba's ``normalmap``), sRGB-decoded unless ``raw``.
- ``bumpmap``: Mitsuba displaces the surface's tangents by ``scale · ∇h`` (h's derivative
  per unit u and v): n' ∝ (∂p/∂u + n·s·h_u) × (∂p/∂v + n·s·h_v), which in the tangent frame
  is (−s·h_u/|∂p/∂u|, −s·h_v/|∂p/∂v|, 1) for a parameterisation with orthogonal ∂p/∂u,
  ∂p/∂v. gi bakes that per shape with the shape's median |∂p/∂u|, |∂p/∂v| in world space,
  h's derivatives by central differences at texel centres (Mitsuba differentiates the
  bilinear interpolant within each texel cell): an AssetWarning names the approximation.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from gi.meshes import scene_error
from gi.mitsuba.elements import Element
from gi.textures import TextureError, read_image, srgb_to_linear

if TYPE_CHECKING:
    from gi.mitsuba.translator import Translator

LUMINANCE = np.array([0.212671, 0.715160, 0.072169])  # Mitsuba's luminance (linear sRGB)


def nested(t: Translator, el: Element) -> str:
    """The material of the one BSDF a wrapper holds."""
    from gi.mitsuba.bsdfs import bsdf

    inner = [
        c for c in el.children if c.tag == "bsdf" or (c.tag == "ref" and "name" not in c.attrs)
    ]
    if len(inner) != 1:
        raise t.error(el, "give one nested BSDF")
    target = t.resolve(inner[0]) if inner[0].tag == "ref" else inner[0]
    return bsdf(t, target)


def derived(t: Translator, el: Element, base: str, fields: dict[str, Any], name: str | None) -> str:
    """A copy of material `base` with `fields`, named after the wrapper."""
    name = el.attrs.get("id") or name or f"bsdf@{el.line}"
    while name in t.materials:
        name += "'"
    t.materials[name] = dict(t.materials[base]) | fields
    t.material_of[id(el)] = name
    return name


def texture_values(t: Translator, tex: Element, filtered: bool = True) -> np.ndarray:
    """A bitmap as Mitsuba evaluates it: (H, W, C) linear unless ``raw``."""
    if tex.tag != "texture" or tex.attrs.get("type") != "bitmap":
        raise t.error(tex, "only bitmap textures are supported here")
    from gi.mitsuba.bitmaps import check_bitmap

    props = t.props(tex)
    check_bitmap(t, tex, filtered)
    file = t.file_path(tex, t.string(props, "filename", ""))
    try:
        img, integer = read_image(file)
    except (TextureError, OSError) as e:
        raise t.error(tex, str(e)) from None
    img = img[..., :3] if img.shape[2] >= 3 else img[..., :1]
    if integer and not t.boolean(props, "raw", False):
        img = srgb_to_linear(np.clip(img, 0, None))
    return img.astype(np.float64)


def scalar(img: np.ndarray) -> np.ndarray:
    """Mitsuba's ``eval_1``: the value of a 1-channel image, a colour image's luminance."""
    return img[..., 0] if img.shape[2] == 1 else img @ LUMINANCE


def texture_child(t: Translator, el: Element, name: str | None) -> Element | None:
    """The texture a wrapper names `name` (or its only unnamed/any texture)."""
    props = t.props(el)
    for key, p in props.items():
        if name is None or key == name:
            if p.tag in ("texture", "ref"):
                return t.resolve(p) if p.tag == "ref" else p
    return None


def mask(t: Translator, el: Element, name: str | None) -> str:
    props = t.props(el)
    t.refuse_unknown(props, {"opacity"})
    base = nested(t, el)
    p = props.get("opacity")
    if p is not None and p.tag in ("texture", "ref"):
        tex = t.resolve(p) if p.tag == "ref" else p
        alpha = scalar(texture_values(t, tex, filtered=False))
    else:
        value = float(t.color(props, "opacity", 0.5).mean())
        if value not in (0.0, 1.0):
            raise t.error(
                p or el, f"a constant opacity of {value:g} is not supported (gi cuts out)"
            )
        alpha = np.full((1, 1), value)
    between = ((alpha > 0.01) & (alpha < 0.99)).mean()
    if between > 0.01:
        t.notes[el.label] = f"opacity between 0 and 1 ({between:.0%} of texels) is cut at 0.5"
    rgba = np.concatenate([np.ones(alpha.shape + (3,)), alpha[..., None]], axis=2)
    key = t.textures.add_array(f"mask@{el.line}#linear", rgba)
    return derived(t, el, base, {"alpha_texture": key, "alpha_cutoff": 0.5}, name)


# Mitsuba's normalmap/bumpmap options gi reads (see :func:`note_shadowing`).
OPTIONS = {"use_shadowing_function", "flip_invalid_normals"}
SHADOWING = (
    "Mitsuba's shadowing term for perturbed normals (Estevez et al. 2019, "
    "use_shadowing_function) is not applied: brighter by 1 - 2/(1 + sqrt(1 + a2 tan2(theta_o))), "
    "a2 = min(tan2(tilt)/8, 1) (1.3% at a 30 degree tilt lit at 48 degrees)"
)


def note_shadowing(t: Translator, el: Element, props: dict[str, Element], said: str = "") -> None:
    """The AssetWarning of a normal or bump map: Mitsuba attenuates the nested BSDF by a
    shadowing term unless `use_shadowing_function` is false; gi does not."""
    notes = [said] if said else []
    if t.boolean(props, "use_shadowing_function", True):
        notes.append(SHADOWING)
    if notes:
        t.notes[el.label] = "; ".join(notes)


def normalmap(t: Translator, el: Element, name: str | None) -> str:
    props = t.props(el)
    t.refuse_unknown(props, {"normalmap"} | OPTIONS)
    note_shadowing(t, el, props)
    tex = texture_child(t, el, "normalmap")
    if tex is None:
        raise t.error(el, "a normalmap needs a `normalmap` bitmap texture")
    base = nested(t, el)
    img = texture_values(t, tex)
    if img.shape[2] != 3:
        raise t.error(tex, "a normal map needs an RGB image")
    rgba = np.concatenate([img, np.ones(img.shape[:2] + (1,))], axis=2)
    out = derived(t, el, base, {}, name)
    t.normal_maps[out] = rgba
    return out


def orient_normal_map(t: Translator, material: str, mesh: str, matrix: np.ndarray) -> str:
    """The material for a shape (`mesh` placed by `matrix`) with a normal-mapped `material`.
    Mitsuba's map frame is (s, n × s, n) with s along ∂p/∂u; gi's (t, −w·n × t, n) with w
    the UV handedness (its bitangent w·n × t runs along +v). They agree where w = −1 (v runs
    against n × s, as on OBJ meshes with Mitsuba's flipped v); where the shape's UVs have
    w = +1 (Mitsuba's rectangle, v up +y) the map's green is flipped for gi. A shape whose
    triangles disagree takes the majority, with an AssetWarning."""
    v, f, _n, _m, _fm, uv = t.meshes[mesh]
    if uv is None:
        raise scene_error(t.file, material, "a normal-mapped shape needs UVs")
    p = (v.astype(np.float64) @ matrix[:3, :3].T)[f]
    w = handedness(p, uv.astype(np.float64)[f])
    flip = (w > 0).sum() > (w < 0).sum()
    if (w > 0).any() and (w < 0).any():
        t.notes[f"material {material} on {mesh}"] = (
            "the shape's UVs mix handedness: the normal map's green follows the majority"
        )
    key = f"{material}#normals{'-flipped' if flip else ''}"
    if key not in t.materials:
        rgba = t.normal_maps[material].copy()
        if flip:
            rgba[..., 1] = 1.0 - rgba[..., 1]
        tex = t.textures.add_array(f"{key}#linear", rgba)
        t.materials[key] = dict(t.materials[material]) | {"normal_texture": tex}
    return key


def handedness(p: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Per triangle (p: (n, 3, 3), uv: (n, 3, 2)): +1 where ∂p/∂v runs along n × ∂p/∂u, −1
    against, 0 for degenerate UVs (gi's `triangle_tangent`)."""
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    d1, d2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    ok = np.abs(det) > 1e-20
    det = np.where(ok, det, 1.0)
    tangent = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) / det[:, None]
    bitangent = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) / det[:, None]
    n = np.cross(e1, e2)
    return np.where(ok, np.sign((np.cross(n, tangent) * bitangent).sum(axis=1)), 0.0)


def bumpmap(t: Translator, el: Element, name: str | None) -> str:
    """Records the height map; :func:`bake_bump` makes each shape's normal map."""
    props = t.props(el)
    tex = texture_child(t, el, None)
    if tex is None:
        raise t.error(el, "a bumpmap needs a bitmap texture (the height)")
    t.refuse_unknown(
        props, {"scale", *(k for k, p in props.items() if p.tag in ("texture", "ref"))}
    )
    scale = t.float(el, props, "scale", 1.0)
    base = nested(t, el)
    height = scalar(texture_values(t, tex))
    out = derived(t, el, base, {}, name)
    t.bumps[out] = (height, scale)
    note_shadowing(
        t,
        el,
        props,
        "bump map baked into a tangent-space normal map per shape (central differences at "
        "texel centres, the shape's median |dp/du|, |dp/dv|; Mitsuba differentiates the "
        "bilinear interpolant per texel cell)",
    )
    return out


def bake_bump(t: Translator, material: str, mesh: str, matrix: np.ndarray) -> str:
    """The material for a shape (`mesh` placed by `matrix`) with a bump-mapped `material`: a
    copy with the normal map baked for the shape's world-space |∂p/∂u| and |∂p/∂v|."""
    height, scale = t.bumps[material]
    v, f, _n, _m, _fm, uv = t.meshes[mesh]
    if uv is None:
        raise scene_error(t.file, material, "a bump-mapped shape needs UVs")
    w = v.astype(np.float64) @ matrix[:3, :3].T
    a, b = tangent_lengths(w[f], uv.astype(np.float64)[f])
    rows, cols = height.shape
    hu = (np.roll(height, -1, axis=1) - np.roll(height, 1, axis=1)) * 0.5 * cols
    hv = (np.roll(height, -1, axis=0) - np.roll(height, 1, axis=0)) * 0.5 * rows
    # v runs down the image (Mitsuba's), so +y (up the image) is -dp/dv: y = +s·h_v/|dp/dv|.
    n = np.stack([-scale * hu / a, scale * hv / b, np.ones_like(height)], axis=2)
    n /= np.linalg.norm(n, axis=2, keepdims=True)
    rgba = np.concatenate([n * 0.5 + 0.5, np.ones((rows, cols, 1))], axis=2)
    key = f"{material}#bump {a:.4g} {b:.4g}"
    if key not in t.materials:
        tex = t.textures.add_array(f"{key}#linear", rgba)
        t.materials[key] = dict(t.materials[material]) | {"normal_texture": tex}
    return key


def tangent_lengths(p: np.ndarray, uv: np.ndarray) -> tuple[float, float]:
    """Median |∂p/∂u| and |∂p/∂v| over triangles (p, uv: (n, 3, 3) and (n, 3, 2))."""
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    d1, d2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    det = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    ok = np.abs(det) > 1e-12
    if not ok.any():
        return 1.0, 1.0
    inv = 1.0 / det[ok]
    dpdu = (e1[ok] * d2[ok, 1:2] - e2[ok] * d1[ok, 1:2]) * inv[:, None]
    dpdv = (e2[ok] * d1[ok, 0:1] - e1[ok] * d2[ok, 0:1]) * inv[:, None]
    return float(np.median(np.linalg.norm(dpdu, axis=1))), float(
        np.median(np.linalg.norm(dpdv, axis=1))
    )
