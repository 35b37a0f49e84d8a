"""Directional albedos of the glossy lobes of Mitsuba's models (GGX and Beckmann, Mitsuba's
separable Smith masking G1(ωo)·G1(ωi), `gpu/shaders/common/models.wgsl`) as the tables of
`raster/model_energy.rs` (a storage buffer of bidir's lighting pass, read by
`raster/shaders/bidir_models.wgsl`): bidir's roughness clamp (Tokuyoshi & Ogaki
§5) scales a model's widened lobe by E(α, μ)/E(α', μ) so that it keeps the albedo of the
lobe it replaces, Fresnel included.

E is tabulated split-sum style (Karis 2013) for a Schlick-shaped Fresnel term
F(c) = F0 + (1 − F0)·(1 − c)^5 at the half-vector cosine c = ωo·h:
E(α, μ; F0) = F0·A(α, μ) + B(α, μ), A = ∫ w·(1 − (1 − c)^5), B = ∫ w·(1 − c)^5, with
w = D·G·cos θi/(4μ·cos θi) the lobe's weight at F = 1. The lighting pass takes F0 from the
model's own Fresnel term at normal incidence (a conductor's complex-index reflectance, a
coating's dielectric one); the residual (a conductor's or dielectric's Fresnel curve is not
Schlick's) is measured by `--check` below.

Rows: roughness r = √α at i/(N−1), i = 0…N−1; columns: μ = cos θo at (j + 0.5)/N
(as `GGX_ENERGY` of roughness_clamp.wgsl). Integrated with half vectors drawn ∝ D·cos θh on
a stratified grid. Run: `python3 scripts/data/model_energy_tables.py` and paste its output
(`MODEL_ENERGY`: GGX's A, GGX's B, Beckmann's A, Beckmann's B, N rows each) into
model_energy.rs; `--check` prints the clamp factor's error for copper, gold, aluminium
(at their normal-incidence F0) and a dielectric coating of index 1.5.
"""

import sys

import numpy as np
from ggx_energy_table import reflect

N = 16


def lam(c, a, beckmann):
    t2 = np.maximum(1 - c * c, 0) / np.maximum(c * c, 1e-12)
    if not beckmann:
        return 0.5 * (np.sqrt(1 + a * a * t2) - 1)
    t = a * a * t2
    x = 1 / np.sqrt(np.maximum(t, 1e-30))
    g1 = (3.535 * x + 2.181 * x * x) / (1 + 2.276 * x + 2.577 * x * x)
    return np.where((t <= 0) | (x >= 1.6), 0.0, 1 / g1 - 1)


def weights(alpha, mu, beckmann, n=384):
    """The lobe's f·cos θi/pdf at F = 1 (separable masking) over an n×n stratified grid of
    half vectors drawn ∝ D·cos θh, and each sample's ωo·h."""
    u = (np.arange(n) + 0.5) / n
    u1, u2 = np.meshgrid(u, u, indexing="ij")
    a2 = alpha * alpha
    if beckmann:
        tan2 = -a2 * np.log(1 - u1)
        cos_h = 1 / np.sqrt(1 + tan2)
    else:
        cos_h = np.sqrt((1 - u1) / (1 + (a2 - 1) * u1))
    oh, ci, ok = reflect(cos_h, u2, mu)
    g = 1 / ((1 + lam(mu, alpha, beckmann)) * (1 + lam(np.where(ok, ci, 1.0), alpha, beckmann)))
    return np.where(ok, g * oh / (mu * cos_h), 0.0), np.clip(oh, 0, 1)


def split(alpha, mu, beckmann):
    """(A, B) of the split sum."""
    if alpha < 1e-3:
        s = (1 - mu) ** 5  # a mirror: E = F(μ)
        return 1.0 - s, s
    w, c = weights(alpha, mu, beckmann)
    s = (1 - c) ** 5
    return float((w * (1 - s)).mean()), float((w * s).mean())


def tables(beckmann):
    rs = np.arange(N) / (N - 1)
    mus = (np.arange(N) + 0.5) / N
    t = np.array([[split(r * r, m, beckmann) for m in mus] for r in rs])
    return t[..., 0], t[..., 1]


def rust(name, t):
    rows = "\n".join("    " + ", ".join(f"{v:.4f}" for v in row) + "," for row in t)
    return f"pub const {name}: [f32; {t.size}] = [\n{rows}\n];"


def fresnel_conductor(c, eta, k):
    c2 = c * c
    s2 = 1 - c2
    t1 = eta * eta - k * k - s2
    a2b2 = np.sqrt(t1 * t1 + 4 * k * k * eta * eta)
    a = np.sqrt(0.5 * (a2b2 + t1))
    rs = (a2b2 + c2 - 2 * c * a) / (a2b2 + c2 + 2 * c * a)
    rp = rs * (a2b2 * c2 + s2 * s2 - 2 * c * a * s2) / (a2b2 * c2 + s2 * s2 + 2 * c * a * s2)
    return 0.5 * (rs + rp)


def fresnel_dielectric(c, eta):
    s2 = (1 - c * c) / (eta * eta)
    ct = np.sqrt(np.maximum(1 - s2, 0))
    rs = (c - eta * ct) / (c + eta * ct)
    rp = (eta * c - ct) / (eta * c + ct)
    return np.where(s2 >= 1, 1.0, 0.5 * (rs * rs + rp * rp))


def check():
    """The clamp factor k = E(α)/E(α') with the split sum (at F0 = F(1)) and with F = 1,
    against the exact one, for a few clamps."""
    fresnels = {
        "Cu (R)": lambda c: fresnel_conductor(c, 0.27, 3.41),
        "Au (B)": lambda c: fresnel_conductor(c, 1.47, 1.95),
        "Al": lambda c: fresnel_conductor(c, 1.35, 7.47),
        "coat 1.5": lambda c: fresnel_dielectric(c, 1.5),
    }
    worst = {"split": 0.0, "F=1": 0.0}
    for beckmann in (False, True):
        for name, f in fresnels.items():
            f0 = float(f(np.array(1.0)))
            for a, a2 in [(0.04, 0.3), (0.1, 0.5), (0.2, 0.6), (0.3, 1.0)]:
                for mu in (0.2, 0.5, 0.9):
                    e = []
                    for al in (a, a2):
                        w, c = weights(al, mu, beckmann)
                        s = (1 - c) ** 5
                        e.append(
                            (
                                (w * f(c)).mean(),
                                f0 * (w * (1 - s)).mean() + (w * s).mean(),
                                w.mean(),
                            )
                        )
                    exact = e[0][0] / e[1][0]
                    ks = e[0][1] / e[1][1]
                    k1 = e[0][2] / e[1][2]
                    worst["split"] = max(worst["split"], abs(ks / exact - 1))
                    worst["F=1"] = max(worst["F=1"], abs(k1 / exact - 1))
                    print(
                        "beckmann" if beckmann else "ggx",
                        name,
                        a,
                        a2,
                        mu,
                        f"exact {exact:.4f} split {ks:.4f} F=1 {k1:.4f}",
                    )
    print("largest relative error of k:", worst)


if __name__ == "__main__":
    if "--check" in sys.argv:
        check()
    else:
        # One array: GGX's A, GGX's B, Beckmann's A, Beckmann's B.
        parts = [t for beckmann in (False, True) for t in tables(beckmann)]
        print(rust("MODEL_ENERGY", np.concatenate(parts)))
