#!/usr/bin/env python3
"""Cold compile of `bidir`'s lighting pipeline, build against build, in one session.

For each gi build (a folder holding the `gi` package and its extension, e.g. main's
`python/` and this worktree's), a fresh process with Mesa's shader cache off
(`MESA_SHADER_CACHE_DISABLE=true`) renders one small `bidir` frame of a scene twice: the
first frame makes every pipeline cold (the lighting pass's with the exact models' code where
the scene has one of Mitsuba's models: `raster/vpl.rs`), the second reuses them. The first
frame's CPU time (the process's, all threads: lavapipe compiles in it) less the second's is
the frames' pipeline cost; the builds' difference on the same scene is the change's. CPU
time, not wall time: on a shared machine a niced process gets a fraction of a core (wall
times are also printed). Prints one JSON line per build and scene.

    scripts/probe/bidir_compile.py --builds /work/main/python python --scenes models plain
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# `models`: a spot light on a rough-plastic wall (one of Mitsuba's models) lighting a
# diffuse floor (tests/test_bidir_models.py); `plain`: the built-in `cornell` (no model).
CHILD = """
import sys, time, warnings, json, resource
sys.path.insert(0, {tests!r})
import gi
warnings.simplefilter("ignore")
if {scene!r} == "plain":
    scene = gi.load_scene("cornell")
else:
    from pathlib import Path
    import test_bidir_models as t
    tmp = Path({tmp!r})
    tmp.mkdir(exist_ok=True)
    scene = t.wall_scene(tmp, "roughplastic-beckmann")
r = gi.Renderer(scene, "bidir", size=(16, 16), seed=1)
def cpu():
    u = resource.getrusage(resource.RUSAGE_SELF)
    return u.ru_utime + u.ru_stime
out = {{"cpu_s": [], "wall_s": []}}
for _ in range(3):
    t0, c0 = time.perf_counter(), cpu()
    r.render()
    out["cpu_s"].append(round(cpu() - c0, 1))
    out["wall_s"].append(round(time.perf_counter() - t0, 1))
print(json.dumps(out))
"""


def measure(build: str, scene: str) -> dict:
    env = dict(os.environ, MESA_SHADER_CACHE_DISABLE="true", PYTHONPATH=build)
    code = CHILD.format(tests=str(ROOT / "tests"), scene=scene, tmp="/tmp/bidir_compile")
    out = subprocess.run(
        [sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True
    )
    row = json.loads(out.stdout.strip().splitlines()[-1])
    return {"build": build, "scene": scene, **row, "load": round(os.getloadavg()[0], 1)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--builds", nargs="+", required=True)
    ap.add_argument("--scenes", nargs="+", default=["models", "plain"])
    args = ap.parse_args()
    for scene in args.scenes:
        for build in args.builds:
            print(json.dumps(measure(build, scene)), flush=True)


if __name__ == "__main__":
    main()
