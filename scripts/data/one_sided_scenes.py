"""Mitsuba 3 references of the one-sided BSDF scenes (issue 42): a Mitsuba BSDF without
`twosided` (other than the dielectrics) is black seen or lit from behind.

Reads tests/scenes/one-sided/rectangle.xml (a 2 m square seen and lit by a point light from
its front or back, `diffuse` or `twosided` diffuse) and panel.xml (a panel lit from behind,
standing on a two-sided floor, seen from behind) and writes references.json there: per
configuration the image mean per channel of Mitsuba's `path` (max_depth 65 = gi's 64
scattering events) and, for the panel, of its direct light alone (max_depth 2), each the
mean of BATCHES renders of different seeds, with its standard error. tests/test_mitsuba_sides.py
compares every gi method with them.

Run: /work/main/.venv/bin/python scripts/data/one_sided_scenes.py (mitsuba==3.9.1; CI never
runs Mitsuba)."""

import json
import pathlib

import numpy as np

OUT = pathlib.Path(__file__).resolve().parents[2] / "tests" / "scenes" / "one-sided"
SPP = 1024
BATCHES = 4
# (camera z, light z, BSDF id) of rectangle.xml.
RECTANGLE = [(3, 3, "plain"), (-3, -3, "plain"), (-3, -3, "both"), (3, -3, "plain")]


def mean(mi, path, depth=65, **params):
    scene = mi.load_file(str(path), **{k: str(v) for k, v in params.items()})
    integrator = mi.load_dict({"type": "path", "max_depth": depth})
    imgs = [
        np.array(mi.render(scene, integrator=integrator, spp=SPP, seed=s)) for s in range(BATCHES)
    ]
    means = np.array([i.reshape(-1, 3).mean(0) for i in imgs])
    return {
        "mean": means.mean(0).tolist(),
        "standard_error": (means.std(0, ddof=1) / np.sqrt(BATCHES)).tolist(),
    }


def main() -> None:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    refs = {}
    for cam, light, bsdf in RECTANGLE:
        refs[f"rectangle cam={cam} light={light} bsdf={bsdf}"] = mean(
            mi, OUT / "rectangle.xml", cam=cam, light=light, bsdf=bsdf
        )
    for bsdf in ("plain", "both"):
        refs[f"panel bsdf={bsdf}"] = mean(mi, OUT / "panel.xml", bsdf=bsdf)
        refs[f"panel bsdf={bsdf} direct"] = mean(mi, OUT / "panel.xml", depth=2, bsdf=bsdf)
    meta = {
        "references": refs,
        "spp": SPP * BATCHES,
        "mitsuba": mi.__version__,
        "command": "python scripts/data/one_sided_scenes.py",
    }
    (OUT / "references.json").write_text(json.dumps(meta, indent=1) + "\n")
    for k, v in refs.items():
        print(k, np.round(v["mean"], 5), np.round(v["standard_error"], 6))


if __name__ == "__main__":
    main()
