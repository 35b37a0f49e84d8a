"""What a point-lit scene pays for the GPU direct light of many kinds of light: builds of
gi (``--build NAME=DIR``, DIR a ``python/`` directory holding a built ``gi`` package)
render the same frames in one run, alternating round by round (the order rotating), each
in its own worker process, the scene's first light moving every frame (so shadows and
direct light are redrawn). Prints the median frame time and median per-stage times of each
build, a Markdown table for ``docs/bench/lights-gpu.md``.

    python scripts/bench/lights_cost.py --build old=/tmp/old/python --build new=python \\
        [--scene cornell] [--size 640x480] [--photons 20000] [--rounds 8] [--frames 4] \\
        [--method ispm] [--move light|camera] [--option sky_samples=64 ...]

On a machine shared with builds, ``chrt -f 50`` before it (as root) runs the workers and
lavapipe's threads ahead of the other work, so that the frames measure the renderer rather
than the load.

``--move camera`` moves the camera instead (scenes lit by emitters alone, e.g. a scene
file such as veach-mis: G-buffer, edges and direct light redone each frame).

The machine may be shared: alternating rounds give the builds the same load, and the
medians leave out the rounds a burst of other work slowed. ``CPU`` is the worker's CPU time
a frame (user + system, every thread: lavapipe's too), which a loaded machine changes far
less than the wall time.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time

# `photon upload` waited for the GPU work queued before it up to 0e18125; later builds wait
# in `readback`.
STAGES = ("direct light", "edge shading", "shadow maps", "photon upload", "readback")


def worker(a: argparse.Namespace) -> None:
    """Reads a frame count per line, renders that many frames and answers a JSON line."""
    import warnings

    import gi

    # Builds older than the RenderWarning category warn with a plain UserWarning.
    warnings.simplefilter("ignore", getattr(gi, "RenderWarning", UserWarning))
    w, h = (int(v) for v in a.size.split("x"))
    options = {"photons": a.photons} if a.method == "ispm" else {}
    options.update(json.loads(a.options))
    r = gi.Renderer(gi.load_scene(a.scene), a.method, size=(w, h), **options)
    target = "camera" if a.move == "camera" else "light"
    p0 = r.describe(target, None if target == "camera" else 0)["position"]
    r.render()
    i = 0
    for line in sys.stdin:
        frames = []
        for _ in range(int(line)):
            i += 1
            dx = 0.02 * ((i % 10) - 5)
            moved = {"position": [p0[0] + dx, p0[1], p0[2]]}
            if target == "camera":
                r.update(camera=moved)
            else:
                r.update(lights={0: moved})
            u = resource.getrusage(resource.RUSAGE_SELF)
            t = time.perf_counter()
            out = r.render()
            total = time.perf_counter() - t
            v = resource.getrusage(resource.RUSAGE_SELF)
            cpu = v.ru_utime - u.ru_utime + v.ru_stime - u.ru_stime
            stages: dict[str, float] = {}
            for name, s in out.stats.stages:
                stages[name] = stages.get(name, 0.0) + s
            frames.append({"frame": total, "cpu": cpu, "stages": stages})
        print(json.dumps(frames), flush=True)


def start(path: str, a: argparse.Namespace) -> subprocess.Popen[str]:
    env = dict(os.environ, PYTHONPATH=os.path.abspath(path))
    cmd = [sys.executable, __file__, "--worker", "--scene", a.scene, "--size", a.size]
    cmd += ["--photons", str(a.photons), "--method", a.method, "--move", a.move]
    cmd += ["--options", json.dumps(a.parsed)]
    return subprocess.Popen(cmd, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--build", action="append", default=[], help="NAME=DIR (repeat)")
    p.add_argument("--scene", default="cornell")
    p.add_argument("--size", default="640x480")
    p.add_argument("--photons", type=int, default=20_000)
    p.add_argument("--rounds", type=int, default=8)
    p.add_argument("--frames", type=int, default=4, help="frames per round")
    p.add_argument("--method", default="ispm")
    p.add_argument("--move", choices=["light", "camera"], default="light")
    p.add_argument("--option", action="append", default=[], help="KEY=INT for every build")
    p.add_argument(
        "--all-stages",
        action="store_true",
        help="a column for every stage any build times (else the direct light's five)",
    )
    p.add_argument("--options", default="{}", help=argparse.SUPPRESS)
    p.add_argument("--worker", action="store_true", help=argparse.SUPPRESS)
    a = p.parse_args()
    a.parsed = {k: int(v) for k, v in (o.split("=", 1) for o in a.option)}
    if a.worker:
        worker(a)
        return
    builds = {}
    for b in a.build:
        name, _, path = b.partition("=")
        builds[name] = start(path, a)
    names = list(builds)
    got: dict[str, list[dict]] = {k: [] for k in builds}
    for rnd in range(a.rounds):
        order = names[rnd % len(names) :] + names[: rnd % len(names)]
        for k in order:
            proc = builds[k]
            assert proc.stdin is not None and proc.stdout is not None
            proc.stdin.write(f"{a.frames}\n")
            proc.stdin.flush()
            line = proc.stdout.readline()
            if not line:
                sys.exit(f"the {k} build's worker ended early")
            got[k].extend(json.loads(line))
    for proc in builds.values():
        assert proc.stdin is not None
        proc.stdin.close()
        proc.wait()
    n = a.rounds * a.frames
    what = f"{a.method}, {a.photons} photons" if a.method == "ispm" else a.method
    print(f"{a.scene} {a.size}, {what}, {a.move} moving; median of {n} frames")
    print(f"a build each, {a.rounds} alternating rounds of {a.frames} frames (ms)\n")
    stages = list(STAGES)
    if a.all_stages:
        seen = {
            s: max(x["stages"][s] for k in got for x in got[k] if s in x["stages"])
            for s in {s for k in got for x in got[k] for s in x["stages"]}
        }
        stages = sorted(seen, key=lambda s: -seen[s])
    print("| build | frame | CPU | " + " | ".join(stages) + " |")
    print("|---|---:|---:|" + "---:|" * len(stages))
    for k in builds:
        f = [x["frame"] for x in got[k]]
        cells = [statistics.median(x["stages"].get(s, 0.0) for x in got[k]) for s in stages]
        lo, hi = min(f), max(f)
        cpu = statistics.median(x["cpu"] for x in got[k]) * 1e3
        row = f"| {k} | {statistics.median(f) * 1e3:.0f} ({lo * 1e3:.0f}–{hi * 1e3:.0f}) "
        row += f"| {cpu:.0f} | "
        print(row + " | ".join(f"{c * 1e3:.1f}" for c in cells) + " |")


if __name__ == "__main__":
    main()
