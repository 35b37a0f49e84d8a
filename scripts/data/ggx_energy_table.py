"""The directional albedo E(α, μ) of gi's GGX lobe with F = 1 (height-correlated Smith G2,
`gpu/shaders/common/bsdf.wgsl`), as the WGSL table `GGX_ENERGY` of `bidir.wgsl`: the
roughness clamp there (Tokuyoshi & Ogaki §5) scales the widened lobe by E(α, μ)/E(α', μ)
so that it keeps the albedo of the lobe it replaces.

Rows: roughness r = √α at i/(N−1), i = 0…N−1; columns: μ = cos θo at (j + 0.5)/N.
Integrated with half vectors drawn ∝ D·cos θh on a stratified grid. Run:
`python3 scripts/data/ggx_energy_table.py` and paste its output into bidir.wgsl.
"""

import numpy as np

N = 16


def lam(c, a):
    t2 = np.maximum(1 - c * c, 0) / np.maximum(c * c, 1e-12)
    return 0.5 * (np.sqrt(1 + a * a * t2) - 1)


def reflect(cos_h, u2, mu):
    """Half vectors of cosines `cos_h` and azimuths 2π·`u2`: ωo·h, cos θi of the reflected
    direction, and where it lies above the surface (with ωo·h > 0)."""
    sin_h = np.sqrt(np.maximum(1 - cos_h * cos_h, 0))
    phi = 2 * np.pi * u2
    h = np.stack([sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h], -1)
    wo = np.array([np.sqrt(1 - mu * mu), 0, mu])
    oh = h @ wo
    wi = 2 * oh[..., None] * h - wo
    ci = wi[..., 2]
    return oh, ci, (ci > 0) & (oh > 0)


def energy(alpha: float, mu: float, n=384) -> float:
    """E = ∫ f·cos θi dωi with the half vectors drawn ∝ D·cos θh on an n×n stratified grid:
    each sample weighs G2·(ωo·h)/(μ·cos θh) where ωi lies above the surface."""
    if alpha < 1e-3:
        return 1.0
    u = (np.arange(n) + 0.5) / n
    u1, u2 = np.meshgrid(u, u, indexing="ij")
    a2 = alpha * alpha
    cos_h = np.sqrt((1 - u1) / (1 + (a2 - 1) * u1))
    oh, ci, ok = reflect(cos_h, u2, mu)
    g2 = 1 / (1 + lam(mu, alpha) + lam(np.where(ok, ci, 1.0), alpha))
    w = np.where(ok, g2 * oh / (mu * cos_h), 0.0)
    return float(w.mean())


def table() -> np.ndarray:
    rs = np.arange(N) / (N - 1)
    mus = (np.arange(N) + 0.5) / N
    return np.array([[energy(r * r, m) for m in mus] for r in rs])


if __name__ == "__main__":
    t = table()
    rows = ",\n".join("    " + ", ".join(f"{v:.4f}" for v in row) for row in t)
    print(f"var<private> GGX_ENERGY: array<f32, {N * N}> = array<f32, {N * N}>(\n{rows}\n);")
