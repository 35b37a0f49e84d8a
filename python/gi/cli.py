"""The ``gi`` command line."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import gi
from gi import denoising
from gi.aovs import aov_names, check_aovs
from gi.display import TONEMAPS
from gi.io import check_output_path, planned_files, save_result


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
    p.add_argument("--version", action="version", version=f"gi {gi.__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene to an image")
    r.add_argument("scene", help="built-in scene name (see `gi scenes`) or JSON scene file")
    r.add_argument(
        "-o",
        "--output",
        required=True,
        action="append",
        help="output image: .exr (float; AOVs become layers of the same file), .png/.jpg"
        " (8-bit sRGB through --tonemap), .hdr/.pfm/.tif (float); repeat for several",
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
    r.add_argument(
        "--exposure", type=float, default=0.0, help="exposure in stops for 8-bit outputs"
    )
    r.add_argument(
        "--tonemap",
        default="clip",
        choices=list(TONEMAPS),
        help="display transform for 8-bit outputs: clip (default), filmic (AgX-style; alias"
        " agx) or aces (ACES 2.0 SDR through OpenColorIO)",
    )
    r.add_argument(
        "--denoise",
        action="store_true",
        help="denoise with Intel Open Image Denoise, guided by the albedo and normal AOVs",
    )
    r.add_argument(
        "--aov",
        action="append",
        default=[],
        help="also write this AOV (repeatable; 'all' for every one): albedo, normal, position,"
        " depth, caustics; method direct adds direct, ispm direct, specular, indirect, photons;"
        " --denoise adds noisy. EXR: layers of the output file; other formats: NAME.AOV.EXT",
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
    b = sub.add_parser(
        "batch",
        help="render the frames of a job file as Ray tasks (see `gi.batch` for the format)",
    )
    b.add_argument("job", help="job file (JSON): scene, method, settings, frames, sweep, outputs")
    b.add_argument("--address", help="Ray cluster address (default: RAY_ADDRESS, else local Ray)")
    b.add_argument("--retries", type=int, help="times a failed frame is tried again (default 2)")
    b.add_argument("-q", "--quiet", action="store_true", help="print only failures")
    i = sub.add_parser("info", help="show the GPU adapter gi uses")
    i.add_argument("--adapter", help='"cpu", "gpu" or part of an adapter name')
    return p


def _check_outputs(args: argparse.Namespace) -> list[str]:
    """Checks outputs, formats and AOV names before rendering; returns the AOVs to write."""
    if args.denoise and not denoising.available():
        raise gi.SettingError(denoising.INSTALL_HINT)
    if args.method not in gi.methods():
        raise gi.SettingError(f"unknown method {args.method!r} (use {', '.join(gi.methods())})")
    names = aov_names(args.method, args.denoise)
    wanted = names[1:] if "all" in args.aov else list(dict.fromkeys(args.aov))
    check_aovs(args.method, wanted, args.denoise)
    targets: list[Path] = []
    for out in args.output:
        targets += planned_files(out, wanted)
    seen: set[Path] = set()
    for t in targets:
        check_output_path(t)
        if t.resolve() in seen:
            raise ValueError(f"{t} would be written twice")
        seen.add(t.resolve())
    return wanted


def _render(args: argparse.Namespace) -> int:
    aovs = _check_outputs(args)
    scene = gi.load_scene(args.scene)
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
        denoise=args.denoise,
    )
    written: list[Path] = []
    for out in args.output:
        written += save_result(out, result, aovs, tonemap=args.tonemap, exposure=args.exposure)
    if not args.quiet:
        s = result.stats
        stages = ", ".join(f"{n} {t:.2f}s" for n, t in s.stages)
        files = ", ".join(map(str, written))
        print(f"wrote {files} ({s.method}, {s.total_seconds:.2f}s: {stages})", file=sys.stderr)
    return 0


def _batch(args: argparse.Namespace) -> int:
    from gi.batch import render_batch

    def report(entry: dict) -> None:
        if entry["status"] == "ok" and not args.quiet:
            retried = f", attempt {entry['attempts']}" if entry["attempts"] > 1 else ""
            print(
                f"frame {entry['index']}: {', '.join(entry['files'])}"
                f" ({entry['seconds']:.2f}s on {entry['worker']}{retried})",
                file=sys.stderr,
            )
        elif entry["status"] == "failed":
            print(f"frame {entry['index']} failed: {entry['errors'][-1]}", file=sys.stderr)

    summary = render_batch(args.job, address=args.address, retries=args.retries, on_frame=report)
    if not args.quiet or summary["failed"]:
        print(
            f"{summary['ok']} of {len(summary['frames'])} frames rendered, {summary['failed']}"
            f" failed, {summary['retried']} retried ({summary['wall_seconds']:.1f}s)",
            file=sys.stderr,
        )
    return 0 if summary["failed"] == 0 else 1


def _footprints(args: argparse.Namespace) -> int:
    qs = [1.0, 5.0, 25.0, 50.0, 75.0, 95.0, 99.0]
    rows = gi.footprint_radii(
        gi.load_scene(args.scene), args.photons, args.seed, args.smoothing, qs
    )
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
        if args.command == "batch":
            return _batch(args)
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
    except (OSError, ValueError) as e:
        print(f"gi: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("\ngi: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
