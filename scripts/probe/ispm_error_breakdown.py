"""What ispm's error against the `path` reference is made of (docs/bench/denoise.md).

Renders cornell at 96x96: two `path` references (4096 spp, full and direct-only) and
`ispm` at its defaults with 8 seeds; splits the per-pixel squared error of ispm's indirect
AOV into seed variance and bias² (minus the reference's own noise), says where the bias
lies (a ±2 px band around normal/depth edges) and at what scale the seed variance is
correlated, and scores filters with FLIP: OIDN on the beauty, OIDN on the albedo-demodulated
indirect (full resolution and downsampled 2x/4x), and a joint bilateral filter of the
demodulated indirect (normal and position guided) as a non-learned comparison.

With ``--variants`` it also splits the indirect error of ispm with other settings
(no subsampling, no boundary compensation, 4x the photons, half-size photon volumes), to see
which of them moves the bias.

Usage: .venv/bin/python scripts/probe/ispm_error_breakdown.py [--variants]
"""

from __future__ import annotations

import sys

import flip_evaluator
import numpy as np

import gi
from gi.denoising import denoise_image

SIZE = (96, 96)
SEEDS = range(1, 9)


def flip(ref: np.ndarray, img: np.ndarray) -> float:
    img = np.ascontiguousarray(np.maximum(img, 0), np.float32)
    _, mean, _ = flip_evaluator.evaluate(np.ascontiguousarray(ref, np.float32), img, "HDR")
    return float(mean)


def gaussian(a: np.ndarray, s: float) -> np.ndarray:
    r = int(3 * s) + 1
    x = np.arange(-r, r + 1)
    k = np.exp(-x * x / (2 * s * s))
    k /= k.sum()
    out = a.astype(np.float64)
    for ax in (0, 1):
        pad = [(0, 0)] * out.ndim
        pad[ax] = (r, r)
        p = np.pad(out, pad, mode="reflect")
        out = sum(
            k[i] * np.take(p, np.arange(i, i + out.shape[ax]), axis=ax) for i in range(2 * r + 1)
        )
    return out


def bilateral(img, normal, pos, s=2.0, sn=0.1, sp=0.2):
    r = int(2 * s) + 1
    h, w = img.shape[:2]
    acc, wsum = np.zeros_like(img), np.zeros((h, w, 1))

    def pad(x):
        return np.pad(x, ((r, r), (r, r), (0, 0)), mode="edge")

    pi, pn, pp = pad(img), pad(normal), pad(pos)
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            sl = (slice(r + dy, r + dy + h), slice(r + dx, r + dx + w))
            wt = np.exp(
                -(dx * dx + dy * dy) / (2 * s * s)
                - ((pn[sl] - normal) ** 2).sum(-1, keepdims=True) / (2 * sn * sn)
                - ((pp[sl] - pos) ** 2).sum(-1, keepdims=True) / (2 * sp * sp)
            )
            acc += wt * pi[sl]
            wsum += wt
    return acc / wsum


