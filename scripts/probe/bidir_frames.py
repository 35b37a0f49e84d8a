"""`bidir` one frame at a time (issues 42 and 48): per-seed image means and hot spots on the
Cornell boxes, Mitsuba's `cbox` over progressive passes, the material spheres against
Mitsuba. Writes nothing; prints the figures of `docs/bench/bidir-depth.md`.

    python scripts/probe/bidir_frames.py spread [--seeds 8]
    python scripts/probe/bidir_frames.py cbox
    python scripts/probe/bidir_frames.py spheres
"""

import argparse
import json
import warnings
from pathlib import Path

import numpy as np

import gi

ROOT = Path(__file__).resolve().parents[2]
BOXES = {
    "cornell": "cornell",
    "cbox": str(ROOT / "tests/scenes/third_party/cbox/cbox.xml"),
    "cornell_box()": str(ROOT / "docs/scenes/cornell-box/cornell-box.xml"),
}
SIZE = (48, 48)


def indirect(scene, method, **kw) -> np.ndarray:
    """The light past the direct light (depth 7 less depth 1, mean of RGB)."""
    full = gi.render(scene, method, size=SIZE, max_depth=7, **kw).radiance
    direct = gi.render(scene, method, size=SIZE, max_depth=1, **kw).radiance
    return (full - direct).mean(axis=2)


def spread(seeds: int) -> None:
    print(
        f"| scene | seeds 1–4 spread | seeds 1–{seeds} spread | σ |"
        " largest indirect pixel / path's |"
    )
    print("|---|---|---|---|---|")
    for name, path in BOXES.items():
        scene = gi.load_scene(path)
        ref = indirect(scene, "path", spp=1024, seed=5).max()
        means, peaks = [], []
        for s in range(1, seeds + 1):
            means.append(float(gi.render(scene, "bidir", size=SIZE, seed=s).radiance.mean()))
            peaks.append(float(indirect(scene, "bidir", seed=s).max() / ref))
        m = np.array(means)
        sp4 = (m[:4].max() - m[:4].min()) / m[:4].mean()
        sp = (m.max() - m.min()) / m.mean()
        print(
            f"| {name} | {sp4:.1%} | {sp:.1%} | {m.std(ddof=1) / m.mean():.1%} | "
            + " ".join(f"{p:.2f}" for p in peaks)
            + " |"
        )


def cbox() -> None:
    scene = gi.load_scene(BOXES["cbox"])
    ref = gi.read_image(ROOT / "tests/scenes/third_party/cbox/reference.exr")[..., :3]
    print("| size | max_depth | passes | mean / Mitsuba (RGB) |")
    print("|---|---|---|---|")
    for size in (64, 128):
        for depth in (1, 64):
            for passes in (1, 4, 16):
                r = gi.Renderer(
                    scene,
                    "bidir",
                    size=(size, size),
                    seed=7,
                    max_depth=depth,
                    spp=16,
                    progressive=True,
                )
                img = r.render_progressive(passes=passes).radiance
                ratio = img.mean(axis=(0, 1)) / ref.mean(axis=(0, 1))
                print(
                    f"| {size}² | {depth} | {passes} | "
                    + " ".join(f"{v:.3f}" for v in ratio)
                    + " |"
                )


def spheres() -> None:
    folder = ROOT / "tests/scenes/materials"
    refs = json.loads((folder / "references.json").read_text())
    print("| sphere | path 64 spp | direct | bidir | bidir, roughness_clamping off |")
    print("|---|---|---|---|---|")
    for name in sorted(refs):
        scene = gi.load_scene(folder / f"{name}.xml")
        ref = np.array(refs[name]["mean"])
        cells = []
        for method, kw in [
            ("path", {"spp": 64}),
            ("direct", {}),
            ("bidir", {}),
            ("bidir", {"roughness_clamping": False}),
        ]:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                img = gi.render(scene, method, size=(64, 64), seed=3, **kw).radiance
            cells.append(" ".join(f"{v:.3f}" for v in img.mean(axis=(0, 1)) / ref))
        print(f"| {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("what", choices=["spread", "cbox", "spheres"])
    ap.add_argument("--seeds", type=int, default=8)
    a = ap.parse_args()
    {"spread": lambda: spread(a.seeds), "cbox": cbox, "spheres": spheres}[a.what]()
