#!/usr/bin/env python3
"""Cold compile of the GPU direct light's pipelines, per build of gi (``--build NAME=DIR``,
DIR a ``python/`` directory holding a built ``gi`` package) and scene: each case in a fresh
process with Mesa's shader cache off (``MESA_SHADER_CACHE_DISABLE=true``), the first
`direct` frame (pipelines compiled on first use) minus the second (warm, another seed) at
48×48, in wall time and in the process's CPU time (every thread's: lavapipe compiles on
its own threads), which a machine loaded by other work changes far less. Rounds alternate
the builds so that they share the machine's load; prints every round and the medians as a
Markdown table.

    python scripts/probe/direct_compile.py --build main=/tmp/main/python --build new=python \\
        [--scene glossy-quad] [--scene cornell] \\
        [--scene tests/scenes/third_party/veach-mis/scene.xml]

``glossy-quad``: a GGX floor (roughness 0.3) under a one-sided emitting quad and a black
box (`crates/core/tests/gpu_ltc.rs`'s highlight scene): a glossy area-lit scene.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

GLOSSY_QUAD = {
    "camera": {"position": [0, 1.6, 3.0], "look_at": [0, 0.2, 0.5], "fov": 50},
    "materials": {
        "floor": {"diffuse": [0, 0, 0], "specular": [0.6, 0.6, 0.6], "roughness": 0.3},
        "black": {"diffuse": [0, 0, 0]},
        "light": {"diffuse": [0, 0, 0], "emission": [3, 2.5, 2]},
    },
    "objects": [
        {"shape": {"type": "quad", "size": [4, 4]}, "material": "floor"},
        {
            "shape": {"type": "box", "size": [0.5, 0.5, 0.5]},
            "material": "black",
            "transform": {"rotate": [0, 25, 0], "translate": [0.1, 0.25, 0]},
        },
        {
            "shape": {"type": "quad", "size": [1.2, 0.8]},
            "material": "light",
            "transform": {"rotate": [150, 0, 0], "translate": [-0.2, 1.4, -0.3]},
        },
    ],
}


def worker(scene: str) -> None:
    import warnings

    import gi

    warnings.simplefilter("ignore")
    s = gi.load_scene(scene)
    times, cpu = [], []
    for seed in (1, 2):
        u = resource.getrusage(resource.RUSAGE_SELF)
        t = time.perf_counter()
        gi.render(s, "direct", size=(48, 48), seed=seed)
        times.append(time.perf_counter() - t)
        v = resource.getrusage(resource.RUSAGE_SELF)
        cpu.append(v.ru_utime - u.ru_utime + v.ru_stime - u.ru_stime)
    print(json.dumps({"first": times[0], "warm": times[1], "cpu": cpu[0] - cpu[1]}))


def run(path: str, scene: str) -> dict:
    env = dict(os.environ, PYTHONPATH=os.path.abspath(path), MESA_SHADER_CACHE_DISABLE="true")
    out = subprocess.run(
        [sys.executable, __file__, "--worker", scene],
        env=env,
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--build", action="append", default=[], help="NAME=DIR (repeat)")
    p.add_argument("--scene", action="append", default=[], help="glossy-quad, a name or a file")
    p.add_argument("--rounds", type=int, default=2)
    p.add_argument("--worker", help=argparse.SUPPRESS)
    a = p.parse_args()
    if a.worker:
        worker(a.worker)
        return
    tmp = Path(tempfile.mkdtemp())
    (tmp / "glossy-quad.json").write_text(json.dumps(GLOSSY_QUAD))
    scenes = a.scene or ["glossy-quad", "cornell"]
    builds = [b.partition("=")[::2] for b in a.build]
    rows: dict[tuple[str, str], list[tuple[float, float]]] = {}
    for r in range(a.rounds):
        order = builds[r % len(builds) :] + builds[: r % len(builds)]
        for scene in scenes:
            file = str(tmp / "glossy-quad.json") if scene == "glossy-quad" else scene
            for name, path in order:
                t = run(path, file)
                cold = t["first"] - t["warm"]
                rows.setdefault((scene, name), []).append((cold, t["cpu"]))
                print(
                    f"round {r}: {scene} {name}: first {t['first']:.2f} s, warm {t['warm']:.2f} s,"
                    f" CPU first − warm {t['cpu']:.1f} s",
                    flush=True,
                )
    head = "| scene | build | wall, first − warm frame (s), per round | median |"
    head += " CPU s, per round | median |"
    print("\n" + head)
    print("|---|---|---|---:|---|---:|")
    for (scene, name), v in rows.items():
        wall, cpu = [x[0] for x in v], [x[1] for x in v]
        w = ", ".join(f"{x:.1f}" for x in wall)
        c = ", ".join(f"{x:.1f}" for x in cpu)
        print(
            f"| {Path(scene).stem} | {name} | {w} | {statistics.median(wall):.1f} | {c} |"
            f" {statistics.median(cpu):.1f} |"
        )


if __name__ == "__main__":
    main()