def down(x, f):
    h, w = x.shape[:2]
    return x.reshape(h // f, f, w // f, f, -1).mean((1, 3))


def up(x, f):
    return np.repeat(np.repeat(x, f, 0), f, 1)


def main() -> None:
    scene = gi.load_scene("cornell")
    refs = [gi.render(scene, "path", spp=4096, size=SIZE, seed=s).radiance for s in (1000, 3000)]
    direct_refs = [
        gi.render(scene, "path", spp=4096, size=SIZE, seed=s, max_depth=1) for s in (2000, 4000)
    ]
    ref = (refs[0] + refs[1]) / 2
    ref_direct = (direct_refs[0].radiance + direct_refs[1].radiance) / 2
    ref_indirect = ref - ref_direct
    ref_noise = float(((refs[0] - refs[1]) ** 2).mean() / 4)  # variance of the mean of two
    print(f"reference: FLIP between the two 4096-spp renders {flip(refs[0], refs[1]):.4f}")

    runs = [gi.render(scene, "ispm", size=SIZE, seed=s, adapter="cpu") for s in SEEDS]
    n = len(runs)
    ind = np.stack([r.aov("indirect") for r in runs])
    direct = np.stack([r.aov("direct") + r.aov("specular") for r in runs])
    noisy = [flip(ref, r.radiance) for r in runs]
    print(f"ispm FLIP per seed: mean {np.mean(noisy):.4f} ({min(noisy):.4f}..{max(noisy):.4f})")
    with_ref_indirect = np.mean([flip(ref, d + ref_indirect) for d in direct])
    print(f"  with the reference's indirect: {with_ref_indirect:.4f}")
    print(
        f"  with the reference's direct:   {np.mean([flip(ref, ref_direct + i) for i in ind]):.4f}"
    )
    print(
        f"  mean image of the {n} seeds:    {flip(ref, np.mean([r.radiance for r in runs], 0)):.4f}"
    )

    def split(ind: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Per-pixel MSE, seed variance and bias² (less the reference's noise) of `ind`."""
        mean = ind.mean(0)
        var = ind.var(0, ddof=1).mean(-1)
        mse = ((ind - ref_indirect) ** 2).mean(0).mean(-1)
        bias2 = np.maximum(((mean - ref_indirect) ** 2).mean(-1) - var / n - ref_noise, 0)
        return mean, var, mse, bias2

    mean, var, mse, bias2 = split(ind)
    normal, depth = direct_refs[0].normal, direct_refs[0].depth
    grad_n = sum(
        np.abs(np.diff(normal, axis=a, append=normal.take([-1], axis=a))).sum(-1) for a in (0, 1)
    )
    grad_d = sum(np.abs(np.diff(depth, axis=a, append=depth.take([-1], axis=a))) for a in (0, 1))
    band = (grad_n > 0.1) | (grad_d > 0.05 * depth.max())
    for _ in range(2):
        b = band.copy()
        b[1:] |= band[:-1]
        b[:-1] |= band[1:]
        b[:, 1:] |= band[:, :-1]
        b[:, :-1] |= band[:, 1:]
        band = b
    print(
        f"indirect per-pixel MSE {mse.mean():.6f} = seed variance {var.mean():.6f} "
        f"({var.mean() / mse.mean():.0%}) + bias² {bias2.mean():.6f} "
        f"({bias2.mean() / mse.mean():.0%}) "
        f"+ reference noise {ref_noise:.6f}"
    )
    print(
        f"bias² inside the ±2 px edge band ({band.mean():.0%} of the pixels): "
        f"{bias2[band].sum() / bias2.sum():.0%}"
    )
    dev = ind - mean
    kept = [
        float((np.stack([gaussian(d, s) for d in dev]) ** 2).mean() / (dev**2).mean())
        for s in (1, 2, 4)
    ]
    print(
        "seed-deviation energy kept by a Gaussian of sigma 1/2/4 px: "
        f"{kept[0]:.2f}/{kept[1]:.2f}/{kept[2]:.2f} (white noise: 0.08/0.02/0.005)"
    )

    rows: dict[str, list[float]] = {}
    for r in runs[:4]:
        d = r.aov("direct") + r.aov("specular")
        alb = np.maximum(r.albedo, 1e-3)
        dem = r.aov("indirect") / alb
        ones = np.ones_like(alb)
        rows.setdefault("OIDN on the beauty (gi.denoise)", []).append(
            flip(ref, denoise_image(r.radiance, r.albedo, r.normal))
        )
        rows.setdefault("OIDN on the demodulated indirect", []).append(
            flip(ref, d + denoise_image(dem, ones, r.normal) * alb)
        )
        for f in (2, 4):
            lo = denoise_image(down(dem, f), down(ones, f), down(r.normal, f))
            rows.setdefault(f"OIDN on the demodulated indirect at 1/{f} resolution", []).append(
                flip(ref, d + (dem - up(down(dem, f), f) + up(lo, f)) * alb)
            )
        rows.setdefault(
            "joint bilateral (2 px, normal 0.1, position 0.2 m) on the demodulated indirect", []
        ).append(flip(ref, d + bilateral(dem, r.normal, r.position) * alb))
    if "--variants" in sys.argv:
        variants = {
            "subsample=1": {"subsample": 1},
            "boundary_compensation=False": {"boundary_compensation": False},
            "photons=800000": {"photons": 800_000},
            "kernel_scale=0.5": {"kernel_scale": 0.5},
        }
        for name, kw in variants.items():
            rs = [gi.render(scene, "ispm", size=SIZE, seed=s, adapter="cpu", **kw) for s in SEEDS]
            _, v, m, b = split(np.stack([r.aov("indirect") for r in rs]))
            f = np.mean([flip(ref, r.radiance) for r in rs])
            print(
                f"{name}: FLIP {f:.4f}; indirect MSE {m.mean():.6f} = variance {v.mean():.6f} "
                f"+ bias² {b.mean():.6f} ({b[band].sum() / b.sum():.0%} in the edge band)"
            )

    base = np.mean(noisy[:4])
    print(f"FLIP, seeds 1-4 (noisy {base:.4f}):")
    for k, v in rows.items():
        print(f"  {k}: {np.mean(v):.4f} ({np.mean(v) / base:.3f}x)")


if __name__ == "__main__":
    main()
