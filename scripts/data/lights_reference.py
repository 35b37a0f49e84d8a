"""References for issue 28's light scenes (`docs/scenes/`): Mitsuba 3 renders each scene to
convergence, gi renders it in every method, and the table `docs/bench/lights.md` gives per
scene and method the ratio of gi's image mean to the reference's and HDR-FLIP.

    .venv/bin/python scripts/data/lights_reference.py mitsuba   # the references (needs mitsuba)
    .venv/bin/python scripts/data/lights_reference.py gi        # gi per method -> the table
    .venv/bin/python scripts/data/lights_reference.py all

The references are committed beside their scenes, SIZE×SIZE float EXRs that
`tests/test_lights_reference.py` reads (CI never runs Mitsuba), one per `max_depth` that
gi's methods default to: `reference-depth64.exr` (`path`, `photon`, `gather`, `ispm`),
`reference-depth3.exr` (`bidir`: two indirect bounces) and `reference-depth1.exr` (`direct`:
emission seen by the camera and direct light). Both renderers trace the same light paths:
gi's `max_depth` counts scattering events, Mitsuba's path segments, so gi's N is Mitsuba's
N + 1; Mitsuba's pixel filter is set to a box, as gi's. The reference's own noise is
estimated from independent batches (its mean's standard error is in the table).
Mitsuba's `scalar_rgb` variant needs nothing else; `--variant llvm_ad_rgb` needs libLLVM
19 (e.g. Debian's `libllvm19` unpacked with `dpkg -x`, `DRJIT_LIBLLVM_PATH` pointing at
`libLLVM-19.so`; versions 14-16 abort).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared
from shared import cpu_name, flip  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "docs" / "scenes"
TABLE = ROOT / "docs" / "bench" / "lights.md"
NAMES = ["cornell-box", "sun-sky", "emissive-room"]
SIZE = 64
# gi's default max_depth per method (scattering events; `direct` renders direct light: 1)
# and the Mitsuba samples per pixel of its reference, as a fraction of --spp.
DEPTHS = {64: 1, 3: 1, 1: 1 / 4}
METHODS = ["path", "photon", "gather", "direct", "ispm", "bidir"]

# gi's settings per method for the table (converged further than the CI test's).
GI_SETTINGS = {
    "path": {"spp": 4096},
    "photon": {"photons": 2_000_000, "spp": 64},
    "gather": {"photons": 1_000_000, "spp": 64},
    "direct": {"spp": 64},
    "ispm": {"photons": 1_000_000, "spp": 64},
    # bidir: its VPLs of area lights, the sun and the sky are the first hits of 64 photons a
    # frame, so its image is the mean of progressive passes (new VPLs and bundles each).
    "bidir": {"spp": 64, "progressive": True, "passes": 64},
}


def scene_file(name: str) -> Path:
    return SCENES / name / f"{name}.xml"


def reference_file(name: str, depth: int) -> Path:
    """The reference of `name` at gi's `max_depth` `depth`."""
    return SCENES / name / f"reference-depth{depth}.exr"


def method_depth(renderer) -> int:
    """The max_depth a gi.Renderer traces (`direct`, which has none, renders direct light)."""
    return int(renderer.options.get("max_depth", 1))


# -- Mitsuba --------------------------------------------------------------------------------


def mitsuba_xml(path: Path, size: int, max_depth: int, spp: int, seed: int) -> str:
    """The scene's XML with the film at size×size with a box filter, an independent sampler
    of `spp` samples and a path integrator of `max_depth`."""
    root = ET.parse(path).getroot()
    for el in list(root):
        if el.tag == "integrator":
            root.remove(el)
    integrator = ET.Element("integrator", {"type": "path"})
    ET.SubElement(integrator, "integer", {"name": "max_depth", "value": str(max_depth)})
    root.insert(0, integrator)
    for el in root.iter("string"):
        if el.get("name") == "filename":  # the scene's files, wherever Mitsuba runs
            el.set("value", str(path.parent / el.get("value", "")))
    sensor = root.find("sensor")
    assert sensor is not None, path
    for el in list(sensor):
        if el.tag in ("film", "sampler"):
            sensor.remove(el)
    sampler = ET.SubElement(sensor, "sampler", {"type": "independent"})
    ET.SubElement(sampler, "integer", {"name": "sample_count", "value": str(spp)})
    ET.SubElement(sampler, "integer", {"name": "seed", "value": str(seed)})
    film = ET.SubElement(sensor, "film", {"type": "hdrfilm"})
    ET.SubElement(film, "integer", {"name": "width", "value": str(size)})
    ET.SubElement(film, "integer", {"name": "height", "value": str(size)})
    ET.SubElement(film, "rfilter", {"type": "box"})
    return ET.tostring(root, encoding="unicode")


