"""Where progressive `ispm`'s error comes from: direct light versus the rest.

Runs progressive `ispm` (the per-pass settings of scripts/bench/bench_progressive.py) with its
`direct` image read back each pass, and at every power-of-two pass splits the running
mean's squared error against a `path` reference into
- *direct*: the mean of the passes' `direct` images against `path` at max_depth 1 (the
  direct light of the first surface, nothing behind mirrors);
- *rest*: the mean radiance minus that, against the full reference minus the direct one
  (indirect light, mirrors and glass),
each as relMSE with the full reference's denominator (ref² + 0.01), so the two parts and
their cross term add up to the total. Also: the share of the total squared error in the
pixels next to a crease or depth step (*edge*), the mean signed relative error of the
direct part and of the rest there and elsewhere, the rest's relMSE off the edges, and
*w/o mirror pixels*: the total's squared error summed over the pixels whose `specular`
image stayed black (nothing seen through a mirror or glass: `path` misses a point light's
caustic seen in a mirror, which photon mapping renders). The full reference is the cached
one of scripts/bench/bench_progressive.py (same arguments; with GI_REF_CACHE the same files as
scripts/bench/bench_caustics.py's), the direct one is made here and cached beside it.

    .venv/bin/python scripts/probe/ispm_progressive_split.py --scene cornell --size 128x128 \\
        --ref-spp 32768 --passes 256
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from bench.bench_progressive import PROGRESSIVE, ref_cache_dir, reference  # noqa: E402


def direct_reference(scene_name: str, size: tuple[int, int], spp: int) -> np.ndarray:
    cache = ref_cache_dir() / f"ispm-split-direct-{scene_name}-{size[0]}x{size[1]}-{spp}.npz"
    if cache.exists():
        return np.load(cache)["radiance"]
    scene = gi.load_scene(scene_name)
    img = gi.render(scene, "path", spp=spp, size=size, seed=99, max_depth=1).radiance
    cache.parent.mkdir(parents=True, exist_ok=True)
    tmp = cache.with_suffix(".tmp")
    with open(tmp, "wb") as f:
        np.savez(f, radiance=img)
    os.replace(tmp, cache)
    return img


def edge_mask(position: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Pixels next to a crease or a depth discontinuity (a neighbour off the pixel's tangent
    plane by more than a tenth of their distance), or to the background."""
    h, w = normal.shape[:2]
    edge = np.zeros((h, w), bool)
    for a, b in [
        ((slice(0, h - 1), slice(None)), (slice(1, h), slice(None))),
        ((slice(None), slice(0, w - 1)), (slice(None), slice(1, w))),
    ]:
        d = position[b] - position[a]
        dist = np.linalg.norm(d, axis=-1)
        off = np.maximum(
            np.abs(np.sum(d * normal[a], axis=-1)), np.abs(np.sum(d * normal[b], axis=-1))
        )
        empty = (np.abs(normal[a]).sum(-1) == 0) | (np.abs(normal[b]).sum(-1) == 0)
        jump = (off > 0.1 * dist) | (empty != (np.abs(normal[a]).sum(-1) == 0))
        edge[a] |= jump
        edge[b] |= jump
    return edge


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--size", default="128x128")
    ap.add_argument("--ref-spp", type=int, default=32768)
    ap.add_argument("--ref-light-paths", type=int)
    ap.add_argument("--ref-parts", type=int, default=1)
    ap.add_argument("--direct-spp", type=int, default=4096)
    ap.add_argument("--passes", type=int, default=256)
    ap.add_argument(
        "--set", action="append", default=[], help="override a per-pass setting, KEY=VALUE"
    )
    ap.add_argument("--save", type=Path, help="write the last means and references (.npz)")
    args = ap.parse_args()
    size = tuple(int(v) for v in args.size.split("x"))
    ref, _ = reference(args.scene, size, args.ref_spp, 1234, args.ref_light_paths, args.ref_parts)
    dref = direct_reference(args.scene, size, args.direct_spp)
    rest_ref = ref - dref
    den = ref**2 + 1e-2
    scene = gi.load_scene(args.scene)
    settings = dict(PROGRESSIVE["ispm"])
    for kv in args.set:
        key, value = kv.split("=", 1)
        settings[key] = type(settings.get(key, 1.0))(value)
    r = gi.Renderer(scene, "ispm", size=size, progressive=True, **settings)
    direct_sum = np.zeros_like(ref, dtype=np.float64)
    seen_specular = np.zeros(ref.shape[:2], bool)
    elapsed = 0.0
    edge = None
    print(f"gi {gi.__file__}; {args.scene} {args.size}; {settings}")
    print(
        "| passes | seconds | relMSE | direct | rest | edge share | direct bias edge"
        " | elsewhere | rest bias edge | elsewhere | rest relMSE off edges"
        " | relMSE w/o mirror pixels |"
    )
    print("|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")
    for n in range(1, args.passes + 1):
        t = time.perf_counter()
        f = r.render(aovs=edge is None, extras=True)
        elapsed += time.perf_counter() - t
        if edge is None:
            edge = edge_mask(f.position, f.normal)
        direct_sum += f.extra["direct"]
        seen_specular |= f.extra["specular"].max(axis=-1) > 0
        if n & (n - 1) and n != args.passes:
            continue
        mean = f.radiance.astype(np.float64)
        direct = direct_sum / n
        rest = mean - direct
        se = (mean - ref) ** 2 / den
        e_d = float(np.mean((direct - dref) ** 2 / den))
        e_r = float(np.mean((rest - rest_ref) ** 2 / den))
        lum = dref.mean(axis=-1)
        lit = lum > 0.05 * lum.mean()
        rel = (direct - dref).mean(axis=-1) / np.maximum(lum, 1e-6)
        bias_edge = float(np.mean(rel[edge & lit]))
        bias_in = float(np.mean(rel[~edge & lit]))
        rl = rest_ref.mean(axis=-1)
        rlit = rl > 0.05 * rl.mean()
        rrel = (rest - rest_ref).mean(axis=-1) / np.maximum(rl, 1e-6)
        rb_edge = float(np.mean(rrel[edge & rlit]))
        rb_in = float(np.mean(rrel[~edge & rlit]))
        e_r_in = float(np.mean(((rest - rest_ref) ** 2 / den)[~edge]))
        share = float(se[edge].sum() / se.sum())
        plain = float(se[~seen_specular].sum() / se.size)
        print(
            f"| {n} | {elapsed:.2f} | {se.mean():.2e} | {e_d:.2e} | {e_r:.2e} | {share:.2f}"
            f" | {bias_edge:+.2%} | {bias_in:+.2%} | {rb_edge:+.2%} | {rb_in:+.2%}"
            f" | {e_r_in:.2e} | {plain:.2e} |",
            flush=True,
        )
    print(
        f"edge pixels: {edge.mean():.0%} of the image; seen through mirrors or glass:"
        f" {seen_specular.mean():.0%}"
    )
    if args.save:
        np.savez(args.save, mean=mean, direct=direct, ref=ref, dref=dref, edge=edge)


if __name__ == "__main__":
    main()
