"""One `bidir` frame's image mean from seed to seed (issue 48) on the built-in `cornell`,
Mitsuba 3's `cbox` and mitsuba.cornell_box(), 48×48 at the defaults, for one or more builds
(each in its own process, `--build LABEL=PYTHONPATH`): the spread (max − min over the
mean) of seeds 1–4, of 1–8 (the test's) and of 1–N, and σ over N seeds. Prints a Markdown
table; with `--per-seed`, a second table of each seed's image mean.

    python scripts/probe/bidir_spread.py [--seeds 16] [--build LABEL=PYTHONPATH ...]
        [--set vpls_per_light=128 ...] [--per-seed]
"""

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
BOXES = {
    "cornell": "cornell",
    "cbox": str(ROOT / "tests/scenes/third_party/cbox/cbox.xml"),
    "cornell_box()": str(ROOT / "docs/scenes/cornell-box/cornell-box.xml"),
}


def means(seeds: int, settings: dict) -> dict:
    import gi

    out = {}
    for name, path in BOXES.items():
        scene = gi.load_scene(path)
        out[name] = [
            float(gi.render(scene, "bidir", size=(48, 48), seed=s, **settings).radiance.mean())
            for s in range(1, seeds + 1)
        ]
    return out


def setting(text: str) -> tuple:
    """`key=value` of `--set`, the value an int where it reads as one."""
    key, value = text.split("=", 1)
    return key, int(value) if value.lstrip("-").isdigit() else value


def spread(m: np.ndarray) -> float:
    """max − min over the mean."""
    return float((m.max() - m.min()) / m.mean())


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--build", action="append", default=[], help="LABEL=PYTHONPATH")
    ap.add_argument("--set", action="append", default=[], help="KEY=VALUE render setting")
    ap.add_argument("--per-seed", action="store_true", help="also print each seed's mean")
    ap.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.child:
        print(json.dumps(means(a.seeds, dict(setting(t) for t in a.set))))
        return
    builds = [b.split("=", 1) for b in a.build] or [["this", os.pathsep.join(sys.path)]]
    print(f"| build | scene | seeds 1–4 spread | seeds 1–8 spread | seeds 1–{a.seeds} spread | σ |")
    print("|---|---|---|---|---|---|")
    rows = []
    for label, path in builds:
        cmd = [sys.executable, __file__, "--child", "--seeds", str(a.seeds)]
        cmd += [f"--set={t}" for t in a.set]
        env = {**os.environ, "PYTHONPATH": path}
        run = subprocess.run(cmd, env=env, check=True, capture_output=True, text=True)
        got = json.loads(run.stdout.splitlines()[-1])
        for name, m in got.items():
            m = np.array(m)
            sp4, sp8, sp = (spread(m[:k]) for k in (4, 8, len(m)))
            sd = m.std(ddof=1) / m.mean()
            print(f"| {label} | {name} | {sp4:.1%} | {sp8:.1%} | {sp:.1%} | {sd:.2%} |", flush=True)
            rows.append((label, name, m))
    if a.per_seed:
        print(f"\n| build | scene | image mean, seeds 1–{a.seeds} |\n|---|---|---|")
        for label, name, m in rows:
            print(f"| {label} | {name} | {' '.join(f'{x:.4f}' for x in m)} |")


if __name__ == "__main__":
    main()