def render_mitsuba(
    name: str, max_depth: int, spp: int, batches: int, variant: str
) -> tuple[np.ndarray, float, dict]:
    """The mean of `batches` independent renders of `spp` samples, and the standard error
    of its image mean."""
    import mitsuba as mi

    mi.set_variant(variant)
    path = scene_file(name)
    images, means = [], []
    t = time.perf_counter()
    for b in range(batches):
        scene = mi.load_string(mitsuba_xml(path, SIZE, max_depth, spp, seed=b))
        img = np.array(mi.render(scene, spp=spp, seed=b), dtype=np.float64)[..., :3]
        images.append(img)
        means.append(img.mean())
    seconds = time.perf_counter() - t
    img = np.mean(images, axis=0)
    stderr = float(np.std(means, ddof=1) / np.sqrt(batches)) if batches > 1 else float("nan")
    info = {
        "spp": spp * batches,
        "max_depth": max_depth,
        "mean": float(img.mean()),
        "stderr": stderr,
        "seconds": round(seconds, 1),
        "variant": variant,
        "mitsuba": mi.__version__,
    }
    return img.astype(np.float32), stderr, info


def write_exr(path: Path, img: np.ndarray) -> None:
    """A float32 RGB EXR, zip-compressed."""
    import OpenImageIO as oiio  # noqa: N813 (the package's own usual alias)

    buf = oiio.ImageBuf(np.ascontiguousarray(img, np.float32))
    buf.specmod().attribute("compression", "zip")
    if not buf.write(str(path)):
        raise SystemExit(f"cannot write {path}: {buf.geterror()}")


def mitsuba_references(args: argparse.Namespace) -> None:
    out = SCENES / "references.json"
    for name in args.scenes:
        for depth in args.depths:
            per_batch = int(args.spp * DEPTHS[depth]) // args.batches
            img, err, info = render_mitsuba(name, depth + 1, per_batch, args.batches, args.variant)
            write_exr(reference_file(name, depth), img)
            key = f"{name}-depth{depth}"
            meta = json.loads(out.read_text()) if out.exists() else {}
            meta[key] = info
            out.write_text(json.dumps(meta, indent=1, sort_keys=True) + "\n")
            print(f"{key}: mean {img.mean():.5f} ± {err:.5f} ({info['seconds']} s)", flush=True)


# -- gi -------------------------------------------------------------------------------------


def render_gi(name: str, method: str, settings: dict) -> dict:
    """gi's image of a scene in a method, with what the method warned about (or refused);
    with `passes` in `settings`, the mean of that many progressive passes."""
    import gi

    settings = dict(settings)
    passes = settings.pop("passes", None)
    scene = gi.load_scene(scene_file(name))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            r = gi.Renderer(scene, method, size=(SIZE, SIZE), seed=7, **settings)
        except gi.SettingError as e:
            return {"status": "refused", "why": [str(e)]}
    warned = [str(w.message) for w in caught if issubclass(w.category, gi.RenderWarning)]
    t = time.perf_counter()
    img = (r.render_progressive(passes=passes) if passes else r.render()).radiance
    return {
        "status": "warns" if warned else "renders",
        "why": warned,  # one entry per warning (a message may hold a semicolon)
        "image": img,
        "seconds": time.perf_counter() - t,
        "depth": method_depth(r),
    }


def gi_table(args: argparse.Namespace) -> None:
    import gi

    meta = json.loads((SCENES / "references.json").read_text())
    rows, warned = [], {}
    for name in args.scenes:
        for method in args.methods:
            out = render_gi(name, method, GI_SETTINGS[method])
            if "image" in out:
                ref = gi.read_image(reference_file(name, out["depth"]))[..., :3]
                ratio = out["image"].mean() / ref.mean()
                cells = [
                    str(out["depth"]),
                    f"{ratio:.4f}",
                    f"{flip(ref, out['image']):.3f}",
                    f"{out['seconds']:.1f}",
                ]
            else:
                cells = ["–", "–", "–", "–"]
            if out["status"] != "renders":
                for why in out["why"]:
                    warned.setdefault((method, why), []).append(name)
            rows.append([name, method, out["status"], *cells])
            print(" | ".join(rows[-1]), flush=True)
    write_table(rows, warned, meta, args)


