#!/usr/bin/env python3
"""Every method and every ``ispm`` estimator on the built-in scenes: rendered on one adapter
and compared with references rendered on another (lavapipe), by mean and FLIP.

``render`` writes the references (radiance as float16 ``.npz``, two seeds, so that the
difference between two seeds, the noise, is known); ``compare`` renders the first seed on the
current adapter (``GI_ADAPTER``) and writes, per image, the relative difference of the means
and HDR-FLIP against the reference, beside the same two numbers between the references' two
seeds. Used by ``scripts/ci/gpu_check.sh`` (part b); see docs/gpu-check.md.

    GI_ADAPTER=cpu scripts/ci/gpu_images.py render --out refs
    GI_ADAPTER=gpu scripts/ci/gpu_images.py compare --refs refs --out out/images

An image *agrees* when its values are finite, its mean is within ``max(0.5 %, 2 × the two
seeds' mean difference)`` of the reference's and its FLIP is at most ``max(the two seeds'
FLIP, 0.005)`` (``1.25 ×`` the seeds' FLIP where the adapters ran different passes: it is then
another draw, like another seed). ``compare`` exits 1 when an image differs or fails to render.
"""

from __future__ import annotations

import argparse
import fnmatch
import json
import sys
import time
import traceback
from collections.abc import Iterator
from pathlib import Path

import flip_evaluator
import numpy as np

import gi

SIZE = (128, 96)
SEEDS = (1, 2)
SCENES = [
    "cornell",
    "cornell-glass",
    "cornell-anim",
    "caustic-ring",
    "mirror-shadow",
    "ring-room",
    "furnace",
]
METHOD_SETTINGS: dict[str, dict[str, object]] = {
    "path": {"spp": 16},
    "photon": {"photons": 50_000, "spp": 4},
    "gather": {"photons": 20_000, "spp": 4},
    "direct": {"spp": 16},
    "bidir": {"spp": 16},
    "ispm": {"photons": 50_000, "spp": 16},
}
ESTIMATORS = ["volumes", "tiled", "cluster", "directional", "cpu"]
# ispm as a real GPU runs it by default (estimator and first bounce "auto": tiled and raster
# on datacenter GPUs, cpu and traced on lavapipe), and the traced first bounce; two scenes.
EXTRA_SCENES = ["cornell", "cornell-glass"]
EXTRA = {
    "ispm.auto": {"estimator": "auto", "first_bounce": "auto"},
    "ispm.traced": {"estimator": "tiled", "first_bounce": "traced"},
}
MEAN_TOLERANCE = 0.005
FLIP_FLOOR = 0.005
# Where the adapters ran different passes: FLIP between two independent draws varies from
# pair to pair (on the H100, 2026-11-26: the two `ispm.auto` rows were 0.99 and 1.05 times
# the seeds' FLIP); a real difference (a missing term, a wrong pass) is far above.
OTHER_PASSES_FLIP = 1.25


def cases() -> Iterator[tuple[str, str, str, dict[str, object]]]:
    """(case name, scene, method, settings): each method, each estimator (first bounce
    rasterized, the default on a GPU, so that both adapters run the same passes)."""
    for scene in SCENES:
        for method in ["path", "photon", "gather", "direct", "bidir"]:
            yield f"{scene}.{method}", scene, method, METHOD_SETTINGS[method]
        for est in ESTIMATORS:
            extra = {"estimator": est, "first_bounce": "raster"}
            yield f"{scene}.ispm.{est}", scene, "ispm", {**METHOD_SETTINGS["ispm"], **extra}
    for scene in EXTRA_SCENES:
        for name, extra in EXTRA.items():
            yield f"{scene}.{name}", scene, "ispm", {**METHOD_SETTINGS["ispm"], **extra}


def selected(patterns: list[str] | None) -> list[tuple[str, str, str, dict[str, object]]]:
    out = [c for c in cases() if not patterns or any(fnmatch.fnmatch(c[0], p) for p in patterns)]
    if not out:
        raise SystemExit(f"no case matches {patterns}")
    return out


