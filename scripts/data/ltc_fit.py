#!/usr/bin/env python3
"""Fits the linearly transformed cosines (Heitz, Dupuy, Hill & Neubelt 2016) of the GPU
uber material's GGX lobe and writes the table ``crates/core/src/raster/ltc_ggx.json``; with
``--distribution beckmann``, of the Beckmann lobe of Mitsuba's exact models
(``ltc_beckmann.json``: separable Smith G1(wo)·G1(wi) with Walter et al.'s rational Λ, as
`models.wgsl` `mf_lambda` and Mitsuba's conductors evaluate it; D(h) = exp(−tan²θh/α²) /
(π·α²·cos⁴θh), normals drawn by tan²θh = −α²·ln(1 − u)).

The lobe fitted is f(wo, wi)·cos θi of GGX with α = roughness² and the height-correlated
Smith G2 = 1/(1 + Λo + Λi) (`bsdf/microfacet.rs`, the GPU's `bsdf_eval`), Fresnel = 1. For
each (roughness, θo) of a ``N``×``N`` grid (roughness linear from 0.05 to 1, θo linear
from 0 to 89°: ``grid``), with wo in the xz-plane, it finds the matrix

    M = [[a, 0, b], [0, c, 0], [d, 0, 1]]

whose transformed cosine D(w) = D_o(M⁻¹w/|M⁻¹w|)·|det M⁻¹|/|M⁻¹w|³ (D_o = cos/π) is closest
to f·cos/n, n = ∫ f·cos dω the lobe's albedo (also stored, and the Schlick moment
∫ f·cos·(1 − wi·h)⁵ dω, so that a Fresnel of reflectance F0 at normal incidence scales it by
F0·n + (1 − F0)·fresnel). Closest: the L³ error ∫ |D − f·cos/n|³ dω, estimated with
stratified samples of both the GGX lobe and the current fit (balance heuristic), minimized
by Nelder–Mead from the previous cell's fit (smooth to rough, normal to grazing), as the
paper describes. The table holds M⁻¹'s four non-trivial entries normalized by its middle
one (LTC is invariant under scaling of M), n and the Fresnel moment.

    python scripts/data/ltc_fit.py --size 32 --samples 32   # the committed table (~5 min CPU)
    python scripts/data/ltc_fit.py --size 32 --samples 32 --distribution beckmann

Written from the paper's description; no published table or code is used. Checked by
`tests/test_ltc_table.py` (the closed form against a numeric integral over square lights).
Evaluated by `crates/core/src/raster/ltc.rs` (CPU) and `shaders/common/ltc.wgsl` (GPU, the
table as `ltc_table.wgsl`: regenerate it after a refit with
`GI_WRITE_LTC_TABLE=1 cargo test -p gi-core --lib ltc`).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

RASTER = Path(__file__).resolve().parents[2] / "crates" / "core" / "src" / "raster"
MAX_THETA = np.radians(89.0)
MIN_ROUGHNESS = 0.05


def grid(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Roughness values (linear from MIN_ROUGHNESS to 1) and view angles θo (linear up to
    MAX_THETA)."""
    r = np.linspace(MIN_ROUGHNESS, 1.0, n)
    theta = np.linspace(0.0, MAX_THETA, n)
    return r, theta


def ggx_d(cos_h: np.ndarray, alpha: float) -> np.ndarray:
    c2 = cos_h * cos_h
    t = c2 * (alpha * alpha - 1.0) + 1.0
    return np.where(cos_h > 0, alpha * alpha / (np.pi * t * t), 0.0)


def ggx_lambda(cos_t: np.ndarray, alpha: float) -> np.ndarray:
    c2 = np.clip(cos_t * cos_t, 1e-12, 1.0)
    tan2 = (1.0 - c2) / c2
    return 0.5 * (np.sqrt(1.0 + alpha * alpha * tan2) - 1.0)


def beckmann_d(cos_h: np.ndarray, alpha: float) -> np.ndarray:
    c2 = np.maximum(cos_h * cos_h, 1e-12)
    tan2 = (1.0 - c2) / c2
    return np.where(cos_h > 0, np.exp(-tan2 / (alpha * alpha)) / (np.pi * alpha**2 * c2 * c2), 0.0)


def beckmann_lambda(cos_t: np.ndarray, alpha: float) -> np.ndarray:
    """Walter et al.'s rational approximation (`models.wgsl` `mf_lambda`)."""
    c2 = np.clip(cos_t * cos_t, 1e-12, 1.0)
    a = 1.0 / np.maximum(alpha * np.sqrt((1.0 - c2) / c2), 1e-12)
    g1 = (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a)
    return np.where(a >= 1.6, 0.0, 1.0 / np.maximum(g1, 1e-12) - 1.0)


