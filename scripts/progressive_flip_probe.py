"""FLIP and relMSE of progressive runs against a `path` reference on a small `cornell`, with
`path` at 256 and 1024 spp for comparison, all in one run (issue 11: where progressive
`ispm`'s FLIP stays above `path`'s). Saves the last FLIP maps and images to /tmp.

    .venv/bin/python scripts/progressive_flip_probe.py WIDTH HEIGHT REF_SPP SECONDS CONFIGS

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

sys.path.insert(0, str(Path(__file__).parent))
from bench_progressive import reference, relmse  # noqa: E402


def main() -> None:
    size = (int(sys.argv[1]), int(sys.argv[2]))
    ref_spp = int(sys.argv[3])
    seconds = float(sys.argv[4])
    configs = json.loads(sys.argv[5])
    ref, _ = reference("cornell", size, ref_spp, 1234)
    scene = gi.load_scene("cornell")

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
        print(f"path {spp} spp {s:.2f}s relMSE {relmse(img, ref):.2e} FLIP {f:.4f}", flush=True)
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
                    f"{method} {settings} pass {n} {elapsed:.2f}s relMSE {err:.2e} FLIP {f:.4f}",
                    flush=True,
                )
        np.save(f"/tmp/flip_{k}.npy", m)
        np.save(f"/tmp/img_{k}.npy", frame.radiance)


if __name__ == "__main__":
    main()
