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
from gi.mitsuba.metals import METALS
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
    "thindielectric": {"int_ior", "ext_ior", "specular_reflectance", "specular_transmittance"},
    "roughdielectric": {"int_ior", "ext_ior", "specular_reflectance", "specular_transmittance"}
    | _ROUGH,
    "plastic": _PLASTIC,
    "roughplastic": _PLASTIC | _ROUGH,
}
COSMETIC = frozenset({"sample_visible"})
# Mitsuba's BSDFs that scatter on both sides by nature; every other one is black seen or lit
# from behind (the side away from the shape's normal) unless wrapped in `twosided`: gi's
# `one_sided` material flag.
TWO_SIDED_BY_NATURE = frozenset({"dielectric", "thindielectric", "roughdielectric"})


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
    """gi's roughness (√α) of a rough BSDF's `alpha` (or √(αu·αv), with a note); Mitsuba
    clamps α to 1e-4 (a rough BSDF never becomes a mirror)."""
    if "alpha_u" in props or "alpha_v" in props:
        if el.attrs.get("type") == "roughplastic":
            raise r.error(el, "roughplastic has no anisotropic roughness (Mitsuba refuses it)")
        au = r.float(el, props, "alpha_u", 0.1)
        av = r.float(el, props, "alpha_v", 0.1)
        alpha = math.sqrt(au * av)
        r.notes[el.label] = "anisotropic roughness is not supported; sqrt(αu·αv)"
    else:
        alpha = r.float(el, props, "alpha", 0.1)
    return min(math.sqrt(max(alpha, 1e-4)), 1.0)


def distribution(r: Reader, props: Props) -> str:
    """A rough BSDF's microfacet distribution (Mitsuba's default: Beckmann)."""
    name = r.string(props, "distribution", "beckmann").strip().lower()
    if name not in ("beckmann", "ggx"):
        raise r.error(props["distribution"], f"unknown distribution {name!r} (beckmann, ggx)")
    return name


