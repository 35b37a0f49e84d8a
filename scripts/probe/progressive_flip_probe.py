"""FLIP and relMSE of progressive runs against a `path` reference on a small `cornell`, with
`path` at 256 and 1024 spp for comparison, all in one run (issue 11: where progressive
`ispm`'s FLIP stays above `path`'s). Saves the last FLIP maps and images to /tmp. Each FLIP
is also split into its share on the *crease band* (pixels within one pixel of a crease or a
depth step, from the G-buffer of a `path` frame) and on the rest: mean = band + rest.

    .venv/bin/python scripts/probe/progressive_flip_probe.py WIDTH HEIGHT REF_SPP SECONDS CONFIGS

CONFIGS is a JSON list of [method, settings] pairs, e.g.
'[["ispm", {"photons": 20000, "spp": 1, "subsample": 1, "kernel_scale": 0.5}]]'.
The reference is `bench_progressive.reference` (cached like the benchmark's).
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import flip_evaluator
import numpy as np

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared, bench/
from bench.bench_progressive import reference  # noqa: E402
from ispm_progressive_split import edge_mask  # noqa: E402
from shared import relmse  # noqa: E402


def crease_band(scene, size: tuple[int, int]) -> np.ndarray:
    """Pixels next to a crease or a depth step, widened by one pixel."""
    frame = gi.Renderer(scene, "path", size=size, spp=4).render(aovs=True)
    e = edge_mask(frame.position, frame.normal)
    band = e.copy()
    band[1:] |= e[:-1]
    band[:-1] |= e[1:]
    band[:, 1:] |= e[:, :-1]
    band[:, :-1] |= e[:, 1:]
    return band


def main() -> None:
    size = (int(sys.argv[1]), int(sys.argv[2]))
    ref_spp = int(sys.argv[3])
    seconds = float(sys.argv[4])
    configs = json.loads(sys.argv[5])
    ref, _ = reference("cornell", size, ref_spp, 1234)
    scene = gi.load_scene("cornell")
    band = crease_band(scene, size)
    print(f"crease band: {band.mean():.1%} of the pixels", flush=True)

    def split(m: np.ndarray) -> str:
        m = m.reshape(band.shape)
        return f"(band {m[band].sum() / m.size:.4f} + rest {m[~band].sum() / m.size:.4f})"

    def flipmap(x: np.ndarray) -> tuple[np.ndarray, float]:
        m, mean, _ = flip_evaluator.evaluate(
            np.ascontiguousarray(ref, np.float32),
            np.ascontiguousarray(np.maximum(x, 0), np.float32),
            "HDR",
            applyMagma=False,
        )
        return np.asarray(m), float(mean)

    for spp in (256, 1024):
        t = time.perf_counter()
        img = gi.render(scene, "path", spp=spp, size=size, seed=7).radiance
        s = time.perf_counter() - t
        m, f = flipmap(img)
        err = relmse(img, ref)
        print(f"path {spp} spp {s:.2f}s relMSE {err:.2e} FLIP {f:.4f} {split(m)}", flush=True)
        np.save(f"/tmp/flip_path{spp}.npy", m)
    for k, (method, settings) in enumerate(configs):
        r = gi.Renderer(scene, method, size=size, progressive=True, **settings)
        elapsed, n, report = 0.0, 0, 1
        while elapsed < seconds:
            t = time.perf_counter()
            frame = r.render()
            elapsed += time.perf_counter() - t
            n += 1
            if n == report or elapsed >= seconds:
                report *= 2
                m, f = flipmap(frame.radiance)
                err = relmse(frame.radiance, ref)
                print(
                    f"{method} {settings} pass {n} {elapsed:.2f}s relMSE {err:.2e} FLIP {f:.4f}"
                    f" {split(m)}",
                    flush=True,
                )
        np.save(f"/tmp/flip_{k}.npy", m)
        np.save(f"/tmp/img_{k}.npy", frame.radiance)


if __name__ == "__main__":
    main()
