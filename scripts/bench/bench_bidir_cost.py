"""Cost of one `bidir` frame (issue 48): the frame's wall time and its two largest stages
("bidir lighting", the lighting pass; "vpl shadow maps", the VPLs' cube maps), median of
warm frames of a `gi.Renderer` (new seed each frame), for one or more builds run in turn
(rounds alternate between the builds, so that the machine's load falls on each alike).
Prints a Markdown table (`docs/bench/bidir-depth.md`, "Cost").

    python scripts/bench/bench_bidir_cost.py [--build LABEL=PYTHONPATH ...] [--rounds 3]
        [--frames 3] [--size 128] [--scene cornell]

Without --build the current `gi` is measured (label "this").
"""

import argparse
import json
import os
import re
import statistics
import subprocess
import sys

STAGES = ("bidir lighting", "vpl shadow maps", "light subpaths")


def measure(scene: str, size: int, frames: int, first_seed: int) -> dict:
    """One round in this process: `frames` warm frames (after one not counted)."""
    import time

    import gi

    r = gi.Renderer(scene, "bidir", size=(size, size))
    r.render(seed=first_seed)
    out: dict = {"frame": [], **{s: [] for s in STAGES}}
    for k in range(frames):
        t = time.perf_counter()
        res = r.render(seed=first_seed + 1 + k)
        out["frame"].append(time.perf_counter() - t)
        text = repr(res.stats)
        for s in STAGES:
            m = re.search(re.escape(s) + r" ([0-9.]+)s", text)
            out[s].append(float(m.group(1)) if m else 0.0)
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--build", action="append", default=[], help="LABEL=PYTHONPATH")
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--scene", default="cornell")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    ap.add_argument("--seed", type=int, default=1, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        print(json.dumps(measure(a.scene, a.size, a.frames, a.seed)))
        return
    builds = [b.split("=", 1) for b in a.build] or [["this", os.pathsep.join(sys.path)]]
    results = {label: {} for label, _ in builds}
    for rnd in range(a.rounds):
        for label, path in builds:
            cmd = [sys.executable, __file__, "--child", "--scene", a.scene]
            cmd += ["--size", str(a.size), "--frames", str(a.frames), "--seed", str(1 + 10 * rnd)]
            env = {**os.environ, "PYTHONPATH": path}
            got = json.loads(
                subprocess.run(
                    cmd, env=env, check=True, capture_output=True, text=True
                ).stdout.splitlines()[-1]
            )
            for k, v in got.items():
                results[label].setdefault(k, []).extend(v)
    print(f"`{a.scene}` {a.size}², {a.rounds} rounds × {a.frames} warm frames, medians (s):\n")
    print("| build | frame | " + " | ".join(STAGES) + " |")
    print("|---|---|" + "---|" * len(STAGES))
    for label, r in results.items():
        cells = [f"{statistics.median(r[k]):.3f}" for k in ("frame", *STAGES)]
        print(f"| {label} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
