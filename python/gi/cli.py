"""The ``gi`` command line."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import gi
import gi.io
from gi._checks import U64_MAX, float_setting, int_setting
from gi._checks import exposure_setting as check_exposure


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, got {text!r}") from None
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError("width and height must be positive")
    return w, h


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="gi", description="Global illumination renderer (ISPM).")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene to an image")
    r.add_argument(
        "scene", help="built-in scene name (see `gi scenes`), JSON scene file or Mitsuba 3 XML"
    )
    r.add_argument(
        "-o",
        "--output",
        required=True,
        action="append",
        help="output image, .exr (float) or .png (sRGB); repeat for several",
    )
    r.add_argument("--method", default="ispm", help="rendering method (see `gi methods`)")
    r.add_argument(
        "--spp",
        type=int,
        help="samples per pixel (default 64; 16 direct-light samples for direct and ispm)",
    )
    r.add_argument("--size", type=_size, help="image size WIDTHxHEIGHT (default: the scene's)")
    r.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    r.add_argument("--max-depth", type=int, default=64, help="maximum path length")
    r.add_argument("--light-paths", type=int, help="light paths for caustics (default spp·pixels)")
    r.add_argument("--photons", type=int, default=200_000, help="photons (method photon)")
    r.add_argument("--k", type=int, default=100, help="nearest photons per estimate")
    r.add_argument("--max-radius", type=float, help="photon search radius in metres")
    r.add_argument(
        "--kernel", default="cone", choices=["box", "cone", "epanechnikov"], help="photon kernel"
    )
    r.add_argument("--smoothing", type=float, default=1.0, help="footprint scale (gather)")
    r.add_argument("--leaf-size", type=int, help="photon-map BVH leaf size (gather; default auto)")
    r.add_argument("--kernel-scale", type=float, default=1.0, help="photon volume scale (ispm)")
    r.add_argument(
        "--subsample", type=int, default=2, help="splat at 1/k resolution (ispm; default 2)"
    )
    r.add_argument(
        "--footprint-volumes",
        action="store_true",
        help="size ISPM photon volumes by photon-differential footprints",
    )
    r.add_argument(
        "--no-boundary-compensation",
        action="store_true",
        help="don't correct ISPM photon power for kernels that fall off surfaces",
    )
    r.add_argument(
        "--volume-shape",
        default="auto",
        choices=["auto", "icosahedron", "quad"],
        help="shape drawn per ISPM photon volume (default auto: quads for small volumes)",
    )
    r.add_argument("--adapter", help='GPU adapter: "cpu" (lavapipe), "gpu" or part of a name')
    r.add_argument("--shadow-map-size", type=int, default=1024, help="shadow map texels per side")
    r.add_argument("--exposure", type=float, default=0.0, help="PNG exposure in stops")
    r.add_argument(
        "--aov",
        action="append",
        default=[],
        help="also write this image next to the output (repeatable): albedo, normal, position,"
        " depth, caustics; method ispm adds direct, indirect, photons",
    )
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")
    sub.add_parser("scenes", help="list the built-in scenes")
    sub.add_parser("methods", help="list the rendering methods")
    f = sub.add_parser(
        "footprints", help="photon-differential footprint radii per path kind (Table 3)"
    )
    f.add_argument("scene", help="built-in scene name or JSON scene file")
    f.add_argument("--photons", type=int, default=200_000, help="photons to emit")
    f.add_argument("--smoothing", type=float, default=1.0, help="footprint smoothing factor s")
    f.add_argument("--seed", type=int, default=0)
    i = sub.add_parser("info", help="show the GPU adapter gi uses")
    i.add_argument("--adapter", help='"cpu", "gpu" or part of an adapter name')
    return p


def _load(source: str) -> gi.Scene:
    """Loads a scene, printing what its files hold that gi does not render."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", gi.AssetWarning)
        scene = gi.load_scene(source)
    for w in caught:
        if issubclass(w.category, gi.AssetWarning):
            print(f"gi: warning: {w.message}", file=sys.stderr)
        else:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    return scene


def _render(args: argparse.Namespace) -> int:
    # Outputs and exposure are checked before the render, not after it.
    exposure = check_exposure(args.exposure)
    for out in args.output:
        gi.io.check_output(out)
    scene = _load(args.scene)
    result = gi.render(
        scene,
        args.method,
        spp=args.spp,
        size=args.size,
        seed=args.seed,
        max_depth=args.max_depth,
        light_paths=args.light_paths,
        photons=args.photons,
        k=args.k,
        max_radius=args.max_radius,
        kernel=args.kernel,
        smoothing=args.smoothing,
        leaf_size=args.leaf_size,
        kernel_scale=args.kernel_scale,
        subsample=args.subsample,
        footprint_volumes=args.footprint_volumes,
        boundary_compensation=not args.no_boundary_compensation,
        volume_shape=args.volume_shape,
        adapter=args.adapter,
        shadow_map_size=args.shadow_map_size,
        progress=not args.quiet,
    )
    missing = [name for name in args.aov if name not in result.aov_names()]
    if missing:
        raise ValueError(f"no image {missing[0]!r} (available: {', '.join(result.aov_names())})")
    written = []
    for out in map(Path, args.output):
        gi.save_image(out, result.radiance, exposure=exposure)
        written.append(out)
        for name in args.aov:
            aov_path = out.with_name(f"{out.stem}.{name}{out.suffix}")
            gi.save_image(aov_path, result.aov(name), exposure=0.0)
            written.append(aov_path)
    if not args.quiet:
        s = result.stats
        stages = ", ".join(f"{n} {t:.2f}s" for n, t in s.stages)
        files = ", ".join(map(str, written))
        print(f"wrote {files} ({s.method}, {s.total_seconds:.2f}s: {stages})", file=sys.stderr)
    return 0


def _footprints(args: argparse.Namespace) -> int:
    qs = [1.0, 5.0, 25.0, 50.0, 75.0, 95.0, 99.0]
    photons = int_setting("photons", args.photons, U64_MAX)
    seed = int_setting("seed", args.seed, U64_MAX)
    smoothing = float_setting("smoothing", args.smoothing)
    rows = gi.footprint_radii(_load(args.scene), photons, seed, smoothing, qs)
    print(f"footprint radius (m) by percentile, {args.photons} photons, s = {args.smoothing}")
    print(f"{'kind':8} {'photons':>9} " + " ".join(f"{f'p{q:g}':>8}" for q in qs))
    for kind, (count, radii) in rows.items():
        print(f"{kind:8} {count:9d} " + " ".join(f"{r:8.4f}" for r in radii))
    return 0


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    try:
        if args.command == "scenes":
            for name, desc in gi.builtin_scenes():
                print(f"{name:15} {desc}")
            return 0
        if args.command == "footprints":
            return _footprints(args)
        if args.command == "info":
            print(f"gi {gi.__version__}")
            print(gi.adapter_report(args.adapter))
            return 0
        if args.command == "methods":
            print("\n".join(gi.methods()))
            return 0
        return _render(args)
    except gi.GiError as e:
        print(f"gi: error: {e}", file=sys.stderr)
        return 2
    except (OSError, ValueError, MemoryError) as e:
        print(f"gi: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\ngi: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
