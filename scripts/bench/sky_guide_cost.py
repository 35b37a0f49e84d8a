"""What an `ispm` frame whose photons are traced anew costs with the sky's aimed photons
(photon/sky_guide.rs), against other builds in the same run: each build (``--build
NAME=DIR``, DIR a ``python/`` directory holding a built ``gi``) renders single frames of
seeds 1..N with ``gi.render`` (a new photon trace each: pilot, plain and aimed photons) in
its own worker process after one warm-up frame, the builds alternating round by round.
Prints the median frame and stage times (ms), a Markdown table for
``docs/bench/sky-openings.md``.

``--renderer``: the frames of one ``gi.Renderer`` instead, each with its own seed (so every
frame traces its photons anew, as a light or sky animation does, while a build that keeps
the sky's pilot keeps it). ``--move camera``: the camera moves a little every frame and the
seed stays (photons kept: the estimate alone).

    python scripts/bench/sky_guide_cost.py --build main=/tmp/main/python --build new=python \\
        [--scene tests/scenes/openings/window_room.json] [--size 96x72] [--rounds 3] \\
        [--renderer] [--move camera]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

STAGES = ("sky pilot", "cpu trace", "cpu estimate", "direct light", "readback")


def worker(a: argparse.Namespace, first_seed: int) -> None:
    import warnings

    import gi

    warnings.simplefilter("ignore", gi.RenderWarning)
    w, h = (int(v) for v in a.size.split("x"))
    scene = gi.load_scene(a.scene)
    options = {"photons": a.photons} if a.photons else {}
    gi.render(scene, "ispm", size=(w, h), seed=99, **options)
    r = gi.Renderer(scene, "ispm", size=(w, h), seed=first_seed, **options)
    if a.renderer or a.move:
        r.render(seed=99 if a.renderer else None)
    p0 = r.describe("camera")["position"]
    frames = []
    for i, s in enumerate(range(first_seed, first_seed + a.frames)):
        t = time.perf_counter()
        if a.move == "camera":
            r.update(camera={"position": [p0[0], p0[1] + 0.01 * (i % 8), p0[2]]})
            out = r.render()
        elif a.renderer:
            out = r.render(seed=s)
        else:
            out = gi.render(scene, "ispm", size=(w, h), seed=s, **options)
        stages: dict[str, float] = {}
        for name, v in out.stats.stages:
            stages[name] = stages.get(name, 0.0) + v
        frames.append({"frame": time.perf_counter() - t, "stages": stages})
    print(json.dumps(frames))


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--build", action="append", default=[], help="NAME=DIR (repeat)")
    p.add_argument("--scene", default="tests/scenes/openings/window_room.json")
    p.add_argument("--size", default="96x72")
    p.add_argument("--photons", type=int, default=0, help="0: the default")
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--frames", type=int, default=2, help="frames per round")
    p.add_argument("--renderer", action="store_true", help="one Renderer, a seed a frame")
    p.add_argument("--move", default="", help="camera: move it, photons kept")
    p.add_argument("--worker", type=int, default=0, help=argparse.SUPPRESS)
    a = p.parse_args()
    if a.worker:
        worker(a, a.worker)
        return
    builds = dict(b.split("=", 1) for b in a.build)
    got: dict[str, list] = {k: [] for k in builds}
    for r in range(a.rounds):
        for k, path in builds.items():
            cmd = [sys.executable, __file__, "--worker", str(1 + r * a.frames)]
            cmd += ["--scene", a.scene, "--size", a.size, "--photons", str(a.photons)]
            cmd += ["--frames", str(a.frames), "--move", a.move]
            cmd += ["--renderer"] if a.renderer else []
            env = dict(os.environ, PYTHONPATH=path)
            out = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
            got[k] += json.loads(out.stdout.strip().splitlines()[-1])
    n = a.rounds * a.frames
    photons = a.photons or "default"
    how = {
        "camera": "camera moving (photons kept)",
        "": "one Renderer, new seed a frame" if a.renderer else "gi.render a frame",
    }[a.move]
    print(f"{a.scene} {a.size}, ispm, {photons} photons, {how}; median of {n}")
    print("| build | frame | " + " | ".join(STAGES) + " |")
    print("|---|---:|" + "---:|" * len(STAGES))
    for k in builds:
        f = [x["frame"] for x in got[k]]
        cells = [statistics.median(x["stages"].get(s, 0.0) for x in got[k]) for s in STAGES]
        row = f"| {k} | {statistics.median(f) * 1e3:.0f} ({min(f) * 1e3:.0f}–{max(f) * 1e3:.0f}) | "
        print(row + " | ".join(f"{c * 1e3:.1f}" for c in cells) + " |")


if __name__ == "__main__":
    main()