def render(scene: str, method: str, settings: dict[str, object], size, seed: int):
    """Radiance (float32, H×W×3) and the estimator/first bounce that ran, and seconds."""
    t = time.perf_counter()
    r = gi.render(gi.load_scene(scene), method, size=tuple(size), seed=seed, **settings)
    seconds = time.perf_counter() - t
    ran = {"estimator": r.stats.estimator, "first_bounce": r.stats.first_bounce}
    return np.asarray(r.radiance, np.float32), ran, seconds


def flip(ref: np.ndarray, x: np.ndarray) -> float:
    """Mean HDR-FLIP of ``x`` against ``ref`` (negative values clipped, as the benches do)."""
    _, mean, _ = flip_evaluator.evaluate(
        np.ascontiguousarray(np.maximum(ref, 0.0), np.float32),
        np.ascontiguousarray(np.maximum(x, 0.0), np.float32),
        "HDR",
        applyMagma=False,
    )
    return float(mean)


def mean_diff(ref: np.ndarray, x: np.ndarray) -> float:
    """(mean(x) − mean(ref)) / mean(ref) over every pixel and channel."""
    m = float(np.mean(ref, dtype=np.float64))
    d = float(np.mean(x, dtype=np.float64)) - m
    return d / m if m > 0 else (0.0 if d == 0 else float("inf"))


def ratio(a: float, b: float) -> str:
    return f"{a / b:.2f}" if b > 0 else ("0" if a == 0 else "∞")


def adapter_line() -> str:
    return "; ".join(gi.adapter_report().splitlines()[:4])


def cmd_render(args: argparse.Namespace) -> int:
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    size = tuple(args.size)
    meta = {
        "size": size,
        "seeds": list(args.seeds),
        "gi": gi.__version__,
        "adapter": adapter_line(),
        "cases": {},
    }
    print(meta["adapter"], flush=True)
    for name, scene, method, settings in selected(args.cases):
        images = []
        entry: dict[str, object] = {"scene": scene, "method": method, "settings": settings}
        for seed in args.seeds:
            img, ran, seconds = render(scene, method, settings, size, seed)
            images.append(img)
            np.savez_compressed(out / f"{name}.s{seed}.npz", radiance=img.astype(np.float16))
            entry.update(ran)
            entry[f"seconds_s{seed}"] = round(seconds, 3)
        # The noise: the references' two seeds against each other (as stored, float16).
        a, b = (im.astype(np.float16).astype(np.float32) for im in images[:2])
        entry["noise_mean"] = mean_diff(a, b)
        entry["noise_flip"] = flip(a, b)
        meta["cases"][name] = entry
        print(
            f"{name}: {entry['seconds_s' + str(args.seeds[0])]:.2f} s, seeds differ by mean "
            f"{100 * entry['noise_mean']:+.3f}%, FLIP {entry['noise_flip']:.4f}",
            flush=True,
        )
    (out / "meta.json").write_text(json.dumps(meta, indent=1))
    return 0


def verdict(
    mean: float, fl: float, noise_mean: float, noise_flip: float, finite: bool, same: bool = True
) -> str:
    """``same``: both adapters ran the same passes (estimator and first bounce). Where they
    did not (``ispm.auto`` picks per adapter), the image is another draw of the same estimate,
    as another seed's is: its FLIP against the reference is then one more sample of the seeds'
    FLIP, and is allowed ``OTHER_PASSES_FLIP`` times it."""
    if not finite:
        return "DIFFERS (non-finite values)"
    reasons = []
    if abs(mean) > max(MEAN_TOLERANCE, 2 * abs(noise_mean)):
        reasons.append("mean")
    if fl > max(noise_flip * (1.0 if same else OTHER_PASSES_FLIP), FLIP_FLOOR):
        reasons.append("FLIP")
    return f"DIFFERS ({', '.join(reasons)})" if reasons else "agrees"


