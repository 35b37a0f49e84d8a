"""Caustic kernels and photon focusing (issue 11), before and after, against `path`.

Per scene (cornell-glass, caustic-ring, mirror-shadow) and method (ispm, gather): renders
before (no `caustic_density_bound`, no `photon_focus`), with the bound alone, with the
defaults (the bound and photon_focus 0.25), with the bound and photon_focus 0.5 (and
`ispm`'s defaults at subsample 1), each over --seeds seeds, scored against a `path`
reference (cached in --ref-cache, else $GI_REF_CACHE, else target/; a second reference of
another seed gives its own noise): the firefly share (pixels whose error is over 4x the
local median error, see `fireflies`), HDR-FLIP and relMSE, and the image mean relative to
the reference's. `path` cannot render a point light's caustic seen in a mirror or through
glass (light, specular, diffuse, specular, camera), which photon mapping renders, so FLIP,
relMSE and the mean are also given "off mirrors": with the pixels that show something in a
mirror or glass (where `ispm`'s `specular` image is not black) set to the reference's.

    GI_REF_CACHE=/work/cache/refs .venv/bin/python scripts/bench/bench_caustics.py \\
        --out docs/bench/caustics.md
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from bench.bench_progressive import reference  # noqa: E402
from shared import cpu_name, flip, relmse  # noqa: E402

SETTINGS = {
    "ispm": dict(photons=200_000, adapter="cpu"),
    "gather": dict(photons=200_000, spp=4),
}
# (label, settings): before (no bound, no focusing), the density bound alone, the defaults
# (the bound and photon_focus 0.25) and the bound with photon_focus 0.5; the same for both.
VARIANT_LIST = [
    ("before", dict(caustic_density_bound=False, photon_focus=0.0)),
    ("bound", dict(photon_focus=0.0)),
    ("bound + focus 0.25 (defaults)", {}),
    ("bound + focus 0.5", dict(photon_focus=0.5)),
]
# ispm also at full resolution (subsample 1): its default half-resolution splat is upsampled
# by a joint bilateral filter, which the bound and focusing do not touch.
VARIANTS = {
    "ispm": [*VARIANT_LIST, ("defaults, subsample 1", dict(subsample=1))],
    "gather": VARIANT_LIST,
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


def specular_mask(scene, size: tuple[int, int]) -> np.ndarray:
    """Pixels whose camera ray meets a mirror or glass first: where `ispm`'s `specular`
    image (the CPU paths through mirrors and glass) is not black."""
    r = gi.render(scene, "ispm", size=size, seed=0, adapter="cpu", photons=20_000)
    return r.extra["specular"].max(axis=-1) > 0


def off_mirrors(x: np.ndarray, ref: np.ndarray, mask: np.ndarray) -> np.ndarray:
    """`x` with the pixels of `mask` replaced by the reference's."""
    y = x.copy()
    y[mask] = ref[mask]
    return y


def scores(img: np.ndarray, ref: np.ndarray, mask: np.ndarray) -> tuple:
    off = off_mirrors(img, ref, mask)
    return (
        fireflies(img, ref),
        dots(img),
        flip(ref, img),
        relmse(img, ref),
        img.mean() / ref.mean(),
        flip(ref, off),
        relmse(off, ref),
        off.mean() / ref.mean(),
    )


def row(name: str, method: str, label: str, s) -> str:
    f, d, fl, rm, mean, fl_off, rm_off, mean_off = s
    return (
        f"| {name} | {method} | {label} | {f:.4f} | {d:.4f} | {fl:.4f} | {rm:.2e} | {mean:.3f}"
        f" | {fl_off:.4f} | {rm_off:.2e} | {mean_off:.3f} |"
    )


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
    ap.add_argument(
        "--ref-cache",
        type=Path,
        help="directory of the cached references (default: $GI_REF_CACHE, else target/)",
    )
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument(
        "--out",
        type=Path,
        help="Markdown file to write; its sections after this table (## headings) are kept",
    )
    args = ap.parse_args()
    if args.ref_cache:
        os.environ["GI_REF_CACHE"] = str(args.ref_cache)
    w, h = (int(v) for v in args.size.split("x"))
    size = (w, h)
    lines = [
        "# Caustic kernels and photon focusing, before and after",
        "",
        f"Made by `GI_REF_CACHE={os.environ.get('GI_REF_CACHE', 'target')}"
        f" {' '.join(['.venv/bin/python', 'scripts/bench/bench_caustics.py', *sys.argv[1:]])}`"
        f" ({args.size}; reference: `path`, the mean of parts of {args.ref_spp} spp and"
        f" {args.ref_light_paths:.3g} light paths each, parts per scene {args.ref_parts};"
        f" means over {args.seeds} seeds)"
        f" on {cpu_name()}, {os.cpu_count()} logical CPUs, lavapipe for `ispm`."
        f" Settings: {SETTINGS}; kernels: *before* = no density bound and photon_focus 0,"
        " *bound* = the density bound and photon_focus 0, *defaults* = the bound and"
        " photon_focus 0.25."
        " *fireflies*: share of pixels whose error is over 4x the median error of the 9x9"
        " pixels around them (the reference's own noise sets its floor); *dots*: the same"
        " without the reference, pixels over 4x the median of their 9x9 neighbourhood;"
        " *mean*: image mean / reference mean; *off mirrors*: FLIP, relMSE and mean with the pixels"
        " that show something in a mirror or glass set to the reference's (`path`"
        " misses the caustics seen there). The reference row is a"
        " second `path` reference of another seed against the first (its own noise).",
        "",
        "| scene | method | kernels | fireflies | dots | FLIP | relMSE | mean"
        " | FLIP off mirrors | relMSE off mirrors | mean off mirrors |",
        "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for name in args.scenes.split(","):
        scene = gi.load_scene(name)
        parts = dict(kv.split("=") for kv in args.ref_parts.split(","))
        recipe = (args.ref_spp, args.ref_light_paths, int(parts.get(name, 8)))
        ref, _ = reference(name, size, recipe[0], 1234, recipe[1], recipe[2])
        ref2, _ = reference(name, size, recipe[0], 4321, recipe[1], recipe[2])
        mask = specular_mask(scene, size)
        lines.append(row(name, "path (2nd reference)", "", scores(ref2, ref, mask)))
        print(lines[-1], f"(mirror and glass pixels: {mask.mean():.1%})", flush=True)
        for method, settings in SETTINGS.items():
            for label, variant in VARIANTS[method]:
                runs = [
                    scores(
                        gi.render(
                            scene, method, size=size, seed=seed, **settings, **variant
                        ).radiance,
                        ref,
                        mask,
                    )
                    for seed in range(args.seeds)
                ]
                lines.append(row(name, method, label, np.mean(runs, axis=0)))
                print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    if args.out:
        kept = ""
        if args.out.exists():
            old = args.out.read_text()
            at = old.find("\n## ")
            kept = old[at:] if at >= 0 else ""
        args.out.write_text(text + kept)
    print(text)


if __name__ == "__main__":
    main()
