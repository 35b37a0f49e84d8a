#!/usr/bin/env python3
"""gi's methods on the committed third-party Mitsuba scenes against Mitsuba 3's references
(`tests/scenes/third_party/*/reference.exr`, `scripts/data/mitsuba_third_party.py`): per
scene and method the ratio of the image means per channel, HDR-FLIP and the render time, at
the reference's size, written to `docs/bench/real-scenes.md`.

    DRJIT_LIBLLVM_PATH=.../libLLVM-19.so .venv/bin/python scripts/bench/real_scenes.py \
        [--scenes cbox ...] [--methods path ...] [--mitsuba-flip] [--reuse-gi] [--keep-others]

With `--mitsuba-flip` (needs the `mitsuba` package), every row also gives the FLIP of
Mitsuba's own path tracer (`llvm_ad_rgb`, another seed) against its reference at equal
time (the spp its reference render reaches in gi's time: 4096 · gi's seconds / the
reference's seconds, JIT included) and, for `path`, at gi's spp. `--reuse-gi` takes gi's
columns of the selected rows from the table as it is (only Mitsuba's are measured: gi's
time is the one of the run that made them); `--keep-others` keeps the table's rows that are
not selected (with their Mitsuba columns).

Every method traces to gi's max_depth 64 (Mitsuba's 65 path segments); `direct` renders
direct light only and is left out (the references hold all bounces).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import re
import sys
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "scripts"))
from shared import flip  # noqa: E402

import gi  # noqa: E402

THIRD_PARTY = ROOT / "tests" / "scenes" / "third_party"
TABLE = ROOT / "docs" / "bench" / "real-scenes.md"
FILES = {"veach-mis": "scene.xml", "cornell-box": "scene.xml", "cbox": "cbox.xml"}
SETTINGS = {
    "path": {"spp": 256},
    "photon": {"photons": 1_000_000, "spp": 16},
    "gather": {"photons": 500_000, "spp": 16},
    "ispm": {"photons": 500_000, "spp": 16},
    "bidir": {"spp": 16, "progressive": True, "passes": 16},
}


def mitsuba_flip(name: str, spp: int) -> float:
    """FLIP of Mitsuba's render at `spp` (seed 99) against its 4096-spp reference."""
    sys.path.insert(0, str(ROOT / "scripts" / "data"))
    import mitsuba as mi
    from mitsuba_third_party import mitsuba_copy

    mi.set_variant("llvm_ad_rgb")
    d = THIRD_PARTY / name
    ref = gi.read_image(d / "reference.exr")[..., :3]
    h, w = ref.shape[:2]
    scene = mi.load_string(mitsuba_copy(d / FILES[name], w, h, spp, seed=99))
    img = np.array(mi.render(scene, spp=spp, seed=99), np.float32)[..., :3]
    return round(flip(ref, img), 4)


def with_mitsuba_columns(row: dict) -> dict:
    """`row` with Mitsuba's FLIP at equal spp (`path`) and at equal time."""
    name, method = row["scene"], row["method"]
    equal_spp = max(1, round(row["mitsuba_spp"] * row["seconds"] / row["mitsuba_seconds"]))
    own = SETTINGS[method]["spp"] if method == "path" else None
    return {
        **row,
        "mitsuba_flip": mitsuba_flip(name, own) if own else None,
        "mitsuba_equal_time": mitsuba_flip(name, equal_spp),
        "mitsuba_equal_spp": equal_spp,
    }


def table_rows(text: str) -> dict[tuple[str, str], dict]:
    """The rows of a table `table` wrote, by (scene, method)."""
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) < 10 or cells[0] not in FILES or cells[1] not in SETTINGS:
            continue
        number = lambda c: None if c in ("–", "-") else float(c.split()[0])  # noqa: E731
        spp = re.search(r"\((\d+) spp\)", cells[6])
        rows[(cells[0], cells[1])] = {
            "scene": cells[0],
            "method": cells[1],
            "settings": SETTINGS[cells[1]],
            "ratio": [float(x) for x in cells[3].split(",")],
            "flip": float(cells[4]),
            "mitsuba_flip": number(cells[5]),
            "mitsuba_equal_time": number(cells[6]),
            "mitsuba_equal_spp": int(spp.group(1)) if spp else None,
            "seconds": float(cells[-3]),
            "mitsuba_seconds": float(cells[-2]),
            "mitsuba_spp": 4096,
            "warnings": int(cells[-1]),
        }
    return rows


def run(name: str, method: str, with_mitsuba: bool) -> dict:
    d = THIRD_PARTY / name
    ref = gi.read_image(d / "reference.exr")[..., :3]
    meta = json.loads((d / "reference.json").read_text())
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        scene = gi.load_scene(d / FILES[name])
        settings = dict(SETTINGS[method])
        passes = settings.pop("passes", None)
        h, w = ref.shape[:2]
        t = time.perf_counter()
        r = gi.Renderer(scene, method, size=(w, h), seed=7, max_depth=64, **settings)
        img = (r.render_progressive(passes=passes) if passes else r.render()).radiance
        seconds = time.perf_counter() - t
    ratio = img.mean(axis=(0, 1)) / ref.mean(axis=(0, 1))
    row = {
        "scene": name,
        "method": method,
        "settings": SETTINGS[method],
        "ratio": [round(float(x), 4) for x in ratio],
        "flip": round(flip(ref, img), 4),
        "seconds": round(seconds, 1),
        "mitsuba_seconds": meta["seconds"],
        "mitsuba_spp": meta["spp"],
        "warnings": len({str(c.message) for c in caught}),
        "mitsuba_flip": None,
        "mitsuba_equal_time": None,
        "mitsuba_equal_spp": None,
    }
    return with_mitsuba_columns(row) if with_mitsuba else row


