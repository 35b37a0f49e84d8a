"""gi's reference path tracer against Mitsuba 3's on the same cores (issue 29, item 4):
the built-in Cornell box with its point light, written by this script in both renderers'
formats (gi's JSON scene file and Mitsuba XML, `docs/scenes/cornell-point/`), rendered by
both at 16, 64 and 256 samples per pixel in one run, the two renderers interleaved (gi,
Mitsuba, gi, Mitsuba, ...) and repeated so that the load of the shared machine falls on both
alike; each cell is the median of the repeats. Error is against a converged reference (the
mean of gi's and Mitsuba's long renders, see `reference`).

    .venv/bin/python -m pip install -q ".[bench]"
    DRJIT_LIBLLVM_PATH=/path/to/libLLVM-19.so .venv/bin/python scripts/bench/bench_path_mitsuba.py

relMSE is the mean over pixels and channels of (x - ref)² / (ref² + 0.01); FLIP is mean
HDR-FLIP (flip-evaluator, 67 ppd); efficiency is 1 / (seconds × relMSE). Both trace the same
paths: gi's `max_depth` counts scattering events, Mitsuba's path segments (gi's N is
Mitsuba's N + 1); Mitsuba's pixel filter is a box, as gi's; Mitsuba's sampler is its
`independent` one (its default) unless `--mitsuba-sampler` says otherwise.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # scripts/: shared
from shared import cpu_name, flip  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENE_DIR = ROOT / "docs" / "scenes" / "cornell-point"
TABLE = ROOT / "docs" / "bench" / "path-vs-mitsuba.md"
BUILTIN = ROOT / "crates" / "core" / "scenes" / "cornell.json"


# -- the scene in both formats ---------------------------------------------------------------


def rotation(deg: list[float]) -> np.ndarray:
    """gi's rotation: degrees about x, then y, then z."""
    ax, ay, az = (math.radians(d) for d in deg)
    rx = np.array([[1, 0, 0], [0, math.cos(ax), -math.sin(ax)], [0, math.sin(ax), math.cos(ax)]])
    ry = np.array([[math.cos(ay), 0, math.sin(ay)], [0, 1, 0], [-math.sin(ay), 0, math.cos(ay)]])
    rz = np.array([[math.cos(az), -math.sin(az), 0], [math.sin(az), math.cos(az), 0], [0, 0, 1]])
    return rz @ ry @ rx


def to_world(obj: dict) -> np.ndarray:
    """The 4×4 matrix taking Mitsuba's unit shape (`rectangle` [-1,1]² at z = 0 facing +z,
    `cube` [-1,1]³) to gi's object (a `quad` of `size` in the xz plane facing +y, a `box` of
    `size` about the origin), then through gi's transform (scale, rotate, translate)."""
    shape, tf = obj["shape"], obj.get("transform", {})
    if shape["type"] == "quad":
        sx, sz = shape["size"]
        # rectangle (x, y, 0) -> quad (x·sx/2, 0, -y·sz/2): +z goes to +y.
        base = np.array([[sx / 2, 0, 0], [0, 0, 1], [0, -sz / 2, 0]], dtype=float)
    else:
        base = np.diag([s / 2 for s in shape["size"]]).astype(float)
    scale = tf.get("scale", 1.0)
    scale = np.diag(scale if isinstance(scale, list) else [scale] * 3)
    m = np.eye(4)
    m[:3, :3] = rotation(tf.get("rotate", [0, 0, 0])) @ scale @ base
    m[:3, 3] = tf.get("translate", [0, 0, 0])
    return m


