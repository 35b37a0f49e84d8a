"""Renders the single-material spheres of tests/scenes/materials with gi's methods and
writes docs/bench/materials.md: per sphere and method, the image mean's ratio to Mitsuba's
reference per channel, the mean HDR-FLIP and the render time.

Run: /work/wt/dev.sh python scripts/probe/materials_vs_mitsuba.py [--methods path,photon]
(python/ and scripts/ on the path, as dev.sh sets them)."""

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from shared import flip  # noqa: E402

import gi  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "tests" / "scenes" / "materials"
SETTINGS = {
    "path": {"spp": 256},
    "photon": {"photons": 200_000, "spp": 16},
    "gather": {"photons": 200_000, "spp": 16},
    "ispm": {"photons": 200_000, "spp": 16},
    "bidir": {"spp": 16},
    "direct": {"spp": 16},
}


def reference(name: str, method: str) -> np.ndarray:
    """Mitsuba's image to compare `method` with: its `direct` integrator's for `direct`
    (the committed image where it differs from `path`'s: the spheres on a floor)."""
    direct = SCENES / f"{name}-direct-reference.exr"
    path = direct if method == "direct" and direct.exists() else SCENES / f"{name}-reference.exr"
    return gi.read_image(path)[..., :3]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--methods", default=",".join(SETTINGS))
    ap.add_argument("--out", default=str(ROOT / "docs" / "bench" / "materials.md"))
    args = ap.parse_args()
    meta = json.loads((SCENES / "references.json").read_text())
    rows = []
    for name in sorted(meta):
        scene = gi.load_scene(SCENES / f"{name}.xml")
        for method in args.methods.split(","):
            ref = reference(name, method)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                r = gi.Renderer(scene, method, size=(64, 64), seed=7, **SETTINGS[method])
            t0 = time.perf_counter()
            img = r.render().radiance[..., :3]
            dt = time.perf_counter() - t0
            ratio = img.reshape(-1, 3).mean(0) / ref.reshape(-1, 3).mean(0)
            rows.append((name, method, ratio, flip(ref, img), dt))
            print(name, method, np.round(ratio, 4), round(rows[-1][3], 4), f"{dt:.2f} s")
    lines = [
        "# Mitsuba's materials: gi against Mitsuba 3.9.1",
        "",
        "Single-material spheres of `tests/scenes/materials/` (64×64, a constant environment",
        "and a small area light, the rough glass on a grey floor; references: Mitsuba `path`,",
        "4096 spp, box filter; `direct` against Mitsuba's `direct` integrator, 1024 spp).",
        "Ratio: gi's image mean over Mitsuba's per channel (R, G, B). The GPU direct light and",
        "`ispm`'s estimates and first bounce shade the exact models, `bidir`'s VPLs and bundles",
        "uber stand-ins; `direct` adds the light met one delta scattering from the camera and",
        "rough glass's lobes on the CPU; `bidir` renders rough glass as smooth glass",
        "(docs/scene-format.md). Settings: " + ", ".join(f"`{m}` {s}" for m, s in SETTINGS.items()),
        "",
        "Command: `/work/wt/dev.sh python scripts/probe/materials_vs_mitsuba.py` (lavapipe).",
        "",
        "| sphere | method | ratio R | ratio G | ratio B | FLIP | time (s) |",
        "|---|---|---|---|---|---|---|",
    ]
    for name, method, ratio, err, dt in rows:
        r = " | ".join(f"{x:.4f}" for x in ratio)
        lines.append(f"| {name} | {method} | {r} | {err:.4f} | {dt:.2f} |")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print("wrote", args.out)


if __name__ == "__main__":
    main()
