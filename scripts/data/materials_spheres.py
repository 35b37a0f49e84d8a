"""Single-material spheres of issue 42 (Mitsuba's plastic, roughplastic with GGX and
Beckmann, conductor and roughconductor with named metals, roughdielectric) and their
Mitsuba 3 references: the one corpus of material spheres (tests/test_materials_mitsuba.py,
scripts/probe/materials_vs_mitsuba.py).

Writes tests/scenes/materials/<name>.xml (Mitsuba 3 XML: a unit sphere under a constant
environment and a small rectangular area light, 64×64, box pixel filter; the glass sphere
stands on a grey floor, which it refracts, since a uniform environment seen through glass
looks the same whatever the glass) and
<name>-reference.exr (Mitsuba's `path`, max_depth 65 = gi's 64 scattering events, the mean
of BATCHES renders of different seeds), plus references.json: each reference's mean per
channel and its standard error (from the batches), and under "direct" the same for
Mitsuba's `direct` integrator (its defaults: one emitter and one BSDF sample per pixel
sample, at the first hit only; DIRECT_SPP in each of BATCHES renders; no image kept), the
reference of gi's `direct` (its image, <name>-direct-reference.exr, for the spheres on a
floor only).

Run: /work/main/.venv/bin/python scripts/data/materials_spheres.py [--direct] [NAME ...]
(pip install mitsuba==3.9.1; CI never runs Mitsuba). With names, only those spheres are
written and their entries of references.json replaced; with --direct, only the `direct`
references are rendered (from the committed XML) and added to the entries."""

import json
import pathlib
import sys

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
OUT = ROOT / "tests" / "scenes" / "materials"
SIZE = 64
SPP = 512
BATCHES = 8
DIRECT_SPP = 128

MATERIALS = {
    "plastic": """<bsdf type="plastic">
        <rgb name="diffuse_reflectance" value="0.6, 0.25, 0.1"/>
    </bsdf>""",
    "roughplastic-ggx": """<bsdf type="roughplastic">
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.2"/>
        <rgb name="diffuse_reflectance" value="0.1, 0.3, 0.7"/>
    </bsdf>""",
    "roughplastic-beckmann": """<bsdf type="roughplastic">
        <rgb name="diffuse_reflectance" value="0.8, 0.7, 0.2"/>
        <boolean name="nonlinear" value="true"/>
    </bsdf>""",
    "conductor-au": """<bsdf type="conductor">
        <string name="material" value="Au"/>
    </bsdf>""",
    "roughconductor-cu": """<bsdf type="roughconductor">
        <string name="material" value="Cu"/>
        <float name="alpha" value="0.2"/>
    </bsdf>""",
    "roughconductor-al-ggx": """<bsdf type="roughconductor">
        <string name="material" value="Al"/>
        <string name="distribution" value="ggx"/>
        <float name="alpha" value="0.3"/>
    </bsdf>""",
    "roughdielectric": """<bsdf type="roughdielectric">
        <float name="alpha" value="0.1"/>
        <float name="int_ior" value="1.5"/>
    </bsdf>""",
}
# Spheres that stand on a floor (y = -1, 20 m square, grey diffuse).
FLOOR = """<shape type="rectangle">
        <transform name="to_world">
            <scale value="10"/>
            <rotate x="1" angle="-90"/>
            <translate y="-1"/>
        </transform>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0.4"/>
        </bsdf>
    </shape>"""
FLOORED = {"roughdielectric"}

SCENE = """<scene version="3.0.0">
    <!-- Issue 42's single-material sphere: {name} (scripts/data/materials_spheres.py). -->
    <integrator type="path">
        <integer name="max_depth" value="65"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="36"/>
        <transform name="to_world">
            <lookat origin="0, 0.6, 4" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="{spp}"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="{size}"/>
            <integer name="height" value="{size}"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <emitter type="constant">
        <rgb name="radiance" value="0.4"/>
    </emitter>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.4"/>
            <lookat origin="2, 3, 2.5" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <emitter type="area">
            <rgb name="radiance" value="12"/>
        </emitter>
    </shape>
    <shape type="sphere">
        {bsdf}
    </shape>{floor}
</scene>
"""


def batch_means(mi, scene, spp: int, integrator=None) -> tuple[np.ndarray, dict]:
    """BATCHES renders of `scene` (seeds 0..): their mean image, and its mean per channel
    with the standard error over the batches."""
    imgs = [
        np.array(mi.render(scene, integrator=integrator, seed=s, spp=spp)) for s in range(BATCHES)
    ]
    img = np.mean(imgs, axis=0)
    means = np.array([i.reshape(-1, 3).mean(0) for i in imgs])
    se = means.std(0, ddof=1) / np.sqrt(BATCHES)
    return img, {
        "mean": img.reshape(-1, 3).mean(0).tolist(),
        "standard_error": se.tolist(),
        "spp": spp * BATCHES,
        "mitsuba": mi.__version__,
    }


def direct_references(mi, names: list[str], meta: dict) -> None:
    """Mitsuba's `direct` on each committed sphere: its means go to meta[name]["direct"];
    its image to <name>-direct-reference.exr where it differs from `path`'s (the spheres on
    a floor: a lone convex sphere under a sky receives direct light only)."""
    integrator = mi.load_dict({"type": "direct"})
    for name in names:
        scene = mi.load_file(str(OUT / f"{name}.xml"))
        img, meta[name]["direct"] = batch_means(mi, scene, DIRECT_SPP, integrator)
        if name in FLOORED:
            mi.Bitmap(img.astype(np.float32)).write(str(OUT / f"{name}-direct-reference.exr"))
        print(name, "direct", meta[name]["direct"]["mean"])


def main() -> None:
    import mitsuba as mi

    mi.set_variant("scalar_rgb")
    OUT.mkdir(parents=True, exist_ok=True)
    args = [a for a in sys.argv[1:] if a != "--direct"]
    names = args or list(MATERIALS)
    old = (
        json.loads((OUT / "references.json").read_text())
        if (OUT / "references.json").exists()
        else {}
    )
    if "--direct" in sys.argv[1:]:
        direct_references(mi, names, old)
        (OUT / "references.json").write_text(json.dumps(old, indent=1) + "\n")
        return
    meta = old if args else {}
    for name in names:
        bsdf = MATERIALS[name]
        floor = "\n    " + FLOOR if name in FLOORED else ""
        xml = SCENE.format(name=name, spp=SPP, size=SIZE, bsdf=bsdf, floor=floor)
        path = OUT / f"{name}.xml"
        path.write_text(xml)
        scene = mi.load_file(str(path))
        img, meta[name] = batch_means(mi, scene, SPP)
        mi.Bitmap(img.astype(np.float32)).write(str(OUT / f"{name}-reference.exr"))
        print(name, meta[name]["mean"], meta[name]["standard_error"])
    direct_references(mi, names, meta)
    meta = dict(sorted(meta.items(), key=lambda kv: list(MATERIALS).index(kv[0])))
    (OUT / "references.json").write_text(json.dumps(meta, indent=1) + "\n")


if __name__ == "__main__":
    main()
