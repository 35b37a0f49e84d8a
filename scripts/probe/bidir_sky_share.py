"""`bidir`'s sky share β (`frame/bidir/sky_share.rs`) over the frames of one renderer: the
stage "sky share" (24×24 camera hits × 4 cosine rays in the CPU BVH) per frame, and the
frame's total, on still frames and after a light update (the sun moved), which leaves β as
it was. Writes nothing; prints a table.

    python scripts/probe/bidir_sky_share.py [--scene window-sun-sky] [--frames 6]

window-sun-sky: `tests/glass_scenes.py`'s glazed window room (window-sun: the pane, the sun
through it) with the room's constant sky kept, 160×120, default `bidir` settings.
"""

import argparse
import json
import sys
from pathlib import Path

import gi

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
import glass_scenes  # noqa: E402

SUN = {"type": "directional", "direction": [-1.0, -0.8, 0.3], "irradiance": [6] * 3}


def window_sun_sky() -> gi.Scene:
    """The glazed window room lit by the sun through the pane and by the sky."""
    desc = json.loads((glass_scenes.DIR / "window_room.json").read_text())
    desc["materials"]["glass"] = glass_scenes.GLASS
    pane = {"shape": {"type": "box", "size": [0.02, 1.0, 1.2]}, "material": "glass"}
    desc["objects"].append(pane | {"transform": {"translate": [2.05, 1.4, 0.0]}})
    desc["lights"] = [SUN | {"angular_diameter": 0.53}]
    desc["camera"] |= {"width": 160, "height": 120}
    return gi.Scene.from_json(json.dumps(desc), "window-sun-sky")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=6)
    args = ap.parse_args()
    renderer = gi.Renderer(window_sun_sky(), "bidir")
    print("| frame | change | sky share (ms) | frame (ms) |")
    print("|---|---|---|---|")
    for i in range(args.frames):
        change = "first" if i == 0 else "still"
        if i == args.frames - 1:
            renderer.update(lights={0: {"direction": [-1.0, -0.7, 0.1]}})
            change = "sun moved"
        stats = renderer.render().stats
        share = dict(stats.stages).get("sky share")
        cell = f"{share * 1e3:.1f}" if share is not None else "—"
        print(f"| {i} | {change} | {cell} | {stats.total_seconds * 1e3:.0f} |")


if __name__ == "__main__":
    main()
