"""Progressive mode against a converged `path` reference, error versus time.

Per scene: a `path` reference at --ref-spp (and a second one of another seed, whose error
against the first is the reference's own noise), `path` at 4, 16, ... spp (one render each),
and progressive `gather` and `ispm` (one `gi.Renderer(progressive=True)` each, passes added
for --seconds, the running mean scored at every power-of-two pass). Errors: relMSE
(mean of (x − ref)² / (ref² + 0.01)) and HDR-FLIP (flip-evaluator). Times are wall seconds
of the renders only (scoring excluded), all in the same run. Writes a Markdown table and a
log–log SVG plot per scene.

    .venv/bin/python scripts/bench/bench_progressive.py --out docs/bench/progressive.md
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from shared import cpu_name, flip, relmse  # noqa: E402

# Per-pass settings of the progressive runs: small passes (one sub-pixel sample, a modest
# photon count, kernels that start narrow) converge fastest per second; ISPM splats at full
# resolution (subsample 1), since the bilateral upsampling is a bias no pass removes.
# gather: 30k photons with smoothing 0.6 and alpha 0.9 had the lowest error per path-sample
# equivalent of cost among 12 settings tried on cornell 128x128 (photons 3k-100k, smoothing
# 0.15-0.6, alpha 0.5-0.95; docs/bench/progressive.md): with boundary compensation its bias
# is small, so radii may shrink slowly and the variance falls nearly as 1/passes.
# ispm: 80k photons at kernel scale 0.8 had the lowest FLIP after 10-16 s on cornell
# 128x128 among 20k/0.5, 40k/0.7, 80k/0.6, 80k/0.8 and 160k/1.0 (session 9, estimator `cpu`):
# with the estimate on the CPU a pass's fixed costs outweigh its photons' below ~80k.
PROGRESSIVE = {
    "gather": dict(photons=30_000, spp=1, smoothing=0.6, progressive_alpha=0.9, photon_focus=0.5),
    "ispm": dict(photons=80_000, spp=1, subsample=1, kernel_scale=0.8, adapter="cpu"),
}


def ref_cache_dir() -> Path:
    """Where the references are cached: $GI_REF_CACHE if set (a directory outside any
    worktree survives it), else target/ of the current directory."""
    return Path(os.environ.get("GI_REF_CACHE") or "target")


def reference(
    scene_name: str,
    size: tuple[int, int],
    spp: int,
    seed: int,
    light_paths: int | None = None,
    parts: int = 1,
) -> tuple:
    """A `path` reference: the mean of `parts` renders of `spp` samples per pixel (and
    `light_paths` light paths each, default one per camera sample) with seeds derived from
    `seed`, and the seconds they took. Splitting into parts bounds the light tracer's
    memory (16 bytes per light path) and lets a reference grow one cached part at a time."""
    imgs, seconds = [], 0.0
    for part in range(parts):
        img, s = reference_part(scene_name, size, spp, seed + 1_000_003 * part, light_paths)
        imgs.append(img)
        seconds += s
    return np.mean(imgs, axis=0), seconds


def reference_part(
    scene_name: str, size: tuple[int, int], spp: int, seed: int, light_paths: int | None
) -> tuple:
    # Minutes at large spp: kept for the next run in ref_cache_dir() (target/, a build
    # directory, unless GI_REF_CACHE names another).
    lp = "" if light_paths is None else f"-lp{light_paths}"
    cache = (
        ref_cache_dir()
        / f"bench-progressive-ref-{scene_name}-{size[0]}x{size[1]}-{spp}{lp}-{seed}.npz"
    )
    if cache.exists():
        saved = np.load(cache)
        return saved["radiance"], float(saved["seconds"])
    t = time.perf_counter()
    extra = {} if light_paths is None else {"light_paths": light_paths}
    scene = gi.load_scene(scene_name)
    img = gi.render(scene, "path", spp=spp, size=size, seed=seed, **extra).radiance
    seconds = time.perf_counter() - t
    cache.parent.mkdir(parents=True, exist_ok=True)
    tmp = cache.with_suffix(".tmp")
    with open(tmp, "wb") as f:  # whole or not at all: an interrupted run leaves no half file
        np.savez(f, radiance=img, seconds=seconds)
    os.replace(tmp, cache)
    return img, seconds


def progressive_run(
    scene, method: str, size, seconds: float, bounds: dict, stop: tuple = ()
) -> tuple[list, dict]:
    """Passes of a progressive renderer for `seconds` of render time: (pass count, seconds,
    image) at each power of two and at the end; and for each of `bounds` (name -> (metric,
    error function, bound)) the first pass (count, seconds) whose error is at most the
    bound, or None. Every pass is scored until its bounds are met (measured, not
    interpolated between rows); the scoring is not timed. The run ends early once every
    bound named in `stop` is met."""
    r = gi.Renderer(scene, method, size=size, progressive=True, **PROGRESSIVE[method])
    out: list = []
    hits: dict = {name: None for name in bounds}
    elapsed = 0.0
    n = 0
    while elapsed < seconds:
        t = time.perf_counter()
        img = r.render().radiance
        elapsed += time.perf_counter() - t
        n += 1
        errors: dict = {}
        for name, (metric, error, bound) in bounds.items():
            if hits[name] is None:
                if metric not in errors:
                    errors[metric] = error(img)
                if errors[metric] <= bound:
                    hits[name] = (n, elapsed)
        if n & (n - 1) == 0:
            out.append((n, elapsed, img.copy()))
        if stop and all(hits[name] is not None for name in stop):
            break
    if out[-1][0] != n:
        out.append((n, elapsed, img.copy()))
    return out, hits


def svg_plot(rows: list[dict], noise: dict, title: str) -> str:
    """Two log–log panels (relMSE, FLIP against seconds), one line per method."""
    colors = {"path": "#1f77b4", "gather": "#d62728", "ispm": "#2ca02c"}
    panels = [("relmse", "relMSE"), ("flip", "FLIP")]
    w, h, pad = 360, 260, 48
    parts = [
        f'<svg xmlns="http://www.w3.org/2000/svg" width="{2 * w}" height="{h + 30}"'
        ' font-family="sans-serif" font-size="11">',
        f'<text x="{w}" y="14" text-anchor="middle" font-size="13">{title}</text>',
    ]
    ts = [r["seconds"] for r in rows]
    for i, (key, label) in enumerate(panels):
        ox = i * w
        vals = [r[key] for r in rows] + [noise[key]]
        lx0, lx1 = math.floor(math.log10(min(ts))), math.ceil(math.log10(max(ts)))
        ly0, ly1 = math.floor(math.log10(min(vals))), math.ceil(math.log10(max(vals)))

        def px(t: float, lx0=lx0, lx1=lx1, ox=ox) -> float:
            return ox + pad + (math.log10(t) - lx0) / (lx1 - lx0) * (w - pad - 10)

        def py(v: float, ly0=ly0, ly1=ly1) -> float:
            return 20 + (h - pad) - (math.log10(v) - ly0) / (ly1 - ly0) * (h - pad - 10)

        x0, x1, y0, y1 = px(10.0**lx0), px(10.0**lx1), py(10.0**ly0), py(10.0**ly1)
        parts.append(
            f'<rect x="{x0}" y="{y1}" width="{x1 - x0}" height="{y0 - y1}"'
            ' fill="none" stroke="#000"/>'
        )
        for e in range(lx0, lx1 + 1):
            x = px(10.0**e)
            parts.append(f'<line x1="{x}" y1="{y0}" x2="{x}" y2="{y1}" stroke="#ddd"/>')
            parts.append(f'<text x="{x}" y="{y0 + 14}" text-anchor="middle">1e{e}</text>')
        for e in range(ly0, ly1 + 1):
            y = py(10.0**e)
            parts.append(f'<line x1="{x0}" y1="{y}" x2="{x1}" y2="{y}" stroke="#ddd"/>')
            parts.append(f'<text x="{x0 - 4}" y="{y + 4}" text-anchor="end">1e{e}</text>')
        parts.append(f'<text x="{(x0 + x1) / 2}" y="{y0 + 28}" text-anchor="middle">seconds</text>')
        parts.append(f'<text x="{x0 + 6}" y="{y1 + 14}">{label}</text>')
        y = py(noise[key])
        parts.append(
            f'<line x1="{x0}" y1="{y}" x2="{x1}" y2="{y}" stroke="#888" stroke-dasharray="4 3"/>'
        )
        parts.append(
            f'<text x="{x1 - 4}" y="{y - 4}" text-anchor="end" fill="#888">reference noise</text>'
        )
        for j, method in enumerate(colors):
            pts = [(px(r["seconds"]), py(r[key])) for r in rows if r["method"] == method]
            if not pts:
                continue
            path = " ".join(f"{x:.1f},{y:.1f}" for x, y in pts)
            c = colors[method]
            parts.append(f'<polyline points="{path}" fill="none" stroke="{c}" stroke-width="1.5"/>')
            parts += [f'<circle cx="{x:.1f}" cy="{y:.1f}" r="2" fill="{c}"/>' for x, y in pts]
            label_m = method if method == "path" else f"{method} progressive"
            parts.append(f'<text x="{x1 - 110}" y="{y1 + 16 + 13 * j}" fill="{c}">{label_m}</text>')
    parts.append("</svg>")
    return "\n".join(parts)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default="cornell,mirror-shadow")
    ap.add_argument("--size", default="48x48")
    ap.add_argument("--ref-spp", type=int, default=16384)
    ap.add_argument("--seconds", type=float, default=30.0, help="progressive run length")
    ap.add_argument("--max-path-spp", type=int, default=4096)
    ap.add_argument(
        "--ref-light-paths", type=int, help="light paths per reference part (default: per sample)"
    )
    ap.add_argument("--ref-parts", type=int, default=1, help="reference = mean of this many parts")
    ap.add_argument("--methods", default=",".join(PROGRESSIVE), help="progressive methods to run")
    ap.add_argument(
        "--until-noise",
        action="store_true",
        help="end a progressive run once both errors reach the reference's own noise",
    )
    ap.add_argument("--out", type=Path)
    ap.add_argument("--append", action="store_true", help="add the scenes' sections to --out")
    args = ap.parse_args()
    methods = args.methods.split(",")
    w, h = (int(v) for v in args.size.split("x"))
    size = (w, h)
    ref_desc = f"{args.ref_spp} spp" + (
        "" if args.ref_light_paths is None else f" and {args.ref_light_paths:.3g} light paths"
    )
    if args.ref_parts > 1:
        ref_desc = f"the mean of {args.ref_parts} parts of {ref_desc}"
    command = " ".join(["scripts/bench/bench_progressive.py", *sys.argv[1:]])
    lines = (
        []
        if args.append
        else [
            "# Progressive mode: error against the converged image versus time",
            "",
            f"On {cpu_name()}, {os.cpu_count()} logical CPUs shared with other jobs, lavapipe"
            " for `ispm`. relMSE = mean (x − ref)² / (ref² + 0.01); FLIP = mean HDR-FLIP."
            " *Reference noise*: the same errors of a second reference of another seed, the"
            " floor below which no comparison can see. Times are same-run wall seconds on a"
            f" loaded machine. Progressive settings per pass: {PROGRESSIVE}.",
            "",
        ]
    )
    lines += [
        f"Made by `.venv/bin/python {command}` ({args.size}, reference `path` at {ref_desc},"
        f" progressive runs of {args.seconds:g} s"
        + (" or until the reference's noise" if args.until_noise else "")
        + "):",
        "",
    ]
    for name in args.scenes.split(","):
        scene = gi.load_scene(name)
        recipe = (args.ref_spp, args.ref_light_paths, args.ref_parts)
        ref, ref_s = reference(name, size, recipe[0], 1234, recipe[1], recipe[2])
        ref2, _ = reference(name, size, recipe[0], 4321, recipe[1], recipe[2])
        noise = {"relmse": relmse(ref2, ref), "flip": flip(ref, ref2)}
        rows: list[dict] = []
        spp = 4
        while spp <= args.max_path_spp:
            t = time.perf_counter()
            img = gi.render(scene, "path", spp=spp, size=size, seed=7).radiance
            s = time.perf_counter() - t
            rows.append(dict(method="path", step=f"{spp} spp", seconds=s, per=s / spp, image=img))
            spp *= 4
        metrics = {
            "relMSE": ("relmse", lambda img, ref=ref: relmse(img, ref)),
            "FLIP": ("flip", lambda img, ref=ref: flip(ref, img)),
        }
        for r in rows:
            for key, error in metrics.values():
                r[key] = error(r["image"])
        path_1024 = next(
            (r for r in rows if r["method"] == "path" and r["step"] == "1024 spp"), None
        )
        targets = []  # (label, seconds to beat or None, metric, bound)
        for metric, (key, _) in metrics.items():
            if path_1024 is not None:
                targets.append(
                    (
                        f"`path` at 1024 spp: {metric} {path_1024[key]:.3g} in"
                        f" {path_1024['seconds']:.2f} s",
                        path_1024["seconds"],
                        metric,
                        path_1024[key],
                    )
                )
            targets.append(
                (f"The reference's own noise: {metric} {noise[key]:.3g}", None, metric, noise[key])
            )
        bounds = {label: (metric, metrics[metric][1], bound) for label, _, metric, bound in targets}
        stop = tuple(label for label, beat, _, _ in targets if beat is None)
        hits: dict[str, dict] = {}
        for method in methods:
            gi.render(scene, method, size=(8, 8), photons=1000, spp=1)  # warm-up (pipelines)
            steps, hits[method] = progressive_run(
                scene, method, size, args.seconds, bounds, stop if args.until_noise else ()
            )
            for n, s, img in steps:
                row = dict(method=method, step=f"{n} passes", seconds=s, per=s / n, image=img)
                for key, error in metrics.values():
                    row[key] = error(img)
                rows.append(row)
        lines += [
            f"## {name}",
            "",
            f"Reference: {ref_s:.1f} s; reference noise: relMSE {noise['relmse']:.2e},"
            f" FLIP {noise['flip']:.4f}.",
            "",
            "| method | step | seconds | ms per pass or spp | relMSE | FLIP |",
            "|---|---|---:|---:|---:|---:|",
        ]
        for r in rows:
            lines.append(
                f"| {r['method']} | {r['step']} | {r['seconds']:.3f} | {1e3 * r['per']:.1f}"
                f" | {r['relmse']:.2e}"
                f" | {r['flip']:.4f} |"
            )
        lines.append("")
        for label, beat, _, _ in targets:
            for method in methods:
                hit = hits[method][label]
                if hit is None:
                    reached = f"not within {args.seconds:g} s."
                elif beat is None:
                    reached = f"at pass {hit[0]}, {hit[1]:.2f} s."
                else:
                    reached = (
                        f"at pass {hit[0]}, {hit[1]:.2f} s ({beat / hit[1]:.2f}x path's speed)."
                    )
                lines.append(f"- {label}; progressive `{method}` first reaches it {reached}")
        lines.append("")
        if args.out:
            svg = args.out.with_name(f"progressive-{name}-{args.size}.svg")
            svg.write_text(svg_plot(rows, noise, f"{name}, {args.size}: error vs time"))
            lines += [f"![{name}]({svg.name})", ""]
        print("\n".join(lines[-len(rows) - 12 :]), flush=True)
    text = "\n".join(lines)
    if args.out and args.append:
        with args.out.open("a") as f:
            f.write("\n" + text)
    elif args.out:
        args.out.write_text(text)
    else:
        print(text)


if __name__ == "__main__":
    main()