def mitsuba_xml(desc: dict, size: int, max_depth: int, spp: int, sampler: str) -> str:
    """gi's scene description as Mitsuba XML (two-sided diffuse, as gi's materials)."""
    cam = desc["camera"]
    lines = [
        '<scene version="3.0.0">',
        f'  <integrator type="path"><integer name="max_depth" value="{max_depth}"/></integrator>',
        '  <sensor type="perspective">',
        f'    <float name="fov" value="{cam["fov"]}"/>',
        '    <string name="fov_axis" value="y"/>',
        '    <transform name="to_world"><lookat origin="{}" target="{}" up="{}"/>'.format(
            *(", ".join(str(float(v)) for v in cam[k]) for k in ("position", "look_at", "up"))
        )
        + "</transform>",
        f'    <sampler type="{sampler}"><integer name="sample_count" value="{spp}"/></sampler>',
        '    <film type="hdrfilm">',
        f'      <integer name="width" value="{size}"/><integer name="height" value="{size}"/>',
        '      <rfilter type="box"/>',
        "    </film>",
        "  </sensor>",
    ]
    for name, m in desc["materials"].items():
        rgb = ", ".join(str(float(v)) for v in m["diffuse"])
        lines.append(
            f'  <bsdf type="twosided" id="{name}"><bsdf type="diffuse">'
            f'<rgb name="reflectance" value="{rgb}"/></bsdf></bsdf>'
        )
    for obj in desc["objects"]:
        kind = "rectangle" if obj["shape"]["type"] == "quad" else "cube"
        mat = " ".join(f"{v:.9g}" for v in to_world(obj).ravel())
        lines.append(
            f'  <shape type="{kind}"><transform name="to_world"><matrix value="{mat}"/>'
            f'</transform><ref id="{obj["material"]}"/></shape>'
        )
    for light in desc["lights"]:
        assert light["type"] == "point", light
        pos = ", ".join(str(float(v)) for v in light["position"])
        rgb = ", ".join(str(float(v)) for v in light["intensity"])
        lines.append(
            f'  <emitter type="point"><point name="position" value="{pos}"/>'
            f'<rgb name="intensity" value="{rgb}"/></emitter>'
        )
    lines.append("</scene>")
    return "\n".join(lines) + "\n"


def adapt_xml(path: Path, size: int, max_depth: int) -> str:
    """A Mitsuba XML scene (`--xml`) at `size`² pixels, Mitsuba `max_depth` gi's + 1, with a
    box pixel filter (gi's) in place of its own."""
    import re

    xml = path.read_text()
    xml = re.sub(r'<rfilter type="\w+"[^>]*?/>', '<rfilter type="box"/>', xml)
    for name, value in (("width", size), ("height", size), ("max_depth", max_depth + 1)):
        xml = re.sub(rf'(name="{name}" value=")\d+(")', rf"\g<1>{value}\g<2>", xml)
    return xml


def write_scene(size: int, max_depth: int) -> tuple[Path, Path]:
    """The scene as gi JSON and Mitsuba XML (Mitsuba's max_depth is gi's + 1)."""
    desc = json.loads(BUILTIN.read_text())
    desc["camera"]["width"] = desc["camera"]["height"] = size
    SCENE_DIR.mkdir(parents=True, exist_ok=True)
    gi_file, mi_file = SCENE_DIR / "cornell-point.json", SCENE_DIR / "cornell-point.xml"
    gi_file.write_text(json.dumps(desc, indent=1) + "\n")
    mi_file.write_text(mitsuba_xml(desc, size, max_depth + 1, 64, "independent"))
    return gi_file, mi_file


# -- rendering -------------------------------------------------------------------------------


class Gi:
    def __init__(self, scene_file: Path, size: int, max_depth: int):
        import gi

        self.gi, self.scene = gi, gi.load_scene(scene_file)
        self.size, self.max_depth = size, max_depth

    def render(self, spp: int, seed: int) -> tuple[np.ndarray, float]:
        r = self.gi.Renderer(
            self.scene, "path", size=(self.size, self.size), spp=spp, max_depth=self.max_depth,
            seed=seed,
        )  # fmt: skip
        t = time.perf_counter()
        img = r.render().radiance
        return np.asarray(img, np.float64)[..., :3], time.perf_counter() - t


