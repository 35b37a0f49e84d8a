"""Prints Mitsuba 3's BSDF values (scalar_rgb ``BSDF::eval``, |cos θ| of the outgoing
direction included) for the materials and direction pairs of
crates/core/src/bsdf/tests_models.rs::MITSUBA_EVALS, in that table's order, then those of
crates/core/src/bsdf/tests_rough_dielectric.rs::MITSUBA_EVALS (roughdielectric, both sides,
radiance and importance transport) and the single-scattering losses of its LOSSES table.

Run: /work/main/.venv/bin/python scripts/data/mitsuba_bsdf_values.py  (pip install
mitsuba==3.9.1)."""

import math

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")

RHO = {"type": "rgb", "value": [0.8, 0.3, 0.05]}
CASES = {
    "plastic": {"type": "plastic", "diffuse_reflectance": RHO},
    "plastic_nl": {"type": "plastic", "diffuse_reflectance": RHO, "nonlinear": True},
    "rp_beck": {"type": "roughplastic", "diffuse_reflectance": RHO},
    "rp_ggx_nl": {
        "type": "roughplastic",
        "distribution": "ggx",
        "alpha": 0.3,
        "nonlinear": True,
        "diffuse_reflectance": RHO,
    },
    "rc_au_ggx": {"type": "roughconductor", "material": "Au", "distribution": "ggx", "alpha": 0.2},
    "rc_cu_beck": {"type": "roughconductor", "material": "Cu", "alpha": 0.3},
}
# (cos θ, φ) of the incident (Mitsuba's wi, gi's wo) and outgoing directions.
PAIRS = [
    ((0.9, 0.0), (0.7, 3.0)),
    ((0.5, 0.0), (0.5, math.pi + 0.1)),
    ((0.2, 1.0), (0.95, 2.0)),
    ((0.3, 0.0), (0.28, math.pi)),
]


ROUGH_DIELECTRIC = {
    "rd_beck": {"type": "roughdielectric", "alpha": 0.1, "int_ior": 1.5, "ext_ior": 1.0},
    "rd_ggx": {
        "type": "roughdielectric",
        "distribution": "ggx",
        "alpha": 0.3,
        "int_ior": 1.5,
        "ext_ior": 1.0,
        "specular_reflectance": {"type": "rgb", "value": [0.8, 0.8, 0.8]},
        "specular_transmittance": {"type": "rgb", "value": [0.9, 0.7, 0.5]},
    },
    "rd_ggx_rough": {
        "type": "roughdielectric",
        "distribution": "ggx",
        "alpha": 0.8,
        "int_ior": 1.33,
        "ext_ior": 1.0,
    },
}
# Both sides: reflections outside and inside (total internal reflection included) and
# refractions both ways; cos θ < 0 is inside.
ROUGH_PAIRS = [
    ((0.9, 0.0), (0.7, 3.0)),
    ((0.5, 0.0), (0.5, math.pi + 0.1)),
    ((0.8, 0.0), (-0.9, math.pi + 0.1)),
    ((0.5, 0.3), (-0.8, math.pi + 0.2)),
    ((0.3, 0.0), (-0.6, math.pi)),
    ((0.95, 1.0), (-0.3, 1.0 + math.pi)),
    ((0.6, 0.0), (-0.5, 0.4)),
    ((-0.8, 0.0), (0.5, math.pi + 0.1)),
    ((-0.9, 0.0), (0.3, math.pi)),
    ((-0.6, 0.0), (-0.6, math.pi + 0.05)),
    ((-0.3, 0.0), (-0.3, math.pi)),
]


def direction(c: float, phi: float) -> mi.Vector3f:
    s = math.sqrt(1 - c * c)
    return mi.Vector3f(s * math.cos(phi), s * math.sin(phi), c)


def importance_sample(bsdf, ctx, si, u) -> float:
    _, w = bsdf.sample(ctx, si, float(u[0]), mi.Point2f(float(u[1]), float(u[2])))
    return w[0]


def value(bsdf, ctx, wi, wo) -> str:
    si = mi.SurfaceInteraction3f()
    si.wi = direction(*wi)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    v = bsdf.eval(ctx, si, direction(*wo))
    return f"[{v[0]:.6g}, {v[1]:.6g}, {v[2]:.6g}]"


def main() -> None:
    ctx = mi.BSDFContext()
    for name, desc in CASES.items():
        bsdf = mi.load_dict(desc)
        for wi, wo in PAIRS:
            si = mi.SurfaceInteraction3f()
            si.wi = direction(*wi)
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            v = bsdf.eval(ctx, si, direction(*wo))
            print(f'("{name}", {wi}, {wo}, [{v[0]:.6g}, {v[1]:.6g}, {v[2]:.6g}]),')
    importance = mi.BSDFContext(mi.TransportMode.Importance)
    print("// roughdielectric: (case, wo, wi, radiance, importance)")
    for name, desc in ROUGH_DIELECTRIC.items():
        bsdf = mi.load_dict(desc)
        for wi, wo in ROUGH_PAIRS:
            r, i = value(bsdf, ctx, wi, wo), value(bsdf, importance, wi, wo)
            print(f'("{name}", {wi}, {wo}, {r}, {i}),')
    print("// roughdielectric α 1, η 1.5: 1 − mean importance-mode sample weight")
    rng = np.random.default_rng(1)
    for dist in ("ggx", "beckmann"):
        desc = {"type": "roughdielectric", "distribution": dist, "alpha": 1.0}
        bsdf = mi.load_dict(desc | {"int_ior": 1.5, "ext_ior": 1.0})
        for c in (1.0, 0.3, -1.0):
            si = mi.SurfaceInteraction3f()
            si.wi = direction(math.copysign(min(abs(c), 0.99999), c), 0.3)
            si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
            u = rng.random((20000, 3))
            w = [importance_sample(bsdf, importance, si, row) for row in u]
            print(dist, c, round(1 - float(np.mean(w)), 4))


if __name__ == "__main__":
    main()
