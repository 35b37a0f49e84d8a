"""A thin dielectric pane between an area light and a floor (issue 44 item 4, Mitsuba's
`thindielectric`) and its Mitsuba 3 reference: tests/test_thin_dielectric.py.

Reads tests/scenes/thin-pane/thin-pane.xml (Mitsuba 3 XML, gi's own, kept there: a 4 m
grey floor, a 0.6 m square light 2 m above it, a 1.2 m thindielectric pane tilted 30° at
1 m, its reflectance and transmittance coloured; 64×48, box pixel filter, 512 spp, no
environment) and writes thin-pane-reference.exr (Mitsuba's `path`, max_depth 65 = gi's
64 scattering events, the mean of BATCHES renders of different seeds), with
reference.json: the mean per channel and its standard error (from the batches).

Run: /work/main/.venv/bin/python scripts/data/thin_pane_scene.py (mitsuba==3.9.1; CI
never runs Mitsuba)."""

import json
import pathlib

import numpy as np

OUT = pathlib.Path(__file__).resolve().parents[2] / "tests" / "scenes" / "thin-pane"
SPP = 512  # the scene file's sample_count
BATCHES = 8


def main() -> None:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    scene = mi.load_file(str(OUT / "thin-pane.xml"))
    imgs = [np.array(mi.render(scene, seed=s)) for s in range(BATCHES)]
    img = np.mean(imgs, axis=0)
    means = np.array([i.reshape(-1, 3).mean(0) for i in imgs])
    se = means.std(0, ddof=1) / np.sqrt(BATCHES)
    mi.Bitmap(img.astype(np.float32)).write(str(OUT / "thin-pane-reference.exr"))
    meta = {
        "mean": img.reshape(-1, 3).mean(0).tolist(),
        "standard_error": se.tolist(),
        "spp": SPP * BATCHES,
        "mitsuba": mi.__version__,
        "command": "python scripts/data/thin_pane_scene.py",
    }
    (OUT / "reference.json").write_text(json.dumps(meta, indent=1) + "\n")
    print(meta["mean"], se / img.reshape(-1, 3).mean(0))


if __name__ == "__main__":
    main()
