"""BSDFs onto gi's materials: one function per Mitsuba BSDF type (:data:`BSDFS`), each
taking the element and its properties and returning the material's fields; :func:`bsdf`
translates an element once (``twosided`` unwrapped) and names its material."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from gi.mitsuba.bitmaps import use_bitmap
from gi.mitsuba.elements import Element
from gi.mitsuba.values import Reader

if TYPE_CHECKING:
    from gi.mitsuba.translator import Translator

Props = dict[str, Element]

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

# Properties each BSDF type's function reads; any other is a SceneError (it may change the
# picture). `sample_visible` only changes how a microfacet lobe is sampled (the noise).
_CONDUCTOR = {"material", "eta", "k", "specular_reflectance"}
_ROUGH = {"alpha", "alpha_u", "alpha_v", "distribution"}
_PLASTIC = {"int_ior", "ext_ior", "diffuse_reflectance", "specular_reflectance", "nonlinear"}
KNOWN = {
    "diffuse": {"reflectance"},
    "conductor": _CONDUCTOR,
    "roughconductor": _CONDUCTOR | _ROUGH,
    "dielectric": {"int_ior", "ext_ior", "specular_transmittance"},
    "plastic": _PLASTIC,
    "roughplastic": _PLASTIC | _ROUGH,
}
COSMETIC = frozenset({"sample_visible"})


def ior(r: Reader, props: Props, name: str, default: float) -> float:
    """An index of refraction: a number or one of Mitsuba's named ones."""
    p = props.get(name)
    if p is None:
        return default
    value = r.attr(p, "value").strip()
    if p.tag == "string" or value.lower() in IOR_NAMES:
        if value.lower() not in IOR_NAMES:
            raise r.error(p, f"unknown index of refraction {value!r}")
        return IOR_NAMES[value.lower()]
    return r.float(p, props, name, default)


def roughness(r: Reader, el: Element, props: Props) -> float:
    """gi's roughness (√α) of a rough BSDF's `alpha` (or √(αu·αv), with a note)."""
    if "alpha_u" in props or "alpha_v" in props:
        au = r.float(el, props, "alpha_u", 0.1)
        av = r.float(el, props, "alpha_v", 0.1)
        alpha = math.sqrt(au * av)
        r.notes[el.label] = "anisotropic roughness is not supported; sqrt(αu·αv)"
    else:
        alpha = r.float(el, props, "alpha", 0.1)
    return min(max(math.sqrt(max(alpha, 0.0)), 0.0), 1.0)


def diffuse(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    desc = {"diffuse": r.color(props, "reflectance", 0.5)}
    use_bitmap(r, desc, props, "reflectance", "diffuse")
    return desc


def conductor(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    metal = r.string(props, "material", "none")
    if "eta" in props or "k" in props:
        eta = r.color(props, "eta", 0.0)
        k = r.color(props, "k", 1.0)
        f0 = ((eta - 1) ** 2 + k**2) / ((eta + 1) ** 2 + k**2)
    elif metal in CONDUCTOR_F0:
        f0 = np.array(CONDUCTOR_F0[metal])
    else:
        raise r.error(props["material"], f"unknown conductor {metal!r}")
    return {
        "diffuse": np.zeros(3),
        "specular": f0 * r.color(props, "specular_reflectance", 1.0),
        "fresnel": metal != "none" or "eta" in props,
    }


def roughconductor(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    return conductor(r, el, props) | {"roughness": roughness(r, el, props)}


def dielectric(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    n = ior(r, props, "int_ior", 1.5046) / ior(r, props, "ext_ior", 1.000277)
    return {
        "diffuse": np.zeros(3),
        "transmission": r.color(props, "specular_transmittance", 1.0),
        "ior": min(max(n, 1.0), 4.0),
    }


def plastic(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    n = ior(r, props, "int_ior", 1.49) / ior(r, props, "ext_ior", 1.000277)
    f0 = ((n - 1) / (n + 1)) ** 2
    desc = {
        "diffuse": r.color(props, "diffuse_reflectance", 0.5),
        "specular": f0 * r.color(props, "specular_reflectance", 1.0),
        "fresnel": True,
    }
    use_bitmap(r, desc, props, "diffuse_reflectance", "diffuse")
    return desc


def roughplastic(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    return plastic(r, el, props) | {"roughness": roughness(r, el, props)}


BSDFS: dict[str, Callable[[Reader, Element, Props], dict[str, Any]]] = {
    "diffuse": diffuse,
    "conductor": conductor,
    "roughconductor": roughconductor,
    "dielectric": dielectric,
    "plastic": plastic,
    "roughplastic": roughplastic,
}


def bsdf(t: Translator, el: Element, name: str | None = None) -> str:
    """Translates a BSDF (once) and returns its material name (its id, else `name`, else
    where it is)."""
    if id(el) in t.material_of:
        return t.material_of[id(el)]
    kind = el.attrs.get("type")
    if kind == "twosided":
        return twosided(t, el, name)
    if kind in ("mask", "normalmap", "bumpmap"):
        from gi.mitsuba import layers

        return getattr(layers, kind)(t, el, name)
    translate = BSDFS.get(kind or "")
    if translate is None:
        raise t.error(el, "unsupported BSDF (see docs/mitsuba.md for the list)")
    props = t.props(el)
    ext_eta = props.pop("ext_eta", None)  # Mitsuba 0.x conductors: the outside's index
    if ext_eta is not None and t.float(ext_eta, {"ext_eta": ext_eta}, "ext_eta", 1.0) != 1.0:
        raise t.error(ext_eta, "property `ext_eta` other than 1 is not supported")
    desc = translate(t, el, props)
    t.refuse_unknown(props, KNOWN[kind or ""], COSMETIC)
    note_approximations(t, el, kind or "", props)
    name = el.attrs.get("id") or name or f"bsdf@{el.line}"
    while name in t.materials:
        name += "'"
    t.materials[name] = {
        k: (np.clip(v, 0.0, 1.0).tolist() if isinstance(v, np.ndarray) else v)
        for k, v in desc.items()
    }
    t.material_of[id(el)] = name
    return name


def note_approximations(t: Translator, el: Element, kind: str, props: Props) -> None:
    """An AssetWarning for each way the uber BSDF approximates Mitsuba's model (until the
    `materials` branch's models replace these mappings)."""
    said = []
    if kind.startswith("rough"):
        dist = t.string(props, "distribution", "beckmann").lower()
        if dist != "ggx":
            said.append(f"the {dist} distribution is rendered as GGX")
    if kind in ("plastic", "roughplastic"):
        said.append("the coating over the diffuse base is Lambert + Fresnel-weighted GGX")
    if kind in ("conductor", "roughconductor") and ("eta" in props or "material" in props):
        said.append("the complex index is reduced to Schlick's F0")
    if said:
        t.notes[el.label] = "; ".join(said)


def twosided(t: Translator, el: Element, name: str | None) -> str:
    """``twosided``: its inner BSDF (gi's opaque surfaces are two-sided already)."""
    inner = [c for c in el.children if c.tag in ("bsdf", "ref")]
    if len(inner) != 1:
        raise t.error(el, "gi's opaque surfaces are two-sided: give one inner BSDF")
    target = t.resolve(inner[0]) if inner[0].tag == "ref" else inner[0]
    name = bsdf(t, target, el.attrs.get("id") or name)
    t.material_of[id(el)] = name
    return name
