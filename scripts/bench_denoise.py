"""FLIP against a converged reference, with and without Intel Open Image Denoise.

For each method: the noisy render, the same render denoised (OIDN guided by gi's albedo
and normal AOVs), and a noisy render given about the same time as render + denoise
(more samples or photons), all scored with HDR-FLIP (flip-evaluator) against a `path`
reference. Writes a Markdown table.

    .venv/bin/python scripts/bench_denoise.py --out docs/bench/denoise.md
"""

from __future__ import annotations

import argparse
import platform
import time
from pathlib import Path

import flip_evaluator
import numpy as np

import gi
from gi.denoising import denoise_image


def flip(reference: np.ndarray, test: np.ndarray) -> float:
    """Mean HDR-FLIP (0 = identical), at FLIP's default 67 pixels per degree."""
    _, mean, _ = flip_evaluator.evaluate(
        np.ascontiguousarray(reference, np.float32),
        np.ascontiguousarray(np.maximum(test, 0.0), np.float32),
        "HDR",
        applyMagma=False,
    )
    return float(mean)


def timed_render(scene, method: str, **settings) -> tuple[gi.RenderResult, float]:
    t = time.perf_counter()
    r = gi.render(scene, method, **settings)
    return r, time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--size", default="96x96")
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--adapter", default="cpu")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    scene = gi.load_scene(args.scene)
    t = time.perf_counter()
    ref = gi.render(scene, "path", spp=args.ref_spp, size=(w, h), seed=1234).radiance
    ref_seconds = time.perf_counter() - t

    # (method, settings label, settings, key scaled for the equal-time run)
    cases = [
        ("path", "16 spp", {"spp": 16}, "spp"),
        ("ispm", "defaults (64 spp, 200k photons)", {}, "photons"),
        ("gather", "defaults (64 spp, 200k photons)", {}, "photons"),
    ]
    defaults = {"spp": 64, "photons": 200_000}
    rows = []
    for method, label, settings, scaled in cases:
        common = {"size": (w, h), "seed": 1, "adapter": args.adapter, **settings}
        noisy, seconds = timed_render(scene, method, **common)
        t = time.perf_counter()
        clean_aux = denoise_image(noisy.radiance, noisy.albedo, noisy.normal)
        denoise_seconds = time.perf_counter() - t
        clean = denoise_image(noisy.radiance, noisy.albedo, noisy.normal, clean_aux=False)
        # Equal time: scale the method's main budget by (render + denoise) / render.
        base = settings.get(scaled, defaults[scaled])
        more = max(base + 1, round(base * (seconds + denoise_seconds) / seconds))
        equal, equal_seconds = timed_render(scene, method, **{**common, scaled: more})
        rows.append(
            (
                method,
                label,
                seconds,
                denoise_seconds,
                flip(ref, noisy.radiance),
                flip(ref, clean),
                flip(ref, clean_aux),
                f"{scaled}={more}",
                equal_seconds,
                flip(ref, equal.radiance),
            )
        )
        print(rows[-1], flush=True)

    lines = [
        "# Denoising: FLIP against the reference, with and without OIDN",
        "",
        f"Scene `{args.scene}`, {w}x{h}, adapter `{args.adapter}`; reference: `path` at"
        f" {args.ref_spp} spp ({ref_seconds:.0f} s). HDR-FLIP (flip-evaluator, 67 ppd; lower is"
        " better). Denoised: Intel Open Image Denoise (pyoidn), filter RT, hdr, quality high,"
        " guided by gi's albedo and normal AOVs; *clean aux* (gi's default) tells OIDN the"
        " pixel-centre AOVs are noise-free, *prefiltered aux* lets OIDN clean them first."
        " Equal time: the same method with its budget scaled by (render + denoise) / render.",
        "",
        f"Machine: {platform.processor() or platform.machine()}, gi {gi.__version__}.",
        "",
        "| method | settings | render s | denoise s | FLIP noisy | FLIP denoised"
        " (prefiltered aux) | FLIP denoised (clean aux) | equal-time noisy | its s |"
        " FLIP equal-time noisy |",
        "|---|---|---:|---:|---:|---:|---:|---|---:|---:|",
    ]
    for m, label, s, d, fn, fd, fc, eq, es, fe in rows:
        lines.append(
            f"| {m} | {label} | {s:.2f} | {d:.3f} | {fn:.4f} | {fd:.4f} | {fc:.4f} | {eq} |"
            f" {es:.2f} | {fe:.4f} |"
        )
    lines += [
        "",
        "Command: `.venv/bin/python scripts/bench_denoise.py --out docs/bench/denoise.md`",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
