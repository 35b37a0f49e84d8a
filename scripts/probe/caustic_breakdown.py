"""Where the caustic scenes' extra light comes from (issue 29): `ispm` and `gather` against
`path`, split by pixel and path type, and the change each part of the caustic machinery
makes to the image mean.

Per scene (caustic-ring, cornell-glass, ring-room), at --size, over --seeds seeds:

- **References.** `path` (the mean of --ref-parts renders of --ref-spp samples and
  --ref-light-paths light paths, cached in $GI_REF_CACHE or target/): its image R, its
  light-traced part C (the `caustics` image: paths whose first bounce from the light is a
  delta lobe) and its direct light D (max_depth 1, no light paths).
- **Pixels.** The mirror and glass pixels (where `ispm`'s `specular` image is not black, any
  of two seeds) and the rest. `path` cannot render a point light's caustic seen in a mirror
  or through glass (light, delta, ..., diffuse, delta, camera: camera paths never reach the
  point light, light paths cannot connect to the camera through the delta surface), which
  photon mapping renders. On caustic-ring that light is computed here independently
  (`ring_mirror_caustic`): a top-down `path` render of the floor's light-traced radiance
  (Lambertian, so the same towards any direction), read where the camera rays reflected by
  the ring (traced with `Scene.intersect`) land. Its check: the same map read at the floor
  seen directly reproduces `path`'s own `caustics` image there (printed).
- **Contributions** to the image mean, as fractions of the reference's mean (± the standard
  error over seeds): on the mirror pixels (against R, and against R + the missing light
  where computed); off them, `ispm`'s direct light (against D) and its indirect light
  (against R - D) on the pixels where the reference's light is mostly caustic (C > (R - D)/2)
  and on the others; `gather`'s off them.
- **Switches.** Each candidate's change of the mean, paired by seed against the defaults:
  no caustic density bound (`photon/density.rs`), no boundary compensation
  (`photon/boundary.rs`), no photon focusing (`photon/focus.rs`), half and double kernels
  (`kernel_scale`: the overlap of kernels at the caustic's edge), full-resolution splat
  (`subsample` 1: the upsampling), every specular path gathered (`specular_sampling` full:
  the landings, `photon/delta_paths.rs`), 4x the photons.
- **Resolution.** `ispm` at subsample 1 against the same photons splatted at twice the size
  and averaged 2x2: its indirect light is one sample at each pixel's centre, the
  reference's the pixel's mean.

    GI_REF_CACHE=/work/cache/refs .venv/bin/python scripts/probe/caustic_breakdown.py \\
        --out docs/bench/caustic_breakdown.md
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from bench.bench_progressive import ref_cache_dir  # noqa: E402
from shared import cpu_name  # noqa: E402

SETTINGS = {
    "ispm": dict(photons=200_000, adapter="cpu"),
    "gather": dict(photons=200_000, spp=4),
}
SWITCHES = {
    "ispm": [
        ("no density bound", dict(caustic_density_bound=False)),
        ("no boundary compensation", dict(boundary_compensation=False)),
        ("photon_focus 0", dict(photon_focus=0.0)),
        ("kernel_scale 0.5", dict(kernel_scale=0.5)),
        ("kernel_scale 2", dict(kernel_scale=2.0)),
        ("subsample 1", dict(subsample=1)),
        ("specular_sampling full", dict(specular_sampling="full")),
        ("4x photons", dict(photons=800_000)),
    ],
    "gather": [
        ("no density bound", dict(caustic_density_bound=False)),
        ("no boundary compensation", dict(boundary_compensation=False)),
        ("photon_focus 0", dict(photon_focus=0.0)),
        ("4x photons", dict(photons=800_000)),
    ],
}


def cached(name: str, make) -> dict:
    """`make()` (a dict of arrays), kept in the reference cache under `name`."""
    path = ref_cache_dir() / f"caustic-breakdown-{name}.npz"
    if path.exists():
        return dict(np.load(path))
    out = make()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    with open(tmp, "wb") as f:
        np.savez(f, **out)
    os.replace(tmp, path)
    return out


def references(name: str, size: tuple, spp: int, light_paths: int, parts: int) -> dict:
    """`path`'s image R, its light-traced part C and its direct light D (means of parts)."""
    scene = gi.load_scene(name)

    def part(i: int) -> dict:
        def make() -> dict:
            full = gi.render(
                scene, "path", size=size, spp=spp, light_paths=light_paths, seed=7000 + i
            )
            direct = gi.render(
                scene, "path", size=size, spp=spp, max_depth=1, light_paths=0, seed=8000 + i
            )
            return {"R": full.radiance, "C": full.caustics, "D": direct.radiance}

        return cached(f"{name}-{size[0]}x{size[1]}-{spp}-{light_paths}-{i}", make)

    ps = [part(i) for i in range(parts)]
    return {k: np.mean([p[k] for p in ps], axis=0) for k in ("R", "C", "D")}


