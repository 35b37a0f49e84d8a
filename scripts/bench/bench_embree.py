"""Incoherent closest-hit throughput of gi's obvhs BVH against Embree (PyPI `embreex`), on
the same rays over the same ~246k-triangle scene, measured in the same run.

    .venv/bin/pip install embreex && .venv/bin/python scripts/bench/bench_embree.py

Writes docs/bench/embree.md. Both are driven from Python with the same numpy arrays, so the
figures include the same call overhead; gi releases the GIL and traces with all cores
(rayon), Embree's `run` traces on one thread, so the table reports both per-thread and
whole-machine rates.
"""

from __future__ import annotations

import json
import os
import platform
import time
from pathlib import Path

import numpy as np

import gi


def dense_cornell() -> gi.Scene:
    """The scene of `cargo bench --bench bvh` (crates/core/src/scene/bench.rs)."""
    desc = json.loads(gi.builtin_json("cornell"))
    for x, z in [(-0.5, 0.3), (0.5, -0.3), (0.0, 0.5)]:
        desc["objects"].append(
            {
                "shape": {"type": "sphere", "radius": 0.3, "subdivisions": 6},
                "transform": {"translate": [x, 1.2, z]},
                "material": "white",
            }
        )
    return gi.Scene.from_json(json.dumps(desc), "dense-cornell")


def best_of(f, repeats: int = 5) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        f()
        times.append(time.perf_counter() - t)
    return min(times)


def main() -> None:
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    scene = dense_cornell()
    verts, faces = scene.mesh_arrays()
    rng = np.random.default_rng(1)
    n = 1 << 20
    origins = (rng.random((n, 3)) * [1.9, 1.9, 1.9] + [-0.95, 0.05, -0.95]).astype(np.float32)
    dirs = rng.normal(size=(n, 3))
    dirs = (dirs / np.linalg.norm(dirs, axis=1, keepdims=True)).astype(np.float32)

    build_gi = best_of(lambda: dense_cornell().build_bvh(), 3)
    scene.build_bvh()
    t_gi = best_of(lambda: scene.intersect(origins, dirs))
    tri = verts[faces].astype(np.float32)
    e_scene = rtcs.EmbreeScene()
    t0 = time.perf_counter()
    TriangleMesh(e_scene, tri)
    e_scene.run(origins[:1], dirs[:1])  # Embree commits (builds) lazily
    build_embree = time.perf_counter() - t0
    t_em = best_of(lambda: e_scene.run(origins, dirs, output=1))

    # Both must find the same hits: compare distances where both hit.
    t_hit, tri_hit = scene.intersect(origins, dirs)
    em = e_scene.run(origins, dirs, output=1)
    both = (tri_hit >= 0) & (em["primID"] >= 0)
    agree = np.isclose(t_hit[both], em["tfar"][both], rtol=1e-4, atol=1e-5).mean()

    threads = os.cpu_count() or 1
    rows = [
        ("gi (obvhs CWBVH, rayon)", n / t_gi, threads, build_gi),
        ("Embree 4 (embreex, 1 thread)", n / t_em, 1, build_embree),
    ]
    lines = [
        "# Incoherent closest-hit rays: gi (obvhs) vs Embree",
        "",
        f"Command: `.venv/bin/python scripts/bench/bench_embree.py` · {len(faces):,} triangles · "
        f"{n:,} rays (origins uniform in the box, directions uniform) · best of 5 · "
        f"{platform.processor() or platform.machine()}, {threads} cores · "
        f"hit distances agree on {agree * 100:.3f}% of rays hit by both.",
        "",
        "| tracer | Mrays/s | threads | Mrays/s per thread | build (s) |",
        "|---|---|---|---|---|",
    ]
    for name, rate, th, build in rows:
        lines.append(f"| {name} | {rate / 1e6:.2f} | {th} | {rate / th / 1e6:.2f} | {build:.3f} |")
    ratio = (n / t_gi / threads) / (n / t_em)
    lines += ["", f"Per-thread ratio gi / Embree: **{ratio:.2f}**", ""]
    out = Path(__file__).resolve().parents[2] / "docs" / "bench" / "embree.md"
    out.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