# The distribution fitted (`main` sets it): its D, its masking G2(cos θo, cos θi) and
# tan²θh of a normal drawn from D·cos θh for a uniform u.
DIST = {
    "d": ggx_d,
    "g2": lambda co, ci, a: 1.0 / (1.0 + ggx_lambda(co, a) + ggx_lambda(ci, a)),
    "tan2": lambda u, a: a * a * u / np.maximum(1.0 - u, 1e-12),
    "about": "LTC fit of GGX (height-correlated Smith, Fresnel 1), scripts/data/ltc_fit.py",
}
BECKMANN = {
    "d": beckmann_d,
    "g2": lambda co, ci, a: 1.0 / ((1.0 + beckmann_lambda(co, a)) * (1.0 + beckmann_lambda(ci, a))),
    "tan2": lambda u, a: -a * a * np.log(np.maximum(1.0 - u, 1e-12)),
    "about": "LTC fit of Beckmann (separable Smith, Walter's rational Lambda, Fresnel 1), "
    "scripts/data/ltc_fit.py --distribution beckmann",
}


def lobe(wo: np.ndarray, wi: np.ndarray, alpha: float) -> tuple[np.ndarray, np.ndarray]:
    """f·cos θi (Fresnel 1) and the Schlick weight (1 − wi·h)⁵ for directions `wi` (k×3)."""
    h = wi + wo
    h = h / np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-12)
    ci = wi[:, 2]
    co = wo[2]
    g2 = DIST["g2"](np.array(co), ci, alpha)
    f = DIST["d"](h[:, 2], alpha) * g2 / (4.0 * co)
    f = np.where(ci > 0, f, 0.0)
    return f, (1.0 - np.clip((wi * h).sum(axis=1), 0.0, 1.0)) ** 5


def stratified(k: int) -> np.ndarray:
    """k² stratified points of [0, 1)² (fixed jitter, so the objective is deterministic)."""
    rng = np.random.default_rng(7)
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    return (np.stack([i.ravel(), j.ravel()], axis=1) + rng.random((k * k, 2))) / k


