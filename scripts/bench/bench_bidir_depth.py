"""`bidir` at any depth (issue 29): its frame time and error at depths 3, 7 and 64.

Per scene, in one run on the same cores: `bidir` at `max_depth` 3 (two bounces), 7 and its
default (64), `ispm` and `path` at their defaults, each scored against a converged `path`
reference (default depth 64; cached as bench_progressive's): the image mean relative to the
reference's, HDR-FLIP and relMSE, and the frame's wall-clock seconds (the mean of --frames
frames of a warm renderer, seeds 1, 2, …; the error columns are those of the first frame).

    GI_REF_CACHE=/work/cache/refs .venv/bin/python scripts/bench/bench_bidir_depth.py \\
        --out docs/bench/bidir-depth.md

`--tag before --bidir-only` (run with an older build's interpreter) gives rows to set beside
a newer build's: `docs/bench/bidir-depth.md` has main's and issue 29's MIS change so.

`--terms` (issue 48) breaks the image down by path length instead: `bidir` and `path` each
limited to `max_depth` 1, 2, 3 and 7, the differences of successive depths taken as the
terms (direct light; one bounce; two bounces; bounces 3–6), `bidir` as the mean of --frames
frames (seeds 1, 2, …; ± the standard error over them), `path` at --ref-spp with one seed
for every depth (so that the terms share its first bounces). Scenes are built-in names, scene
files, or a Mitsuba file with `:sun` (its environment emitters dropped) or `:sky` (its
directional emitters dropped):

    .venv/bin/python scripts/bench/bench_bidir_depth.py --terms --size 64 --frames 16 \\
        --scenes docs/scenes/sun-sky/sun-sky.xml,docs/scenes/sun-sky/sun-sky.xml:sun,...
"""

from __future__ import annotations

import argparse
import re
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from bench.bench_progressive import reference  # noqa: E402
from shared import cpu_name, flip, relmse  # noqa: E402

RUNS = [
    ("bidir", "`bidir` max_depth 3", dict(max_depth=3)),
    ("bidir", "`bidir` max_depth 7", dict(max_depth=7)),
    ("bidir", "`bidir` defaults (max_depth 64)", {}),
    ("ispm", "`ispm` defaults", dict(adapter="cpu")),
    ("path", "`path` defaults", {}),
]


def timed(scene: gi.Scene, method: str, size, frames: int, settings: dict):
    """(first frame's radiance, mean seconds per frame, stats of the last) of a warm
    renderer."""
    r = gi.Renderer(scene, method, size=size, seed=1, **settings)
    first = r.render().radiance
    seconds = 0.0
    stats = None
    for seed in range(2, frames + 2):
        t = time.perf_counter()
        out = r.render(seed=seed)
        seconds += time.perf_counter() - t
        stats = out.stats
    return first, seconds / frames, stats


TERM_DEPTHS = [1, 2, 3, 7]
TERMS = ["direct (depth 1)", "one bounce", "two bounces", "bounces 3–6", "all (depth 7)"]


def load_variant(spec: str, tmp: Path) -> gi.Scene:
    """The scene of `spec`: a built-in name or a file, or `file.xml:sun` / `file.xml:sky`,
    a Mitsuba file without its environment or its directional emitters (written beside
    `tmp`, its relative file names made absolute)."""
    name, _, keep = spec.partition(":")
    if not keep:
        return gi.load_scene(name)
    src = Path(name).resolve()
    xml = re.sub(
        r'value="([^"/]+\.exr)"', lambda m: f'value="{src.parent / m[1]}"', src.read_text()
    )
    drop = {"sun": ("envmap", "constant"), "sky": ("directional",)}[keep]
    for kind in drop:
        xml = re.sub(rf'<emitter type="{kind}".*?</emitter>', "", xml, flags=re.S)
    out = tmp / f"{src.stem}-{keep}.xml"
    out.write_text(xml)
    return gi.load_scene(out)