class Mitsuba:
    def __init__(
        self, desc: dict, size: int, max_depth: int, variant: str, sampler: str,
        xml: str | None = None,
    ):  # fmt: skip
        import mitsuba as mi

        mi.set_variant(variant)
        self.mi, self.variant, self.version = mi, variant, mi.__version__
        self.desc, self.size, self.max_depth, self.sampler = desc, size, max_depth, sampler
        self.xml = xml
        self.scenes: dict[int, object] = {}

    def render(self, spp: int, seed: int) -> tuple[np.ndarray, float]:
        if spp not in self.scenes:
            xml = self.xml or mitsuba_xml(
                self.desc, self.size, self.max_depth + 1, spp, self.sampler
            )
            self.scenes[spp] = self.mi.load_string(xml)
            self.mi.render(self.scenes[spp], spp=spp, seed=10_000)  # JIT warm-up, not timed
        t = time.perf_counter()
        img = np.array(self.mi.render(self.scenes[spp], spp=spp, seed=seed), dtype=np.float64)
        return img[..., :3], time.perf_counter() - t


def rel_mse(ref: np.ndarray, img: np.ndarray) -> float:
    return float(np.mean((img - ref) ** 2 / (ref**2 + 0.01)))


def reference(gi_r: Gi, mi_r: Mitsuba, spp: int, batches: int) -> tuple[np.ndarray, dict]:
    """Converged reference: `batches` renders of `spp` by each renderer, all averaged (so it
    favours neither's bias); their means' ratio checks that both compute the same image."""
    gis, mis = [], []
    for b in range(batches):
        gis.append(gi_r.render(spp, 1000 + b)[0])
        mis.append(mi_r.render(spp, 1000 + b)[0])
    g, m = np.mean(gis, axis=0), np.mean(mis, axis=0)
    info = {
        "spp": 2 * spp * batches,
        "gi_mean": float(g.mean()),
        "mitsuba_mean": float(m.mean()),
        "gi_vs_mitsuba_relmse": rel_mse(m, g),
    }
    return (g + m) / 2, info


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--max-depth", type=int, default=7, help="gi's (scattering events)")
    ap.add_argument("--spp", type=int, nargs="+", default=[16, 64, 256])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--ref-spp", type=int, default=1024, help="per reference batch")
    ap.add_argument("--ref-batches", type=int, default=4, help="per renderer")
    ap.add_argument("--variant", default="llvm_ad_rgb")
    ap.add_argument("--mitsuba-sampler", default="independent")
    ap.add_argument("--no-table", action="store_true")
    ap.add_argument(
        "--xml", type=Path,
        help="compare on this Mitsuba XML scene instead (both renderers load it; the table "
        "is printed, not written), e.g. docs/scenes/cornell-box/cornell-box.xml",
    )  # fmt: skip
    args = ap.parse_args()

    if args.xml:
        import tempfile

        xml = adapt_xml(args.xml, args.size, args.max_depth)
        gi_file = Path(tempfile.mkdtemp()) / args.xml.name
        gi_file.write_text(xml)
        args.no_table = True
        gi_r = Gi(gi_file, args.size, args.max_depth)
        mi_r = Mitsuba({}, args.size, args.max_depth, args.variant, args.mitsuba_sampler, xml)
    else:
        gi_file, _ = write_scene(args.size, args.max_depth)
        desc = json.loads(gi_file.read_text())
        gi_r = Gi(gi_file, args.size, args.max_depth)
        mi_r = Mitsuba(desc, args.size, args.max_depth, args.variant, args.mitsuba_sampler)
    t = time.perf_counter()
    ref, ref_info = reference(gi_r, mi_r, args.ref_spp, args.ref_batches)
    ref_info["seconds"] = round(time.perf_counter() - t, 1)
    print("reference:", ref_info, flush=True)

    rows = []
    for spp in args.spp:
        runs: dict[str, list] = {"gi path": [], "Mitsuba 3": []}
        for rep in range(args.repeats):
            for name, r in (("gi path", gi_r), ("Mitsuba 3", mi_r)):
                img, sec = r.render(spp, rep)
                runs[name].append((sec, rel_mse(ref, img), flip(ref, img)))
        for name, res in runs.items():
            sec, err, fl = (statistics.median(x) for x in zip(*res, strict=True))
            rows.append([name, spp, sec, err, fl, 1.0 / (sec * err)])
            print(f"{name:10s} {spp:4d} spp: {sec:6.2f} s relMSE {err:.5f} FLIP {fl:.4f} "
                  f"efficiency {1 / (sec * err):8.2f}", flush=True)  # fmt: skip
    if not args.no_table:
        write_table(rows, ref_info, args, mi_r)