def table(rows: list[dict], command: str, run: str) -> str:
    """The markdown table of `rows`; `run`: the size, wall time and load it ran at."""
    out = [
        "# gi on published Mitsuba scenes",
        "",
        "Per committed third-party scene (`tests/scenes/third_party/`, loaded untouched) and",
        "method: gi's image mean over Mitsuba 3's per channel (R, G, B), HDR-FLIP against the",
        "reference, and gi's render time at the reference's size. Mitsuba's references: "
        f"{rows[0]['mitsuba_spp']} spp,",
        "`llvm_ad_rgb`, box filter, max_depth 65 (gi's 64), on the same machine (their time is",
        "a converged render's, not an equal-time one). `warnings`: distinct warnings at load and",
        "at the renderer's creation (AssetWarning, RenderWarning: e.g. `bidir`'s uber stand-ins",
        "for Mitsuba's exact models in its VPLs and bundles, before issue 42's `mitsuba4`).",
        "Mitsuba's FLIP at equal time: its own path tracer (`llvm_ad_rgb`, seed 99) at the spp",
        "its reference render reaches in gi's time (4096 · gi s / Mitsuba s), against the",
        "reference; at equal spp (`path`): at gi's 256 spp. A FLIP near 0.02 at thousands of",
        "spp is the two renders' own noise: Mitsuba's path tracer converges faster than any",
        "of gi's methods on these scenes at equal time.",
        "",
        run,
        "",
        "| scene | method | settings | mean ratio (R, G, B) | FLIP | Mitsuba's FLIP at equal "
        "spp | Mitsuba's FLIP at equal time (its spp) | gi s | Mitsuba s (4096 spp) | warnings |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        settings = ", ".join(f"{k} {v}" for k, v in r["settings"].items())
        ratio = ", ".join(f"{x:.3f}" for x in r["ratio"])
        own = "–" if r.get("mitsuba_flip") is None else f"{r['mitsuba_flip']:.3f}"
        timed = "–"
        if r.get("mitsuba_equal_time") is not None:
            timed = f"{r['mitsuba_equal_time']:.3f} ({r['mitsuba_equal_spp']} spp)"
        out.append(
            f"| {r['scene']} | {r['method']} | {settings} | {ratio} | {r['flip']:.3f} | {own} | "
            f"{timed} | {r['seconds']} | {r['mitsuba_seconds']} | {r['warnings']} |"
        )
    out += [
        "",
        f"Command: `{command}` (gi {gi.__version__}, {platform.processor() or platform.machine()},"
        " GPU passes on Mesa lavapipe, 2 shared cores).",
        "",
    ]
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", nargs="*", default=list(FILES))
    ap.add_argument("--methods", nargs="*", default=list(SETTINGS))
    ap.add_argument("--mitsuba-flip", action="store_true")
    ap.add_argument("--reuse-gi", action="store_true")
    ap.add_argument("--keep-others", action="store_true")
    args = ap.parse_args()
    old = table_rows(TABLE.read_text()) if TABLE.exists() else {}
    rows = []
    start, load = time.perf_counter(), os.getloadavg()[0]
    for name in FILES:
        for method in SETTINGS:
            if name in args.scenes and method in args.methods:
                if args.reuse_gi:
                    row = with_mitsuba_columns(old[(name, method)])
                else:
                    row = run(name, method, args.mitsuba_flip)
            elif args.keep_others and (name, method) in old:
                row = old[(name, method)]
            else:
                continue
            rows.append(row)
            print(json.dumps(row), flush=True)
    sizes = ", ".join(
        f"{n} {'×'.join(map(str, gi.read_image(THIRD_PARTY / n / 'reference.exr').shape[1::-1]))}"
        for n in args.scenes
    )
    selected = f"scenes {', '.join(args.scenes)}; methods {', '.join(args.methods)}"
    measured = "Mitsuba's columns only, gi's reused" if args.reuse_gi else "gi's columns"
    header = (
        f"This run ({selected}: {measured}): at the references' sizes ({sizes}), "
        f"{time.perf_counter() - start:.0f} s in all, load average {load:.1f} at its start "
        "(times are those of a loaded machine)."
        + ("" if args.mitsuba_flip else " Mitsuba's FLIP columns not measured (`--mitsuba-flip`).")
    )
    if (args.reuse_gi or args.keep_others) and TABLE.exists():
        earlier = re.search(r"^This run.*?(?=\n\n)", TABLE.read_text(), re.S | re.M)
        if earlier:
            before = earlier.group(0)[9:].lstrip(" :")
            header += "\n\nThe run before (its rows and gi's columns kept): " + before
    command = " ".join(["scripts/bench/real_scenes.py", *sys.argv[1:]])
    TABLE.write_text(table(rows, command, header))
    print(f"wrote {TABLE}")


if __name__ == "__main__":
    main()
