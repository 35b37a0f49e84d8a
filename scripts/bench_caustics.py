"""Caustic kernels before and after the local-density bound (issue 11), against `path`.

Per scene (cornell-glass, caustic-ring, mirror-shadow) and method (ispm, gather): renders
with `caustic_density_bound` off (before) and on (after), each over --seeds seeds, scored
against a `path` reference (cached in target/; a second reference of another seed gives its
own noise): the firefly share (pixels whose error is over 4x the local median error, see
`fireflies`), HDR-FLIP and relMSE, and the image mean relative to the reference's.

    .venv/bin/python scripts/bench_caustics.py --out docs/bench/caustics.md
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).parent))
from bench_progressive import cpu_name, flip, reference, relmse  # noqa: E402

SETTINGS = {
    "ispm": dict(photons=200_000, adapter="cpu"),
    "gather": dict(photons=200_000, spp=4),
}
# (label, settings): before (no bound, no focusing), the density bound, and for gather the
# bound with half the photons focused (the default share, 0.25, is chosen in bench_focus.py).
VARIANTS = {
    "ispm": [("before", dict(caustic_density_bound=False)), ("bound", {})],
    "gather": [
        ("before", dict(caustic_density_bound=False, photon_focus=0.0)),
        ("bound", dict(photon_focus=0.0)),
        ("bound + focus 0.5", dict(photon_focus=0.5)),
    ],
}


def fireflies(x: np.ndarray, ref: np.ndarray, window: int = 9, factor: float = 4.0) -> float:
    """Share of pixels whose error (mean absolute RGB difference from the reference) is over
    `factor` times the median error of the `window`² pixels around it. Errors below 1% of
    the reference's mean count as none (black areas, where the median is zero)."""
    e = np.abs(x - ref).mean(axis=2)
    floor = 0.01 * float(ref.mean())
    pad = window // 2
    padded = np.pad(e, pad, mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(padded, (window, window))
    median = np.median(windows, axis=(2, 3))
    return float(np.mean((e > factor * median) & (e > floor)))


def dots(x: np.ndarray, window: int = 9, factor: float = 4.0) -> float:
    """Reference-free: share of pixels whose luminance is over `factor` times the median of
    the `window`² pixels around them (isolated bright dots), ignoring pixels under 1% of
    the image mean. The reference's own share is the floor (sharp caustic features)."""
    y = x.mean(axis=2)
    floor = 0.01 * float(y.mean())
    pad = window // 2
    windows = np.lib.stride_tricks.sliding_window_view(
        np.pad(y, pad, mode="edge"), (window, window)
    )
    median = np.median(windows, axis=(2, 3))
    return float(np.mean((y > factor * median) & (y > floor)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default="cornell-glass,caustic-ring,mirror-shadow")
    ap.add_argument("--size", default="48x48")
    ap.add_argument("--ref-spp", type=int, default=1024, help="camera samples per reference part")
    ap.add_argument(
        "--ref-light-paths", type=int, default=64_000_000, help="light paths per reference part"
    )
    ap.add_argument(
        "--ref-parts",
        default="cornell-glass=8,caustic-ring=4,mirror-shadow=24",
        help="parts per reference, per scene (its light-traced caustics set its noise)",
    )
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    size = (w, h)
    lines = [
        "# Caustic kernels: the local-density bound, before and after",
        "",
        "Made by `.venv/bin/python scripts/bench_caustics.py --out docs/bench/caustics.md`"
        f" ({args.size}; reference: `path`, the mean of parts of {args.ref_spp} spp and"
        f" {args.ref_light_paths:.3g} light paths each, parts per scene {args.ref_parts};"
        f" means over {args.seeds} seeds)"
        f" on {cpu_name()}, {os.cpu_count()} logical CPUs, lavapipe for `ispm`."
        f" Settings: {SETTINGS}."
        " *fireflies*: share of pixels whose error is over 4x the median error of the 9x9"
        " pixels around them (the reference's own noise sets its floor); *dots*: the same"
        " without the reference, pixels over 4x the median of their 9x9 neighbourhood;"
        " *mean*: image mean / reference mean. The reference row is a"
        " second `path` reference of another seed against the first (its own noise).",
        "",
        "| scene | method | kernels | fireflies | dots | FLIP | relMSE | mean |",
        "|---|---|---|---:|---:|---:|---:|---:|",
    ]
    for name in args.scenes.split(","):
        scene = gi.load_scene(name)
        parts = dict(kv.split("=") for kv in args.ref_parts.split(","))
        recipe = (args.ref_spp, args.ref_light_paths, int(parts.get(name, 8)))
        ref, _ = reference(name, size, recipe[0], 1234, recipe[1], recipe[2])
        ref2, _ = reference(name, size, recipe[0], 4321, recipe[1], recipe[2])
        lines.append(
            f"| {name} | path (2nd reference) | | {fireflies(ref2, ref):.4f} | {dots(ref2):.4f}"
            f" | {flip(ref, ref2):.4f}"
            f" | {relmse(ref2, ref):.2e} | {ref2.mean() / ref.mean():.3f} |"
        )
        for method, settings in SETTINGS.items():
            for label, variant in VARIANTS[method]:
                scores = []
                for seed in range(args.seeds):
                    img = gi.render(
                        scene,
                        method,
                        size=size,
                        seed=seed,
                        **settings,
                        **variant,
                    ).radiance
                    scores.append(
                        (
                            fireflies(img, ref),
                            dots(img),
                            flip(ref, img),
                            relmse(img, ref),
                            img.mean() / ref.mean(),
                        )
                    )
                f, d, fl, rm, mean = np.mean(scores, axis=0)
                lines.append(
                    f"| {name} | {method} | {label} | {f:.4f} | {d:.4f} | {fl:.4f}"
                    f" | {rm:.2e} | {mean:.3f} |"
                )
                print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    if args.out:
        args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
