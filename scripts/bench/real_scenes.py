#!/usr/bin/env python3
"""gi's methods on the committed third-party Mitsuba scenes against Mitsuba 3's references
(`tests/scenes/third_party/*/reference.exr`, `scripts/data/mitsuba_third_party.py`): per
scene and method the ratio of the image means per channel, HDR-FLIP and the render time, at
the reference's size, written to `docs/bench/real-scenes.md`.

    DRJIT_LIBLLVM_PATH=.../libLLVM-19.so .venv/bin/python scripts/bench/real_scenes.py \
        [--scenes cbox ...] [--methods path ...] [--mitsuba-flip]

With `--mitsuba-flip` (needs the `mitsuba` package), every row also gives the FLIP of
Mitsuba's own path tracer (`llvm_ad_rgb`, another seed) against its reference at equal
time (the spp its reference render reaches in gi's time: 4096 · gi's seconds / the
reference's seconds, JIT included) and, for `path`, at gi's spp.

Every method traces to gi's max_depth 64 (Mitsuba's 65 path segments); `direct` renders
direct light only and is left out (the references hold all bounces).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
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
    return {
        "scene": name,
        "method": method,
        "settings": SETTINGS[method],
        "ratio": [round(float(x), 4) for x in ratio],
        "flip": round(flip(ref, img), 4),
        "seconds": round(seconds, 1),
        "mitsuba_seconds": meta["seconds"],
        "mitsuba_spp": meta["spp"],
        "warnings": len({str(c.message) for c in caught}),
        "mitsuba_flip": mitsuba_flip(name, SETTINGS[method]["spp"])
        if with_mitsuba and method == "path"
        else None,
        "mitsuba_equal_time": mitsuba_flip(name, equal_spp)
        if with_mitsuba and (equal_spp := max(1, round(4096 * seconds / meta["seconds"])))
        else None,
    }


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
        "for Mitsuba's exact models in its VPLs and bundles).",
        "",
        run,
        "",
        "| scene | method | settings | mean ratio (R, G, B) | FLIP | Mitsuba's FLIP at equal "
        "spp | Mitsuba's FLIP at equal time | gi s | Mitsuba s (4096 spp) | warnings |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        settings = ", ".join(f"{k} {v}" for k, v in r["settings"].items())
        ratio = ", ".join(f"{x:.3f}" for x in r["ratio"])
        own = "–" if r.get("mitsuba_flip") is None else f"{r['mitsuba_flip']:.3f}"
        timed = "–" if r.get("mitsuba_equal_time") is None else f"{r['mitsuba_equal_time']:.3f}"
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
    args = ap.parse_args()
    rows = []
    start, load = time.perf_counter(), os.getloadavg()[0]
    for name in args.scenes:
        for method in args.methods:
            rows.append(run(name, method, args.mitsuba_flip))
            print(json.dumps(rows[-1]), flush=True)
    sizes = ", ".join(
        f"{n} {'×'.join(map(str, gi.read_image(THIRD_PARTY / n / 'reference.exr').shape[1::-1]))}"
        for n in args.scenes
    )
    header = (
        f"This run: at the references' sizes ({sizes}), {time.perf_counter() - start:.0f} s "
        f"in all, load average {load:.1f} at its start (times are those of a loaded machine)."
        + ("" if args.mitsuba_flip else " Mitsuba's FLIP columns not measured (`--mitsuba-flip`).")
    )
    command = " ".join(["scripts/bench/real_scenes.py", *sys.argv[1:]])
    TABLE.write_text(table(rows, command, header))
    print(f"wrote {TABLE}")


if __name__ == "__main__":
    main()
