"""Light through glass per method and source kind (issue 44 item 4).

The scenes of `tests/glass_scenes.py` (a glass slab over a floor under a point light or an
area light; a glazed window under a point light, an area light, the sun or the sky outside).
Per scene, `path` at --ref-spp (seed 7) is the reference; `ispm`, `bidir` and `direct`
render one frame each at seeds 1..--seeds, at their defaults. Columns: `path`'s mean over the
region lit only through the glass (`behind`) and over the frame, and its depth-1 part's
share of the region (`path@1`: direct light alone, which glass stops); then per method the
region's mean over `path`'s, and the frame's over `path`'s at the same `max_depth`
(`direct`'s over `path` at depth 1, its own light: `nan` where all light comes through the
glass); the mean over the seeds, then min–max.

    .venv/bin/python scripts/bench/glass_sources.py --out docs/bench/glass-sources.md

`--depth N` renders every method and `path` at `max_depth` N instead of the defaults (64);
`--methods bidir` renders that method alone (with `path`).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/
from shared import ROOT, cpu_name  # noqa: E402

sys.path.insert(0, str(ROOT / "tests"))
import glass_scenes  # noqa: E402

METHODS = ("ispm", "bidir", "direct")


def mean(x: np.ndarray, mask: np.ndarray | None = None) -> float:
    x = x.radiance[..., :3].mean(-1)
    return float(x.mean() if mask is None else x[mask].mean())


def cell(values: list[float]) -> str:
    v = np.array(values)
    return f"{v.mean():.3f} ({v.min():.3f}–{v.max():.3f})"


def row(kind: str, args) -> list[str]:
    scene = glass_scenes.scene(kind, args.width, args.height)
    depth = {"max_depth": args.depth} if args.depth else {}
    ref = gi.render(scene, "path", spp=args.ref_spp, seed=7, **depth)
    region = glass_scenes.behind(kind, ref)
    ref1 = gi.render(scene, "path", spp=args.ref_spp // 4, seed=7, max_depth=1)
    full, at1 = mean(ref, region), mean(ref1, region) / mean(ref, region)
    cells = [kind, f"{full:.4f}", f"{mean(ref):.4f}", f"{at1:.3f}"]
    for method in args.methods.split(","):
        kw = {} if method == "direct" else depth
        frames = [gi.render(scene, method, seed=s, **kw) for s in range(1, args.seeds + 1)]
        below = [mean(f, region) / full for f in frames]
        # `direct` renders `path`'s depth 1 (zero where all light comes through the glass).
        r = ref1 if method == "direct" else ref
        whole = [mean(f) / mean(r) if mean(r) > 0 else float("nan") for f in frames]
        cells += [cell(below), cell(whole)]
        print(kind, method, below, whole, flush=True)
    return cells


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kinds", default=",".join(glass_scenes.KINDS))
    ap.add_argument("--width", type=int, default=160)
    ap.add_argument("--height", type=int, default=120)
    ap.add_argument("--ref-spp", type=int, default=1024)
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--depth", type=int, default=0, help="max_depth (0: defaults)")
    ap.add_argument("--methods", default=",".join(METHODS), help="e.g. bidir")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    start = time.time()
    head = ["scene", "path behind", "path frame", "path@1 behind"]
    for m in args.methods.split(","):
        head += [f"{m} behind", f"{m} frame"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for kind in args.kinds.split(","):
        lines.append("| " + " | ".join(row(kind, args)) + " |")
    depth = args.depth or "default (64)"
    text = (
        f"{args.width}×{args.height}, `path` {args.ref_spp} spp, seeds 1–{args.seeds}, "
        f"max_depth {depth}; {cpu_name()}, {time.time() - start:.0f} s.\n\n" + "\n".join(lines)
    )
    print(text)
    if args.out:
        args.out.write_text(text + "\n")


if __name__ == "__main__":
    main()