def term_rows(scene: gi.Scene, size, frames: int, ref_spp: int) -> list[str]:
    """The rows of one scene's breakdown by path length (see the module's doc)."""
    path = [
        float(
            gi.render(scene, "path", size=size, spp=ref_spp, max_depth=d, seed=99).radiance.mean()
        )
        for d in TERM_DEPTHS
    ]
    bidir = np.array(
        [
            [
                float(gi.render(scene, "bidir", size=size, max_depth=d, seed=s).radiance.mean())
                for s in range(1, frames + 1)
            ]
            for d in TERM_DEPTHS
        ]
    )
    rows = []
    for k, label in enumerate(TERMS):
        if k == 0 or k == 4:
            d = 0 if k == 0 else 3
            p, b = path[d], bidir[d]
        else:
            p, b = path[k] - path[k - 1], bidir[k] - bidir[k - 1]
        se = b.std(ddof=1) / np.sqrt(frames)
        rows.append(
            f"| {label} | {p:.5f} | {b.mean():.5f} ± {se:.5f} | {b.mean() / p:.4f} |"
            f" {100 * (b.mean() - p) / path[3]:+.2f}% | {100 * b.std(ddof=1) / path[3]:.2f}% |"
        )
    return rows


def terms_main(a) -> None:
    """`--terms`: the breakdown by path length of each scene (markdown to stdout)."""
    size = (a.size, a.size * 3 // 4)
    print(
        f"Command: `.venv/bin/python scripts/bench/bench_bidir_depth.py --terms --scenes {a.scenes}"
        f" --size {a.size} --frames {a.frames} --ref-spp {a.ref_spp}` · {size[0]}×{size[1]} ·"
        f" `bidir` at its defaults but `max_depth`, the mean of {a.frames} frames (± standard"
        f" error) · `path` {a.ref_spp} spp · term = image mean(depth) − image mean(previous"
        " depth), mean of RGB · share: (bidir − path) of the term over `path`'s depth-7 mean ·"
        " frame sd: one frame's standard deviation of the term over `path`'s depth-7 mean.\n"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for spec in a.scenes.split(","):
            scene = load_variant(spec, Path(tmp))
            print(f"### {spec}\n")
            print("| term | path | bidir | bidir / path | share of the image | frame sd |")
            print("|---|---|---|---|---|---|")
            for row in term_rows(scene, size, a.frames, a.ref_spp):
                print(row, flush=True)
            print()


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenes", default="cornell,furnace")
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--ref-spp", type=int, default=4096)
    ap.add_argument("--frames", type=int, default=2)
    ap.add_argument("--out", type=Path)
    ap.add_argument("--tag", default="", help="appended to the `bidir` rows' labels")
    ap.add_argument("--bidir-only", action="store_true", help="no `ispm` and `path` rows")
    ap.add_argument("--terms", action="store_true", help="the breakdown by path length")
    a = ap.parse_args()
    if a.terms:
        terms_main(a)
        return
    size = (a.size, a.size)
    lines = [
        "# `bidir` at any depth (issue 29)",
        "",
        "Command: `GI_REF_CACHE=/work/cache/refs .venv/bin/python"
        " scripts/bench/bench_bidir_depth.py"
        f" --scenes {a.scenes} --size {a.size} --ref-spp {a.ref_spp} --frames {a.frames}`"
        f" · {a.size}×{a.size} · reference: `path` at {a.ref_spp} spp (max_depth 64) ·"
        f" wall-clock seconds per frame of a warm renderer (mean of {a.frames}) on"
        f" {cpu_name()}, 2 cores shared with other work, lavapipe for the GPU passes ·"
        " mean: the image mean over the reference's (mean of RGB) · FLIP and relMSE of the"
        " first frame.",
        "",
    ]
    for name in a.scenes.split(","):
        scene = gi.load_scene(name)
        ref, ref_s = reference(name, size, a.ref_spp, 7)
        lines += [
            f"## {name}",
            "",
            f"Reference: {ref_s:.0f} s.",
            "",
            "| method | frame (s) | mean / reference | FLIP | relMSE | light subpaths |",
            "|---|---|---|---|---|---|",
        ]
        for method, label, settings in RUNS:
            if a.bidir_only and method != "bidir":
                continue
            if method == "bidir" and a.tag:
                label = f"{label} ({a.tag})"
            img, seconds, stats = timed(scene, method, size, a.frames, settings)
            ratio = float(img.mean() / ref.mean())
            subpaths = stats.light_paths if method == "bidir" else "–"
            row = (
                f"| {label} | {seconds:.3f} | {ratio:.4f} | {flip(ref, img):.4f} |"
                f" {relmse(img, ref):.4f} | {subpaths} |"
            )
            print(name, row, flush=True)
            lines.append(row)
        lines.append("")
    text = "\n".join(lines)
    if a.out:
        a.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
