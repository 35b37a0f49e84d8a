"""FLIP against a converged reference, with and without Intel Open Image Denoise.

For each method: the noisy render, the same render denoised (OIDN guided by gi's albedo
and normal AOVs), and a noisy render given about the same time as render + denoise
(more samples or photons), all scored with HDR-FLIP (flip-evaluator) against a `path`
reference. Writes a Markdown table.

    .venv/bin/python scripts/bench/bench_denoise.py --out docs/bench/denoise.md
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

import gi
from gi.denoising import denoise_image

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared
from shared import cpu_name, flip  # noqa: E402


def timed_render(scene, method: str, **settings) -> tuple[gi.RenderResult, float]:
    t = time.perf_counter()
    r = gi.render(scene, method, **settings)
    return r, time.perf_counter() - t


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--size", default="96x96")
    ap.add_argument("--ref-spp", type=int, default=16384)
    ap.add_argument("--adapter", default="cpu")
    ap.add_argument("--seeds", type=int, default=3, help="renders averaged per row")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    scene = gi.load_scene(args.scene)
    # The reference takes minutes: kept in target/ (a build directory) for the next run.
    cache = Path("target") / f"bench-denoise-ref-{args.scene}-{w}x{h}-{args.ref_spp}.npz"
    if cache.exists():
        saved = np.load(cache)
        ref, ref_seconds = saved["radiance"], float(saved["seconds"])
    else:
        t = time.perf_counter()
        ref = gi.render(scene, "path", spp=args.ref_spp, size=(w, h), seed=1234).radiance
        ref_seconds = time.perf_counter() - t
        cache.parent.mkdir(exist_ok=True)
        np.savez(cache, radiance=ref, seconds=ref_seconds)

    # Untimed warm-ups: OIDN's device and filter set-up (reported), lavapipe's pipelines.
    warm = gi.render(scene, "path", spp=1, size=(w, h))
    t = time.perf_counter()
    denoise_image(warm.radiance, warm.albedo, warm.normal)
    oidn_init = time.perf_counter() - t
    gi.render(scene, "ispm", spp=1, size=(w, h), photons=1000, adapter=args.adapter)

    # (method, settings label, settings, key scaled for the equal-time run)
    cases = [
        ("path", "16 spp", {"spp": 16}, "spp"),
        ("ispm", "defaults (16 spp, 200k photons)", {}, "photons"),
        ("gather", "defaults (64 spp, 200k photons)", {}, "photons"),
    ]
    defaults = {"photons": 200_000}
    seeds = range(1, args.seeds + 1)
    rows = []
    for method, label, settings, scaled in cases:
        seconds, denoise_seconds, f_noisy, f_clean, f_pre = [], [], [], [], []
        for seed in seeds:
            common = {"size": (w, h), "seed": seed, "adapter": args.adapter, **settings}
            noisy, dt = timed_render(scene, method, **common)
            # gi.denoise: OIDN, after the photon-scale indirect filter for ispm.
            t = time.perf_counter()
            clean = gi.denoise(noisy).radiance
            denoise_seconds.append(time.perf_counter() - t)
            pre = denoise_image(noisy.radiance, noisy.albedo, noisy.normal, clean_aux=False)
            seconds.append(dt)
            f_noisy.append(flip(ref, noisy.radiance))
            f_clean.append(flip(ref, clean))
            f_pre.append(flip(ref, pre))
        # Equal time: scale the method's main budget by (render + denoise) / render.
        render_s, denoise_s = float(np.mean(seconds)), float(np.mean(denoise_seconds))
        base = settings[scaled] if scaled in settings else defaults[scaled]
        more = max(base + 1, round(base * (render_s + denoise_s) / render_s))
        equal_seconds, f_equal = [], []
        for seed in seeds:
            common = {"size": (w, h), "seed": seed, "adapter": args.adapter, **settings}
            equal, dt = timed_render(scene, method, **{**common, scaled: more})
            equal_seconds.append(dt)
            f_equal.append(flip(ref, equal.radiance))
        rows.append(
            (
                method,
                label,
                render_s,
                denoise_s,
                float(np.mean(f_noisy)),
                float(np.mean(f_pre)),
                float(np.mean(f_clean)),
                f"{scaled}={more}",
                float(np.mean(equal_seconds)),
                float(np.mean(f_equal)),
            )
        )
        print(rows[-1], flush=True)

    lines = [
        "# Denoising: FLIP against the reference, with and without OIDN",
        "",
        f"Scene `{args.scene}`, {w}x{h}, adapter `{args.adapter}`; reference: `path` at"
        f" {args.ref_spp} spp ({ref_seconds:.0f} s). HDR-FLIP (flip-evaluator, 67 ppd; lower is"
        " better). Denoised: `gi.denoise` = Intel Open Image Denoise (pyoidn), filter RT, hdr,"
        " quality high, guided by gi's albedo and normal AOVs, after (ispm only) the"
        " photon-scale filter of the indirect light (`gi.denoising.filter_indirect`);"
        " *clean aux* (gi's default) tells OIDN the pixel-centre AOVs are noise-free,"
        " *prefiltered aux* lets OIDN clean them first (OIDN alone, on the beauty)."
        " Equal time: the same method with its budget scaled by (render + denoise) / render."
        f" Each row is the mean over seeds 1-{args.seeds}; times after untimed warm-ups (OIDN's"
        f" first call in a process also sets up its device: {oidn_init:.2f} s here).",
        "",
        f"Machine: {cpu_name()}, {os.cpu_count()} cores (shared), gi {gi.__version__}.",
        "",
        "| method | settings | render s | denoise s | FLIP noisy | FLIP denoised"
        " (prefiltered aux) | FLIP denoised (clean aux) | equal-time noisy | its s |"
        " FLIP equal-time noisy | denoised / noisy | denoised / equal-time |",
        "|---|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|",
    ]
    for m, label, s, d, fn, fd, fc, eq, es, fe in rows:
        lines.append(
            f"| {m} | {label} | {s:.2f} | {d:.3f} | {fn:.4f} | {fd:.4f} | {fc:.4f} | {eq} |"
            f" {es:.2f} | {fe:.4f} | {fc / fn:.2f} | {fc / fe:.2f} |"
        )
    lines += [
        "",
        "Command: `.venv/bin/python scripts/bench/bench_denoise.py --out docs/bench/denoise.md`",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    if args.out:
        args.out.write_text(text)


if __name__ == "__main__":
    main()