def sample_lobe(wo: np.ndarray, alpha: float, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Directions reflected about normals drawn from D(h)·cos θh, and their density."""
    tan2 = DIST["tan2"](u[:, 0], alpha)
    cos_h = 1.0 / np.sqrt(1.0 + tan2)
    sin_h = np.sqrt(np.maximum(1.0 - cos_h * cos_h, 0.0))
    phi = 2.0 * np.pi * u[:, 1]
    h = np.stack([sin_h * np.cos(phi), sin_h * np.sin(phi), cos_h], axis=1)
    d = (h * wo).sum(axis=1, keepdims=True)
    wi = 2.0 * d * h - wo
    pdf = DIST["d"](cos_h, alpha) * cos_h / (4.0 * np.abs(d[:, 0]))
    return wi, pdf


def matrix(p: np.ndarray) -> np.ndarray:
    a, b, c, d = p
    return np.array([[a, 0.0, b], [0.0, c, 0.0], [d, 0.0, 1.0]])


def ltc_eval(minv: np.ndarray, w: np.ndarray) -> np.ndarray:
    """The transformed cosine's density at unit directions `w` (k×3), M⁻¹ given."""
    v = w @ minv.T
    length = np.linalg.norm(v, axis=1)
    cos = np.maximum(v[:, 2] / length, 0.0)
    return cos / np.pi * abs(np.linalg.det(minv)) / length**3


def ltc_sample(m: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Cosine-distributed directions transformed by M (normalized)."""
    r = np.sqrt(u[:, 0])
    phi = 2.0 * np.pi * u[:, 1]
    wo = np.stack(
        [r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(1.0 - u[:, 0], 0.0))], axis=1
    )
    w = wo @ m.T
    return w / np.linalg.norm(w, axis=1, keepdims=True)


def moments(wo: np.ndarray, alpha: float, u: np.ndarray) -> tuple[float, float, np.ndarray]:
    """The lobe's albedo n, its Schlick moment and its mean direction (unit)."""
    wi, pdf = sample_lobe(wo, alpha, u)
    f, schlick = lobe(wo, wi, alpha)
    w = np.where(pdf > 0, f / np.maximum(pdf, 1e-30), 0.0)
    mean = (wi * w[:, None]).sum(axis=0)
    return float(w.mean()), float((w * schlick).mean()), mean / np.linalg.norm(mean)


def objective(p, wo, alpha, norm, u, lobe_samples) -> float:
    m = matrix(p)
    det = np.linalg.det(m)
    if not np.isfinite(det) or abs(det) < 1e-9:
        return 1e30
    minv = np.linalg.inv(m)
    wi_f, pdf_f = lobe_samples
    wi_m = ltc_sample(m, u)
    total = 0.0
    for wi in (wi_f, wi_m):
        target, _ = lobe(wo, wi, alpha)
        d = ltc_eval(minv, wi)
        pf = sample_lobe_pdf(wo, alpha, wi)
        denom = pf + d
        err = np.abs(d - target / norm) ** 3
        total += float(np.where(denom > 0, err / np.maximum(denom, 1e-30), 0.0).mean())
    return total


def sample_lobe_pdf(wo: np.ndarray, alpha: float, wi: np.ndarray) -> np.ndarray:
    """`sample_lobe`'s density of directions `wi`."""
    h = wi + wo
    h = h / np.maximum(np.linalg.norm(h, axis=1, keepdims=True), 1e-12)
    d = np.abs((h * wo).sum(axis=1))
    return np.where(
        h[:, 2] > 0, DIST["d"](h[:, 2], alpha) * h[:, 2] / (4.0 * np.maximum(d, 1e-12)), 0.0
    )


def nelder_mead(f, x0: np.ndarray, step: float, iters: int = 400) -> np.ndarray:
    """Plain Nelder–Mead (reflection 1, expansion 2, contraction ½, shrink ½)."""
    n = len(x0)
    pts = [x0] + [x0 + step * np.eye(n)[i] * max(abs(x0[i]), 1e-2) for i in range(n)]
    vals = [f(p) for p in pts]
    for _ in range(iters):
        order = np.argsort(vals)
        pts = [pts[i] for i in order]
        vals = [vals[i] for i in order]
        if abs(vals[-1] - vals[0]) <= 1e-10 * (abs(vals[0]) + 1e-30):
            break
        centroid = np.mean(pts[:-1], axis=0)
        xr = centroid + (centroid - pts[-1])
        fr = f(xr)
        if fr < vals[0]:
            xe = centroid + 2.0 * (centroid - pts[-1])
            fe = f(xe)
            pts[-1], vals[-1] = (xe, fe) if fe < fr else (xr, fr)
        elif fr < vals[-2]:
            pts[-1], vals[-1] = xr, fr
        else:
            xc = centroid + 0.5 * (pts[-1] - centroid)
            fc = f(xc)
            if fc < vals[-1]:
                pts[-1], vals[-1] = xc, fc
            else:
                pts = [pts[0]] + [pts[0] + 0.5 * (p - pts[0]) for p in pts[1:]]
                vals = [vals[0]] + [f(p) for p in pts[1:]]
    return pts[int(np.argmin(vals))]


def initial(alpha: float, mean: np.ndarray) -> np.ndarray:
    """A cosine narrowed to α about the lobe's mean direction (angle φ from the normal):
    R(φ)·diag(α, α, 1), scaled so that its last entry is 1."""
    phi = np.arctan2(mean[0], mean[2])
    c, s = np.cos(phi), np.sin(phi)
    return np.array([alpha, s / c, alpha / c, -alpha * s / c])


def fit(size: int, samples: int) -> dict:
    roughness, theta = grid(size)
    u = stratified(samples)
    table = {}
    for i in range(size - 1, -1, -1):
        alpha = float(roughness[i] ** 2)
        prev = None
        for j, t in enumerate(theta):
            wo = np.array([np.sin(t), 0.0, np.cos(t)])
            norm, fres, mean = moments(wo, alpha, u)
            lobe_samples = sample_lobe(wo, alpha, u)
            # From the best of the previous θ's fit, the rougher row's at this θ and a
            # cosine narrowed about the lobe's mean direction (one start alone left the
            # smoothest row's grazing cells in a poor local minimum).
            args = (wo, alpha, norm, u, lobe_samples)
            starts = [initial(alpha, mean)]
            starts += [prev] if prev is not None else []
            starts += [table[(i + 1, j)][0]] if i < size - 1 else []
            x0 = min(starts, key=lambda q, args=args: objective(q, *args))
            p = nelder_mead(lambda q, args=args: objective(q, *args), x0, 0.1)
            prev = p
            table[(i, j)] = (p, norm, fres)
    cells = []
    for i in range(size):
        for j in range(size):
            p, norm, fres = table[(i, j)]
            minv = np.linalg.inv(matrix(p))
            # Scaled so that its middle entry is 1 (by a positive factor: a negative one
            # would flip z; flipping y leaves the lobe, symmetric in y, as it is).
            minv = minv / abs(minv[1, 1])
            cells.append(
                {
                    "minv": [
                        float(minv[0, 0]),
                        float(minv[0, 2]),
                        float(minv[2, 0]),
                        float(minv[2, 2]),
                    ],
                    "norm": norm,
                    "fresnel": fres,
                }
            )
    return {
        "about": DIST["about"],
        "roughness": [float(r) for r in roughness],
        "theta": [float(t) for t in theta],
        "layout": "cells[i * size + j]: roughness i, theta j; minv = M^-1 entries "
        "[m00, m02, m20, m22] with m11 = 1 and the others 0",
        "cells": cells,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=32)
    ap.add_argument("--samples", type=int, default=32, help="stratified samples per axis")
    ap.add_argument("--distribution", choices=("ggx", "beckmann"), default="ggx")
    ap.add_argument("--out", type=Path, help="default: raster/ltc_<distribution>.json")
    a = ap.parse_args()
    if a.distribution == "beckmann":
        DIST.update(BECKMANN)
    a.out = a.out or RASTER / f"ltc_{a.distribution}.json"
    table = fit(a.size, a.samples)
    a.out.write_text(json.dumps(table, indent=None, separators=(",", ":")) + "\n")
    print(f"wrote {a.out} ({a.out.stat().st_size} bytes)")


if __name__ == "__main__":
    main()