def cmd_compare(args: argparse.Namespace) -> int:
    refs: Path = args.refs
    meta = json.loads((refs / "meta.json").read_text())
    out: Path = args.out
    (out / "renders").mkdir(parents=True, exist_ok=True)
    size, seed = meta["size"], meta["seeds"][0]
    adapter = adapter_line()
    print(f"{adapter}\nreferences: {meta['adapter']} (gi {meta['gi']})", flush=True)
    if meta["gi"] != gi.__version__:
        print(f"warning: references from gi {meta['gi']}, this is gi {gi.__version__}")
    todo = [c for c in selected(args.cases) if c[0] in meta["cases"]]
    missing = [c[0] for c in selected(args.cases) if c[0] not in meta["cases"]]
    if missing:
        print(f"error: no reference for {', '.join(missing)}", file=sys.stderr)
        return 2
    (out / "expected.txt").write_text("".join(f"{c[0]}\n" for c in todo))
    rows = []
    log = (out / "images.jsonl").open("w")
    for name, scene, method, settings in todo:
        ref_meta = meta["cases"][name]
        row: dict[str, object] = {"case": name}
        try:
            img, ran, seconds = render(scene, method, settings, size, seed)
            np.savez_compressed(out / "renders" / f"{name}.npz", radiance=img.astype(np.float16))
            ref = np.load(refs / f"{name}.s{seed}.npz")["radiance"].astype(np.float32)
            finite = bool(np.isfinite(img).all())
            safe = np.nan_to_num(img, nan=0.0, posinf=0.0, neginf=0.0)
            mean, fl = mean_diff(ref, safe), flip(ref, safe)
            row.update(
                ran=f"{ran['estimator']}/{ran['first_bounce']}".strip("/"),
                ref_ran=f"{ref_meta['estimator']}/{ref_meta['first_bounce']}".strip("/"),
                seconds=round(seconds, 3),
                ref_seconds=ref_meta[f"seconds_s{seed}"],
                mean=mean,
                flip=fl,
                noise_mean=ref_meta["noise_mean"],
                noise_flip=ref_meta["noise_flip"],
                verdict=verdict(
                    mean,
                    fl,
                    ref_meta["noise_mean"],
                    ref_meta["noise_flip"],
                    finite,
                    ran == {k: ref_meta[k] for k in ran},
                ),
            )
        except Exception as e:  # every failure is reported as a row
            traceback.print_exc()
            row["verdict"] = f"FAILED ({type(e).__name__}: {e})".replace("|", "/")[:200]
        rows.append(row)
        log.write(json.dumps(row) + "\n")
        log.flush()
        print(f"{name}: {row['verdict']}", flush=True)
    log.close()
    bad = [r for r in rows if r["verdict"] != "agrees"]
    lines = [
        adapter,
        f"references: {meta['adapter']} (gi {meta['gi']}), {size[0]}×{size[1]}, seed {seed}",
        "",
        "| case | ran (estimator/first bounce) | reference ran | time (s) | reference time (s) | "
        "mean diff | seeds' mean diff | FLIP | seeds' FLIP | FLIP / seeds' | verdict |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        if "mean" not in r:
            lines.append(f"| {r['case']} | | | | | | | | | | {r['verdict']} |")
            continue
        lines.append(
            f"| {r['case']} | {r['ran']} | {r['ref_ran']} | {r['seconds']:.2f} | "
            f"{r['ref_seconds']:.2f} | {100 * r['mean']:+.3f}% | {100 * r['noise_mean']:+.3f}% | "
            f"{r['flip']:.4f} | {r['noise_flip']:.4f} | {ratio(r['flip'], r['noise_flip'])} | "
            f"{r['verdict']} |"
        )
    lines += ["", f"{len(rows)} images: {len(rows) - len(bad)} agree, {len(bad)} differ or failed"]
    (out / "images.md").write_text("\n".join(lines) + "\n")
    print(lines[-1])
    return 1 if bad else 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("render", help="render the references (two seeds)")
    r.add_argument("--out", type=Path, required=True)
    r.add_argument("--size", type=int, nargs=2, default=SIZE, metavar=("W", "H"))
    r.add_argument("--seeds", type=int, nargs=2, default=SEEDS)
    c = sub.add_parser("compare", help="render the first seed here and compare")
    c.add_argument("--refs", type=Path, required=True)
    c.add_argument("--out", type=Path, required=True)
    for p in (r, c):
        p.add_argument("--cases", nargs="*", help="case name patterns (fnmatch), e.g. 'cornell.*'")
    sub.add_parser("list", help="print the case names")
    args = ap.parse_args()
    if args.cmd == "list":
        for name, *_ in cases():
            print(name)
        return 0
    return cmd_render(args) if args.cmd == "render" else cmd_compare(args)


if __name__ == "__main__":
    sys.exit(main())