def diffuse(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    desc = {"diffuse": r.color(props, "reflectance", 0.5)}
    use_bitmap(r, desc, props, "reflectance", "diffuse")
    return desc


def conductor(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    """Mitsuba's conductor: the exact Fresnel term of `eta + i·k` (given, or a named
    metal's RGB index as Mitsuba's RGB variants have it), times `specular_reflectance`."""
    metal = r.string(props, "material", "none")
    if "eta" in props or "k" in props or metal == "none":
        if metal != "none":
            raise r.error(props["material"], "give either eta and k or material, not both")
        eta = [float(x) for x in r.color(props, "eta", 0.0)]
        k = [float(x) for x in r.color(props, "k", 1.0)]
    elif metal in METALS:
        eta, k = (list(v) for v in METALS[metal])
    else:
        raise r.error(props["material"], f"unknown conductor {metal!r}")
    if min(eta + k) < 0:
        raise r.error(el, "eta and k must not be negative")
    return {
        "diffuse": np.zeros(3),
        "specular": r.color(props, "specular_reflectance", 1.0),
        "conductor_eta": eta,
        "conductor_k": k,
    }


def roughconductor(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    rough = {"roughness": roughness(r, el, props), "distribution": distribution(r, props)}
    return conductor(r, el, props) | rough


def dielectric(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    n = ior(r, props, "int_ior", 1.5046) / ior(r, props, "ext_ior", 1.000277)
    return {
        "diffuse": np.zeros(3),
        "transmission": r.color(props, "specular_transmittance", 1.0),
        "ior": min(max(n, 1.0), 4.0),
    }


def thindielectric(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    """Mitsuba's thindielectric: a thin slab of index int_ior/ext_ior (defaults bk7 1.5046 /
    air 1.000277), reflecting R' = R + T²R/(1 − R²) = 2R/(1 + R) times
    `specular_reflectance` and passing the rest, times `specular_transmittance`, straight
    through (gi's `thin_glass`; both default 1). A slab that transmits nothing is refused."""
    n = ior(r, props, "int_ior", 1.5046) / ior(r, props, "ext_ior", 1.000277)
    if not 1.0 <= n <= 4.0:
        raise r.error(el, f"the relative index int_ior/ext_ior = {n:.4g} is not in [1, 4]")
    transmission = r.color(props, "specular_transmittance", 1.0)
    if float(np.max(transmission)) <= 0.0:
        raise r.error(el, "a thindielectric with specular_transmittance 0 is not supported")
    return {
        "diffuse": np.zeros(3),
        "transmission": transmission,
        "ior": n,
        "thin_glass": r.color(props, "specular_reflectance", 1.0),
    }


def roughdielectric(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    """Mitsuba's roughdielectric (Walter et al. 2007): gi's `rough_glass` of index
    int_ior/ext_ior, `specular` = `specular_reflectance` and `transmission` =
    `specular_transmittance` (both default 1). Anisotropic roughness (αu ≠ αv) is refused."""
    if ("alpha_u" in props or "alpha_v" in props) and "alpha" not in props:
        au = r.float(el, props, "alpha_u", 0.1)
        av = r.float(el, props, "alpha_v", 0.1)
        if not math.isclose(au, av, rel_tol=1e-6):
            key = "alpha_u" if "alpha_u" in props else "alpha_v"
            raise r.error(props[key], "anisotropic roughness (alpha_u ≠ alpha_v) is not supported")
        alpha = au
    else:
        alpha = r.float(el, props, "alpha", 0.1)
    n = ior(r, props, "int_ior", 1.5046) / ior(r, props, "ext_ior", 1.000277)
    if not 1.0 < n <= 4.0:
        raise r.error(el, f"the relative index int_ior/ext_ior = {n:.4g} is not in (1, 4]")
    return {
        "diffuse": np.zeros(3),
        "specular": r.color(props, "specular_reflectance", 1.0),
        "transmission": r.color(props, "specular_transmittance", 1.0),
        "ior": n,
        "roughness": min(math.sqrt(max(alpha, 1e-4)), 1.0),
        "distribution": distribution(r, props),
        "rough_glass": True,
    }


def plastic(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    """Mitsuba's plastic: the diffuse base under a dielectric coating of index
    int_ior/ext_ior (gi's `coating_ior`), `specular_reflectance` multiplying its Fresnel
    reflectance, `nonlinear` as Mitsuba's."""
    n = ior(r, props, "int_ior", 1.49) / ior(r, props, "ext_ior", 1.000277)
    if not 1.0 < n <= 4.0:
        raise r.error(el, f"the coating's index int_ior/ext_ior = {n:.4g} is not in (1, 4]")
    desc = {
        "diffuse": r.color(props, "diffuse_reflectance", 0.5),
        "specular": r.color(props, "specular_reflectance", 1.0),
        "coating_ior": n,
        "coating_nonlinear": r.boolean(props, "nonlinear", False),
    }
    use_bitmap(r, desc, props, "diffuse_reflectance", "diffuse")
    return desc


def roughplastic(r: Reader, el: Element, props: Props) -> dict[str, Any]:
    rough = {"roughness": roughness(r, el, props), "distribution": distribution(r, props)}
    return plastic(r, el, props) | rough


BSDFS: dict[str, Callable[[Reader, Element, Props], dict[str, Any]]] = {
    "diffuse": diffuse,
    "conductor": conductor,
    "roughconductor": roughconductor,
    "dielectric": dielectric,
    "thindielectric": thindielectric,
    "roughdielectric": roughdielectric,
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
    if kind not in TWO_SIDED_BY_NATURE:
        desc["one_sided"] = True
    t.refuse_unknown(props, KNOWN[kind or ""], COSMETIC)
    name = el.attrs.get("id") or name or f"bsdf@{el.line}"
    while name in t.materials:
        name += "'"
    t.materials[name] = {
        k: (np.clip(v, 0.0, 1.0).tolist() if isinstance(v, np.ndarray) else v)
        for k, v in desc.items()
    }
    t.material_of[id(el)] = name
    return name


def twosided(t: Translator, el: Element, name: str | None) -> str:
    """``twosided``: its inner BSDF on both faces (gi's material without ``one_sided``).
    The inner BSDF keeps its one-sided material for any other use of it."""
    inner = [c for c in el.children if c.tag in ("bsdf", "ref")]
    if len(inner) != 1:
        raise t.error(el, "give one inner BSDF (one BSDF a side is not supported)")
    target = t.resolve(inner[0]) if inner[0].tag == "ref" else inner[0]
    fresh = id(target) not in t.material_of
    base = bsdf(t, target, el.attrs.get("id") or name)
    if not t.materials[base].get("one_sided"):
        t.material_of[id(el)] = base
        return base
    desc = {k: v for k, v in t.materials[base].items() if k != "one_sided"}
    if fresh:  # only this wrapper uses the inner BSDF so far: its material becomes two-sided
        t.materials[base] = desc
        del t.material_of[id(target)]
        t.material_of[id(el)] = base
        return base
    name = el.attrs.get("id") or name or f"bsdf@{el.line}"
    while name in t.materials:
        name += "'"
    t.materials[name] = desc
    t.material_of[id(el)] = name
    return name