def mirror_mask(scene, size: tuple) -> np.ndarray:
    """Pixels whose camera ray meets a mirror or glass first (any of two seeds)."""
    return np.any(
        [
            gi.render(scene, "ispm", size=size, seed=s, photons=20_000, adapter="cpu")
            .extra["specular"]
            .max(axis=-1)
            > 0
            for s in (0, 1)
        ],
        axis=0,
    )


def ring_mirror_caustic(
    size: tuple, light_paths: int, map_size: int = 1024, rays: int = 64
) -> tuple[np.ndarray, np.ndarray]:
    """caustic-ring's light that `path` cannot render, per pixel: the floor's light-traced
    radiance (a top-down `path` render's `caustics` image, map_size² over the floor's
    ±3.05 m) read where each of `rays` jittered camera rays per pixel lands after one or
    more reflections in the ring (mirror reflectance 0.95 each). Also returns the same map
    read where the rays meet the floor directly: it must equal `path`'s `caustics` image
    there (the check of the map and of the camera model)."""
    desc = json.loads(gi.builtin_json("caustic-ring"))
    height, half = 30.0, 3.05
    top = dict(desc)
    top["camera"] = dict(
        position=[0, height, 0],
        look_at=[0, 0, 0],
        up=[0, 0, -1],
        fov=2 * math.degrees(math.atan(half / height)),
        width=map_size,
        height=map_size,
    )
    top_scene = gi.Scene.from_json(json.dumps(top))
    cmap = gi.render(
        top_scene, "path", size=(map_size, map_size), spp=1, light_paths=light_paths, seed=5
    ).caustics

    def lookup(x: np.ndarray, z: np.ndarray) -> np.ndarray:
        # The top-down view maps the floor linearly: +x to the right, +z down the image.
        px = (x / half + 1) / 2 * map_size - 0.5
        py = (z / half + 1) / 2 * map_size - 0.5
        x0 = np.clip(np.floor(px).astype(int), 0, map_size - 2)
        y0 = np.clip(np.floor(py).astype(int), 0, map_size - 2)
        fx = np.clip(px - x0, 0, 1)[:, None]
        fy = np.clip(py - y0, 0, 1)[:, None]
        return (
            cmap[y0, x0] * (1 - fx) * (1 - fy)
            + cmap[y0, x0 + 1] * fx * (1 - fy)
            + cmap[y0 + 1, x0] * (1 - fx) * fy
            + cmap[y0 + 1, x0 + 1] * fx * fy
        )

    scene = gi.load_scene("caustic-ring")
    cam = desc["camera"]
    w, h = size
    eye = np.array(cam["position"], float)
    fwd = np.array(cam["look_at"], float) - eye
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, cam["up"])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    t = math.tan(math.radians(cam["fov"]) / 2)
    rng = np.random.default_rng(3)
    ys, xs = np.mgrid[0:h, 0:w]
    px = (xs[..., None] + rng.random((h, w, rays))).ravel()
    py = (ys[..., None] + rng.random((h, w, rays))).ravel()
    pixel = np.repeat((ys * w + xs).ravel(), rays)
    sx = (2 * px / w - 1) * t * w / h
    sy = (1 - 2 * py / h) * t
    d = fwd + right * sx[:, None] + up * sy[:, None]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    o = np.repeat(eye[None], len(d), 0)
    weight = np.ones(len(d))
    bounces = np.zeros(len(d), int)
    alive = np.ones(len(d), bool)
    missing = np.zeros((w * h, 3))
    direct = np.zeros((w * h, 3))
    # Triangles: the floor quad (2), then the ring's outer wall, inner wall, top and bottom
    # (2 x 256 each; `scene/primitives.rs`'s `ring`), with smooth radial normals.
    for _ in range(8):
        idx = np.nonzero(alive)[0]
        if len(idx) == 0:
            break
        dist, tri = scene.intersect(o[idx].astype(np.float32), d[idx].astype(np.float32))
        hit = np.isfinite(dist)
        alive[idx[~hit]] = False
        idx, dist, tri = idx[hit], dist[hit].astype(float), tri[hit]
        p = o[idx] + d[idx] * dist[:, None]
        floor = tri < 2
        for out, sel in ((missing, bounces[idx] > 0), (direct, bounces[idx] == 0)):
            f = floor & sel
            np.add.at(
                out, pixel[idx[f]], (weight[idx[f]] / rays)[:, None] * lookup(p[f, 0], p[f, 2])
            )
        alive[idx[floor]] = False
        m, pm, tm = idx[~floor], p[~floor], tri[~floor]
        radial = np.stack([pm[:, 0], np.zeros(len(pm)), pm[:, 2]], 1)
        radial /= np.linalg.norm(radial, axis=1, keepdims=True)
        n = np.zeros_like(pm)
        outer, inner = (tm >= 2) & (tm < 514), (tm >= 514) & (tm < 1026)
        n[outer], n[inner] = radial[outer], -radial[inner]
        n[(tm >= 1026) & (tm < 1538)] = [0, 1, 0]
        n[tm >= 1538] = [0, -1, 0]
        r = d[m] - 2 * (d[m] * n).sum(1, keepdims=True) * n
        d[m], o[m] = r, pm + 1e-4 * r
        weight[m] *= 0.95
        bounces[m] += 1
    return missing.reshape(h, w, 3), direct.reshape(h, w, 3)