def realtime() -> bool:
    """Whether this process runs under a real-time scheduling policy (`chrt -f`)."""
    try:
        return os.sched_getscheduler(0) in (os.SCHED_FIFO, os.SCHED_RR)
    except (AttributeError, OSError):
        return False


def write_table(rows: list, ref_info: dict, args: argparse.Namespace, mi_r: Mitsuba) -> None:
    import gi

    lines = [
        "# `path` against Mitsuba 3",
        "",
        "gi's reference path tracer (`path`) and Mitsuba 3's (`path` integrator,",
        f"`{mi_r.variant}`, {args.mitsuba_sampler} sampler) on the built-in Cornell box with",
        "its point light (`docs/scenes/cornell-point/`, both formats written by the script) at",
        f"{args.size}×{args.size}, gi `max_depth` {args.max_depth} (Mitsuba's",
        f"{args.max_depth + 1}: the same paths). **Measured in one run on the same cores**: the",
        "two renderers interleaved, each cell the median of "
        f"{args.repeats} renders (seeds 0..{args.repeats - 1}) on a 2-core machine shared",
        "with other engineers' builds, so only the two columns of one row's spp are",
        "comparable and the absolute seconds are not. Mitsuba's time is its render after a",
        "warm-up render (its JIT compiles once per spp), gi's its `render()` call.",
        "",
        "*relMSE*: mean of (x − ref)² / (ref² + 0.01) over pixels and channels; *FLIP*: mean",
        "HDR-FLIP; *efficiency*: 1 / (seconds × relMSE), higher is better. The reference is",
        f"the mean of {ref_info['spp']} spp, half gi's and half Mitsuba's (their means",
        f"{ref_info['gi_mean']:.5f} and {ref_info['mitsuba_mean']:.5f}; relMSE between their",
        f"halves {ref_info['gi_vs_mitsuba_relmse']:.2e}, the reference's own noise).",
        "",
        "Command: `DRJIT_LIBLLVM_PATH=.../libLLVM-19.so "
        + ("chrt -f 50 " if realtime() else "")
        + ".venv/bin/python "
        + " ".join(["scripts/bench/bench_path_mitsuba.py", *sys.argv[1:]])
        + "`"
        f" (gi {gi.__version__}, Mitsuba {mi_r.version}; machine: {cpu_name()},"
        f" {os.cpu_count()} cores).",
        "",
        "| spp | renderer | seconds | relMSE | FLIP | efficiency | gi / Mitsuba efficiency |",
        "|---|---|---|---|---|---|---|",
    ]
    by = {(r[0], r[1]): r for r in rows}
    ratios = []
    for spp in args.spp:
        g, m = by[("gi path", spp)], by[("Mitsuba 3", spp)]
        ratios.append(g[5] / m[5])
        for r in (g, m):
            ratio = f"**{g[5] / m[5]:.2f}**" if r is g else ""
            lines.append(
                f"| {spp} | {r[0]} | {r[2]:.2f} | {r[3]:.5f} | {r[4]:.4f} | {r[5]:.1f} | {ratio} |"
            )
    verdict = "at least" if min(ratios) >= 1.0 else "below"
    lines += [
        "",
        f"**Result: gi's efficiency is {min(ratios):.2f}–{max(ratios):.2f}× Mitsuba's, "
        f"{verdict} Mitsuba's at every spp.**",
    ]
    # The sections after the table (measurements by hand, history) are kept.
    old = TABLE.read_text() if TABLE.exists() else ""
    rest = old[old.index("\n## ") :] if "\n## " in old else "\n"
    TABLE.write_text("\n".join(lines) + "\n" + rest)
    print(f"wrote {TABLE.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
