"""Resident memory of the large instanced forest of `scripts/data/scale_scenes.py` (issue 33): the
forest as written (2,500 trees placing 50 tree meshes: ~13M placed triangles, 262k unique)
against the same forest with every tree its own mesh (each object naming its own copy of
its tree's file: nothing shared, as before instancing), each loaded and rendered once with
`path` (CPU BVH) and once with `direct` (GPU geometry; on lavapipe the GPU's buffers are
process memory, so the resident set counts them too), in its own process.

    python scripts/bench/bench_forest_memory.py [--trees N] [--variants U] [--out FILE]

Prints a Markdown table (peak resident set, VmHWM, and growth over the interpreter with gi
imported) and writes it to `--out` when given.
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

CHILD = r"""
import sys, gi
def kib(key):
    for line in open("/proc/self/status"):
        if line.startswith(key):
            return int(line.split()[1])
base = kib("VmRSS:")
scene = gi.load_scene(sys.argv[1])
gi.render(scene, sys.argv[2], spp=1, size=(64, 48))
print(scene.triangle_count, scene.unique_triangle_count, base, kib("VmRSS:"), kib("VmHWM:"))
"""


def unshared(forest: Path, out: Path) -> Path:
    """The forest with every tree naming its own copy of its mesh file."""
    desc = json.loads(forest.read_text())
    (out / "copies").mkdir()
    for i, o in enumerate(desc["objects"]):
        shape = o["shape"]
        if shape.get("type") == "mesh":
            copy = out / "copies" / f"tree{i}.obj"
            shutil.copyfile(forest.parent / shape["file"], copy)
            shape["file"] = str(copy)
    path = out / "forest-unshared.json"
    path.write_text(json.dumps(desc))
    return path


def measure(scene: Path, method: str) -> tuple[int, int, float, float] | str:
    """(placed triangles, unique triangles, peak growth MiB, peak MiB), or the error's last
    line when the render is refused."""
    run = subprocess.run(
        [sys.executable, "-c", CHILD, str(scene), method],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONWARNINGS": "ignore"},
    )
    if run.returncode != 0:
        return run.stderr.strip().splitlines()[-1]
    placed, unique, base, _, hwm = (int(x) for x in run.stdout.split()[-5:])
    return placed, unique, (hwm - base) / 1024, hwm / 1024


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trees", type=int, default=2500)
    ap.add_argument("--variants", type=int, default=50)
    ap.add_argument("--out", type=Path)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        subprocess.run(
            [sys.executable, str(ROOT / "scripts" / "scale_scenes.py"), str(tmp),
             "--trees", str(args.trees), "--variants", str(args.variants), "--grid", "4"],
            check=True, capture_output=True,
        )  # fmt: skip
        scenes = {"instanced": tmp / "forest.json", "every tree its own mesh": None}
        scenes["every tree its own mesh"] = unshared(scenes["instanced"], tmp)
        rows = []
        for method in ("path", "direct"):
            for name, scene in scenes.items():
                rows.append((method, name, measure(scene, method)))
    lines = [
        "| method | forest | placed triangles | unique triangles | peak growth MiB "
        "| peak MiB | instanced / unshared growth |",
        "|---|---|---:|---:|---:|---:|---:|",
    ]
    for i, (method, name, m) in enumerate(rows):
        if isinstance(m, str):
            lines.append(f"| `{method}` | {name} | | | refused: {m} | | |")
            continue
        other = rows[i + 1][2] if i % 2 == 0 else None
        share = f"{m[2] / other[2]:.1%}" if isinstance(other, tuple) else ""
        lines.append(
            f"| `{method}` | {name} | {m[0]:,} | {m[1]:,} | {m[2]:.0f} | {m[3]:.0f} | {share} |"
        )
    table = "\n".join(lines)
    print(table)
    if args.out:
        args.out.write_text(table + "\n")


if __name__ == "__main__":
    main()
