"""Prints Mitsuba 3's BSDF values (scalar_rgb ``BSDF::eval``, cos θ of the outgoing
direction included) for the materials and direction pairs of
crates/core/src/bsdf/tests_models.rs::MITSUBA_EVALS, in that table's order.

Run: /work/main/.venv/bin/python scripts/data/mitsuba_bsdf_values.py  (pip install
mitsuba==3.9.1)."""

import math

import mitsuba as mi

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


def direction(c: float, phi: float) -> mi.Vector3f:
    s = math.sqrt(1 - c * c)
    return mi.Vector3f(s * math.cos(phi), s * math.sin(phi), c)


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


if __name__ == "__main__":
    main()