def se(a) -> float:
    a = np.asarray(a, float)
    return float(a.std(ddof=1) / math.sqrt(len(a))) if len(a) > 1 else float("nan")


def fmt(a) -> str:
    return f"{100 * np.mean(a):+.2f} ± {100 * se(a):.2f}"


def down(x: np.ndarray) -> np.ndarray:
    h, w = x.shape[:2]
    return x.reshape(h // 2, 2, w // 2, 2, -1).mean((1, 3))


def breakdown(name: str, size: tuple, seeds: range, ref: dict, missing) -> list[str]:
    scene = gi.load_scene(name)
    r_img, c_img, d_img = ref["R"], ref["C"], ref["D"]
    total = r_img.sum()
    mask = mirror_mask(scene, size)
    off = ~mask
    caustic = off & (c_img.mean(-1) > 0.5 * (r_img - d_img).mean(-1))
    rows = []

    def row(what: str, values, note: str = "") -> None:
        rows.append(f"| {name} | {what} | {fmt(values)} | {note} |")
        print(rows[-1], flush=True)

    print(
        f"{name}: mirror and glass pixels {mask.mean():.1%}, caustic pixels {caustic.mean():.1%},"
        f" the reference's light-traced share {c_img.sum() / total:.1%}",
        flush=True,
    )
    if missing is not None:
        m = missing.sum() / total
        rows.append(
            f"| {name} | path's missing light on the mirror pixels | {100 * m:+.2f} | computed |"
        )
        print(rows[-1], flush=True)
    ispm = [gi.render(scene, "ispm", size=size, seed=s, **SETTINGS["ispm"]) for s in seeds]
    row("ispm: image mean", [r.radiance.sum() / total - 1 for r in ispm])
    row("ispm: mirror pixels", [(r.radiance - r_img)[mask].sum() / total for r in ispm])
    if missing is not None:
        row(
            "ispm: mirror pixels against path + its missing light",
            [(r.radiance - r_img - missing)[mask].sum() / total for r in ispm],
        )
    row("ispm: off mirrors, direct", [(r.extra["direct"] - d_img)[off].sum() / total for r in ispm])
    ind = [r.extra["indirect"] - (r_img - d_img) for r in ispm]
    row("ispm: off mirrors, indirect, caustic pixels", [e[caustic].sum() / total for e in ind])
    row("ispm: off mirrors, indirect, other pixels", [e[off & ~caustic].sum() / total for e in ind])
    base = [r.radiance.sum() / total for r in ispm]
    for label, kw in SWITCHES["ispm"]:
        settings = {**SETTINGS["ispm"], **kw}
        imgs = [gi.render(scene, "ispm", size=size, seed=s, **settings).radiance for s in seeds]
        row(
            f"ispm: {label} (change)",
            [i.sum() / total - b for i, b in zip(imgs, base, strict=True)],
        )
    big = (2 * size[0], 2 * size[1])
    one = {**SETTINGS["ispm"], "subsample": 1}
    row(
        "ispm, subsample 1: one sample per pixel against 2x2 (indirect)",
        [
            (
                gi.render(scene, "ispm", size=size, seed=s, **one).extra["indirect"]
                - down(gi.render(scene, "ispm", size=big, seed=s, **one).extra["indirect"])
            ).sum()
            / total
            for s in seeds
        ],
    )
    gather = [
        gi.render(scene, "gather", size=size, seed=s, **SETTINGS["gather"]).radiance for s in seeds
    ]
    row("gather: image mean", [g.sum() / total - 1 for g in gather])
    row("gather: mirror pixels", [(g - r_img)[mask].sum() / total for g in gather])
    if missing is not None:
        row(
            "gather: mirror pixels against path + its missing light",
            [(g - r_img - missing)[mask].sum() / total for g in gather],
        )
    row("gather: off mirrors", [(g - r_img)[off].sum() / total for g in gather])
    base = [g.sum() / total for g in gather]
    for label, kw in SWITCHES["gather"]:
        settings = {**SETTINGS["gather"], **kw}
        imgs = [gi.render(scene, "gather", size=size, seed=s, **settings).radiance for s in seeds]
        row(
            f"gather: {label} (change)",
            [i.sum() / total - b for i, b in zip(imgs, base, strict=True)],
        )
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--scenes", default="caustic-ring,cornell-glass,ring-room")
    ap.add_argument("--size", default="48x48")
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--ref-spp", type=int, default=512)
    ap.add_argument("--ref-light-paths", type=int, default=32_000_000)
    ap.add_argument("--ref-parts", type=int, default=2)
    ap.add_argument("--map-light-paths", type=int, default=64_000_000)
    ap.add_argument("--out", type=Path, help="Markdown file to write the table to")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    size = (w, h)
    seeds = range(args.seeds)
    t0 = time.perf_counter()
    rows = []
    for name in args.scenes.split(","):
        ref = references(name, size, args.ref_spp, args.ref_light_paths, args.ref_parts)
        missing = None
        if name == "caustic-ring":
            maps = cached(
                f"ring-mirror-{w}x{h}-{args.map_light_paths}",
                lambda: dict(
                    zip(
                        ("missing", "direct"),
                        ring_mirror_caustic(size, args.map_light_paths),
                        strict=True,
                    )
                ),
            )
            missing = maps["missing"]
            check = maps["direct"].sum() / ref["C"].sum()
            print(
                f"caustic-ring: the floor map read on the floor seen directly / path's caustics"
                f" image: {check:.4f} (whole image; the mirror pixels' direct part included)",
                flush=True,
            )
        rows += breakdown(name, size, seeds, ref, missing)
    argv = sys.argv[1:]
    head = [
        f"Made by `{' '.join(['.venv/bin/python', 'scripts/probe/caustic_breakdown.py', *argv])}`"
        f" ({args.size}, {args.seeds} seeds; reference: `path`, {args.ref_parts} parts of"
        f" {args.ref_spp} spp and {args.ref_light_paths:.3g} light paths) on {cpu_name()},"
        f" {os.cpu_count()} logical CPUs, lavapipe; {time.perf_counter() - t0:.0f} s."
        f" Settings: {SETTINGS}. Percent of the reference's image mean, ± the standard error"
        " over seeds; *(change)*: the mean with the switch minus the mean at defaults, paired"
        " by seed.",
        "",
        "| scene | part | % of the mean | |",
        "|---|---|---:|---|",
    ]
    text = "\n".join(head + rows) + "\n"
    if args.out:
        args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