def write_table(rows: list, warned: dict, meta: dict, args: argparse.Namespace) -> None:
    import gi

    first = next(iter(meta.values()))
    lines = [
        "# Lights: gi against Mitsuba 3",
        "",
        "The reference scenes of issue 28 (`docs/scenes/`: Mitsuba's own Cornell box with its",
        "area light, a sun-and-sky scene, a room lit by emissive surfaces only), rendered by",
        f"Mitsuba 3 ({first['mitsuba']}, `{first['variant']}`, path tracer) and by gi in each",
        f"method at {SIZE}×{SIZE}, each method against the reference of the `max_depth` it",
        "traces by default (*depth*, scattering events; Mitsuba's `max_depth` is one more:",
        "64 for all paths (3: `bidir`'s old two-bounce default), 1 for `direct`: emission seen",
        "by the camera and light that reaches a surface straight from a source). *ratio*: gi's",
        "image mean over the reference's (1 is right); *FLIP*: mean HDR-FLIP against the",
        "reference (flip-evaluator, 67 ppd; 0 is identical; it includes the noise of gi's",
        "image). *status*: `renders` (no warning), `warns` (a `gi.RenderWarning`: a kind of",
        "light is left out, so the ratio measures what is missing) or `refused`",
        "(`gi.SettingError`). *seconds*: gi's render time on a 2-core machine shared with",
        "other builds (a rough guide only).",
        "",
        "Command: `.venv/bin/python scripts/data/lights_reference.py all` (references:",
        "`scripts/data/lights_reference.py mitsuba`, then gi: `... gi`). gi "
        f"{gi.__version__}, settings per method: "
        + ", ".join(
            f"`{m}` {', '.join(f'{k}={v}' for k, v in GI_SETTINGS[m].items())}" for m in METHODS
        )
        + f"; seed 7. Machine: {cpu_name()}, lavapipe for the GPU methods.",
        "",
        "## References",
        "",
        "| reference | Mitsuba spp | max_depth | mean | standard error of the mean | seconds |",
        "|---|---|---|---|---|---|",
    ]
    for key, m in meta.items():
        lines.append(
            f"| {key} | {m['spp']} | {m['max_depth']} | {m['mean']:.5f} | {m['stderr']:.5f} "
            f"({m['stderr'] / m['mean'] * 100:.3f} %) | {m['seconds']} |"
        )
    lines += [
        "",
        "## gi per method",
        "",
        "| scene | method | status | depth | ratio | FLIP | seconds |",
        "|---|---|---|---|---|---|---|",
    ]
    lines += ["| " + " | ".join(r) + " |" for r in rows]
    if warned:
        lines += ["", "## What the methods left out", ""]
        lines += ["| method | scenes | warning or refusal |", "|---|---|---|"]
        for (method, why), names in warned.items():
            lines += [f"| `{method}` | {', '.join(names)} | {why} |"]
    TABLE.write_text("\n".join(lines) + "\n")
    print(f"wrote {TABLE.relative_to(ROOT)}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("what", choices=["mitsuba", "gi", "all"])
    ap.add_argument("--scenes", nargs="+", default=NAMES, choices=NAMES)
    ap.add_argument("--methods", nargs="+", default=METHODS, choices=METHODS)
    ap.add_argument(
        "--depths", nargs="+", type=int, default=list(DEPTHS), choices=list(DEPTHS),
        help="gi max_depth of the references to render",
    )  # fmt: skip
    ap.add_argument("--spp", type=int, default=4096, help="Mitsuba samples per pixel")
    ap.add_argument("--batches", type=int, default=16, help="independent Mitsuba renders")
    ap.add_argument("--variant", default="scalar_rgb", help="Mitsuba variant")
    args = ap.parse_args()
    if args.what in ("mitsuba", "all"):
        mitsuba_references(args)
    if args.what in ("gi", "all"):
        gi_table(args)


if __name__ == "__main__":
    sys.exit(main())
