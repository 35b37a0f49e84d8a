"""The ``gi`` command line."""

from __future__ import annotations

import argparse
import math
import signal
import sys
import time
import typing
import warnings
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import gi
from gi import denoising
from gi._checks import U64_MAX, exposure_setting, int_setting, named_error
from gi.animation import default_frames
from gi.aovs import BASE, aov_names, check_aovs
from gi.display import TONEMAPS
from gi.io import (
    FLOAT_FORMATS,
    SRGB_FORMATS,
    check_format,
    check_writable,
    planned_files,
    save_result,
    to_srgb8,
)
from gi.patterns import frame_number_count, frame_path, pattern_error
from gi.presets import PROGRESSIVE_PASS, with_preset
from gi.video import VIDEO_FORMATS, VideoWriter

#: What each method is, in one line (`gi methods`; the README's table says more).
METHOD_SUMMARIES = {
    "path": "CPU reference: path tracing with next-event estimation, light vertices by MIS"
    " and light tracing for caustics; unbiased, the ground truth",
    "photon": "classic photon mapping (Jensen): a kd-tree of photons, k-nearest-neighbour"
    " estimate; the baseline",
    "gather": "photon differentials: each shading point gathers the photon footprints that"
    " contain it (Fabianowski & Dingliana 2009)",
    "direct": "GPU direct light only: G-buffer, shadow maps, supersampled at edges",
    "ispm": "image space photon mapping (McGuire & Luebke 2009): GPU direct light, CPU"
    " photon trace, photon volumes splatted on the GPU",
    "bidir": "bidirectional path tracing by rasterization (Tokuyoshi & Ogaki 2012): virtual"
    " point lights and ray bundles combined by MIS",
}


_METHOD_HELP = (
    f"rendering method: {', '.join(gi.methods())} (default {gi.DEFAULT_METHOD}, as in gi.render"
    " and gi.Renderer; `gi methods` says what each is)"
)


def _size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, got {text!r}") from None
    if w <= 0 or h <= 0:
        raise argparse.ArgumentTypeError("width and height must be positive")
    return w, h


def _frames(text: str) -> range:
    try:
        nums = [int(v) for v in text.split(":")]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected START:END[:STEP] or N, got {text!r}") from None
    if len(nums) == 1:
        start, end, step = nums[0], nums[0] + 1, 1
    elif len(nums) in (2, 3):
        start, end, step = nums[0], nums[1], nums[2] if len(nums) == 3 else 1
    else:
        raise argparse.ArgumentTypeError(f"expected START:END[:STEP] or N, got {text!r}")
    if start < 0 or end <= start or step < 1:
        raise argparse.ArgumentTypeError(
            f"frames {text!r}: need 0 <= START < END (END excluded) and STEP >= 1"
        )
    return range(start, end, step)


def _port(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a port number, got {text!r}") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"port {port} is outside 0..65535")
    return port


def _fps(text: str) -> float:
    try:
        fps = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (math.isfinite(fps) and fps > 0):
        raise argparse.ArgumentTypeError(f"must be positive, got {text!r}")
    return fps


class _Parser(argparse.ArgumentParser):
    """argparse, but an error is its one line and where to read more, not the whole usage
    (35 lines for ``gi render``) with the message at its end."""

    def error(self, message: str) -> typing.NoReturn:
        self.exit(2, f"{self.prog}: error: {message}\n(`{self.prog} --help` lists the options)\n")


# Command-line spellings kept from before the options were generated from the table.
_ALIASES = {"progressive_alpha": ["--alpha"], "bundle_memory_mb": ["--bundle-memory"]}


def _option_names() -> list[str]:
    """The render options the command line takes: the table's, but width and height
    (``--size``)."""
    names = dict.fromkeys(row["name"] for row in gi.options_table())
    return [n for n in names if n not in ("width", "height")]


def _shown(default: object) -> str:
    """An option's default as the command line spells it."""
    if default is None:
        return "auto"
    if isinstance(default, bool):
        return "on" if default else "off"
    return str(default)


def _cli_doc(doc: str, name: str) -> str:
    """An option's doc (written for Python) in the command line's words: ``None`` is
    leaving the option out (auto), ``False`` its ``--no-`` flag."""
    flag = name.replace("_", "-")
    return doc.replace("(None: ", "(auto: ").replace("(False: ", f"(--no-{flag}: ")


def _add_options(parser: argparse.ArgumentParser) -> None:
    """One argument per render option of the core's table (:func:`gi.options`), its help
    the option's doc, default and methods; the value is checked by the core."""
    rows: dict[str, list[dict]] = {}
    for row in gi.options_table():
        rows.setdefault(row["name"], []).append(row)
    for name in _option_names():
        variants = rows[name]
        first = variants[0]
        parts = []
        for row in variants:
            default = _shown(row["default"])
            # A method the option's doc excludes ("not method photon": it refuses) is not
            # listed as one that takes it.
            methods = ", ".join(m for m in row["methods"] if f"not method {m}" not in row["doc"])
            parts.append(
                f"{_cli_doc(row['doc'], name)} [{row['range']}; default {default}; {methods}]"
            )
        flags = [f"--{name.replace('_', '-')}", *_ALIASES.get(name, [])]
        kind = first["kind"]
        # argparse expands %-formats in help; the docs have literal percents ("0.5%").
        help_text = "; ".join(parts).replace("%", "%%")
        kw: dict[str, object] = {"default": None, "dest": name, "help": help_text}
        if kind == "bool":
            kw["action"] = argparse.BooleanOptionalAction
        elif kind == "int":
            kw["type"] = int
        elif kind == "float":
            kw["type"] = float
        elif kind == "choice":
            kw["choices"] = first["choices"]
        parser.add_argument(*flags, **kw)  # type: ignore[arg-type]


def _parser() -> argparse.ArgumentParser:
    p = _Parser(prog="gi", description="Global illumination renderer (ISPM).")
    p.add_argument("--version", action="version", version=f"gi {gi.__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("render", help="render a scene to an image")
    r.add_argument(
        "scene",
        help="built-in scene name (see `gi scenes`), JSON scene file, Mitsuba 3 XML or glTF",
    )
    r.add_argument(
        "-o",
        "--output",
        required=True,
        action="append",
        help="output image: .exr (float; AOVs become layers of the same file), .png/.jpg"
        " (8-bit sRGB through --tonemap), .hdr/.pfm/.tif (float); repeat for several. With"
        " --frames: an image sequence named with its frame number (out/frame_%%04d.exr or"
        " out/frame_{frame:04d}.exr, as in batch jobs), or a"
        " video (.mp4, .mov, .mkv)",
    )
    r.add_argument(
        "--frames",
        type=_frames,
        help="render the scene's animation: frames START:END[:STEP] (END excluded) or N;"
        " default with a sequence or video output: the whole animation",
    )
    r.add_argument(
        "--fps", type=_fps, default=30.0, help="frames a second: frame n shows n/fps s (30)"
    )
    r.add_argument("--method", default=gi.DEFAULT_METHOD, help=_METHOD_HELP)
    r.add_argument("--size", type=_size, help="image size WIDTHxHEIGHT (default: the scene's)")
    r.add_argument(
        "--time",
        type=_fps,
        metavar="SECONDS",
        help="render progressively (implies --progressive) until this many seconds have"
        " passed: the pass under way then is dropped, unless it is the first",
    )
    r.add_argument(
        "--passes", type=int, help="render progressively (implies --progressive) this many passes"
    )
    _add_env_options(r)
    _add_options(r)
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
        " depth, caustics; method direct adds direct, ispm direct, specular, indirect, photons,"
        " bidir direct, indirect;"
        " --denoise adds noisy. EXR: layers of the output file; other formats: NAME.AOV.EXT",
    )
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar or summary")
    r.add_argument(
        "-v",
        "--verbose",
        action="store_true",
        help="also print the time of each stage, and which estimator and first-bounce search"
        " ispm chose, and why",
    )
    v = sub.add_parser("view", help="interactive viewer in the browser (pip install 'gi[view]')")
    v.add_argument("scene", help="built-in scene name, JSON scene file, Mitsuba 3 XML or glTF")
    v.add_argument("--method", default=gi.DEFAULT_METHOD, help=_METHOD_HELP)
    v.add_argument(
        "--size",
        type=_size,
        help="image size WIDTHxHEIGHT (default: the scene's); the page keeps its pixel count"
        " and takes the window's aspect",
    )
    _add_env_options(v)
    _add_options(v)
    v.add_argument("--exposure", type=float, default=0.0, help="exposure in stops (0)")
    v.add_argument(
        "--tonemap", default="clip", choices=list(TONEMAPS), help="display transform (clip)"
    )
    v.add_argument(
        "--port", type=_port, default=0, help="TCP port (default 0: a free one; the URL is printed)"
    )
    v.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to serve on (default 127.0.0.1: this machine only; any other warns,"
        " as the viewer has no password)",
    )
    v.add_argument("--no-browser", action="store_true", help="don't open the page in a browser")
    v.add_argument(
        "--env-dir",
        metavar="DIR",
        help="folder whose .hdr/.exr images the Environment panel offers (default: the folder"
        " of --env FILE)",
    )
    sub.add_parser("scenes", help="list the built-in scenes")
    sub.add_parser("methods", help="list the rendering methods, one line each")
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


@dataclass(frozen=True)
class _Output:
    path: str
    video: bool
    numbered: bool

    def at(self, frame: int) -> str:
        """The image file of ``frame`` (the path itself for a still)."""
        return frame_path(self.path, frame)


_output_error = pattern_error


def _outputs(paths: list[str]) -> list[_Output]:
    """Classifies and validates the outputs before anything is rendered."""
    out = []
    for p in paths:
        suffix = Path(p).suffix.lower()
        numbers = frame_number_count(p)
        if numbers > 1:
            raise _output_error(p, "more than one frame number")
        if suffix in VIDEO_FORMATS:
            if numbers:
                raise _output_error(p, "a video takes no frame number")
            out.append(_Output(p, True, False))
        elif suffix in FLOAT_FORMATS | SRGB_FORMATS:
            out.append(_Output(p, False, numbers == 1))
        else:
            images = ", ".join(sorted(FLOAT_FORMATS | SRGB_FORMATS))
            videos = ", ".join(sorted(VIDEO_FORMATS))
            raise _output_error(
                p, f"unsupported output format {suffix!r} (images: {images}; video: {videos})"
            )
    return out


def _is_sequence(args: argparse.Namespace, outputs: list[_Output]) -> bool:
    return args.frames is not None or any(o.video or o.numbered for o in outputs)


def _check_outputs(args: argparse.Namespace, outputs: list[_Output]) -> list[str]:
    """Checks the method, display settings, AOV names and outputs before the scene is
    loaded or anything rendered; returns the AOVs to write. For a sequence the files of its
    first frame are checked here, those of every frame once the frames are known
    (:func:`_check_files`)."""
    exposure_setting(args.exposure)
    if args.denoise and not denoising.available():
        raise named_error("denoise", denoising.INSTALL_HINT)
    if args.method not in gi.methods():
        raise named_error(
            "method", f"unknown method {args.method!r} (use {', '.join(gi.methods())})"
        )
    # --time and --passes imply --progressive (they mean nothing else).
    if args.time is not None or args.passes is not None:
        if args.progressive is False:
            raise named_error("progressive", "--time and --passes render progressively")
        args.progressive = True
    sequence = _is_sequence(args, outputs)
    if args.progressive:
        if sequence:
            raise named_error(
                "progressive",
                "--progressive renders one still image: not with --frames, an image"
                " sequence or a video",
            )
        if args.time is None and args.passes is None:
            raise named_error("progressive", "--progressive needs --time SECONDS or --passes N")
        if args.passes is not None and args.passes < 1:
            raise named_error("passes", f"--passes must be at least 1, got {args.passes}")
    names = aov_names(args.method, args.denoise)
    wanted = names[1:] if "all" in args.aov else list(dict.fromkeys(args.aov))
    check_aovs(args.method, wanted, args.denoise)
    if sequence:
        for o in outputs:
            if not o.video and not o.numbered:
                raise _output_error(
                    o.path,
                    "an image sequence needs a frame number in its name, e.g. out/frame_%04d.exr",
                )
        if wanted and all(o.video for o in outputs):
            raise named_error("aov", "--aov needs an image-sequence output (videos hold none)")
    _check_files(outputs, wanted, [args.frames[0] if args.frames is not None else 0])
    _warn_display_unused(args, outputs)
    return wanted


def _warn_display_unused(args: argparse.Namespace, outputs: list[_Output]) -> None:
    """``--exposure`` and ``--tonemap`` change the 8-bit outputs (and videos) only: with
    float outputs alone they would change nothing, so say so rather than ignore them."""
    if any(o.video or Path(o.path).suffix.lower() in SRGB_FORMATS for o in outputs):
        return
    given = []
    if args.exposure != 0.0:
        given.append("--exposure")
    if args.tonemap != "clip":
        given.append("--tonemap")
    if given:
        floats = ", ".join(sorted({Path(o.path).suffix.lower() for o in outputs}))
        verb = "change" if len(given) > 1 else "changes"
        print(
            f"gi: warning: {' and '.join(given)} {verb} only 8-bit outputs (.png, .jpg) and"
            f" videos; the {floats} output stores linear radiance as rendered (add a .png"
            " output, or scale the values when reading them)",
            file=sys.stderr,
        )


def _warn_past_the_end(scene: gi.Scene, source: str, frames: range, fps: float) -> None:
    """Frames past the end of the animation all show its last pose: say so, and how many."""
    duration = scene.animation_duration
    if duration is None:
        print(
            f"gi: warning: {source} has no animation: the {len(frames)} frames are all the"
            " same image",
            file=sys.stderr,
        )
        return
    past = [n for n in frames if n / fps > duration * (1 + 1e-9)]
    if past:
        end = max(1, round(duration * fps))
        print(
            f"gi: warning: {len(past)} of the {len(frames)} frames ({past[0]}..{past[-1]}) are"
            f" past the end of {source}'s {duration:g} s animation (frames 0..{end - 1} at"
            f" {fps:g} fps): they all show its last pose",
            file=sys.stderr,
        )


def _check_files(outputs: list[_Output], aovs: list[str], frames: Iterable[int]) -> None:
    """Every file the outputs write for ``frames``: a known format, in a directory that can
    be written (each tried once), and written once."""
    seen: set[Path] = set()
    directories: set[Path] = set()
    planned = [(o, [Path(o.path)]) for o in outputs if o.video]
    for n in frames:
        planned += [(o, planned_files(o.at(n), aovs)) for o in outputs if not o.video]
    for o, targets in planned:
        for t in targets:
            if not o.video:
                check_format(t)
            key = t.absolute()
            if key in seen:
                raise _output_error(o.path, f"{t} would be written twice")
            seen.add(key)
            if key.parent not in directories:
                check_writable(t)
                directories.add(key.parent)


def _add_env_options(parser: argparse.ArgumentParser) -> None:
    """``--env`` and its settings (:mod:`gi.lighting`)."""
    g = parser.add_argument_group("environment light (gi.lighting)")
    g.add_argument(
        "--env",
        metavar="FILE|sky",
        help="light the scene with an equirectangular HDR image (.hdr, .exr) or the built-in"
        " sky with a sun ('sky')",
    )
    g.add_argument("--env-strength", type=float, default=1.0, help="scale of --env (1)")
    g.add_argument("--env-rotation", type=float, default=0.0, help="degrees about +y of --env (0)")
    g.add_argument(
        "--sun",
        metavar="X,Y,Z|none",
        help="--env sky: direction towards the sun (default 0.5,0.7071,0.5), or none",
    )
    g.add_argument(
        "--env-mode",
        choices=["add", "replace"],
        default="add",
        help="add to the scene's light (default) or replace its lights and environment",
    )


def _lit(args: argparse.Namespace, scene: gi.Scene) -> gi.Scene:
    """``scene`` lit by ``--env`` (unchanged without it)."""
    if args.env is None:
        if args.sun is not None:
            raise named_error("sun", "--sun goes with --env sky")
        return scene
    from gi.lighting import with_environment

    spec: dict[str, object] = {
        "source": args.env,
        "strength": args.env_strength,
        "rotation": args.env_rotation,
        "mode": args.env_mode,
    }
    if args.sun is not None:
        try:
            spec["sun"] = None if args.sun == "none" else [float(x) for x in args.sun.split(",")]
        except ValueError as e:
            raise named_error("sun", f"--sun X,Y,Z or none, got {args.sun!r}") from e
    return with_environment(scene, spec)


def _load(source: str) -> gi.Scene:
    """Loads a scene; what its files hold that gi does not render is printed as it is found
    (:func:`_show_warning`), so also when loading then fails."""
    return gi.load_scene(source)


#: Warnings printed as ``gi: warning: ...`` (each time, not once per place).
_GI_WARNINGS = (gi.AssetWarning, gi.SceneWarning, gi.RenderWarning)


def _show_warning(message, category, filename, lineno, file=None, line=None):  # type: ignore[no-untyped-def]
    if issubclass(category, _GI_WARNINGS):
        print(f"gi: warning: {message}", file=sys.stderr)
    else:
        _default_showwarning(message, category, filename, lineno, file, line)


_default_showwarning = warnings.showwarning


def _settings(args: argparse.Namespace) -> dict[str, object]:
    """The render options given on the command line (the rest take the core's defaults)."""
    given: dict[str, object] = {}
    for name in _option_names():
        value = getattr(args, name)
        if value is not None:
            given[name] = value
    if args.size is not None:
        given["size"] = args.size
    return given


def _render(args: argparse.Namespace) -> int:
    outputs = _outputs(args.output)
    aovs = _check_outputs(args, outputs)
    if _is_sequence(args, outputs):
        return _render_sequence(args, outputs, aovs)
    if args.progressive:
        return _render_progressive(args, aovs)
    scene = _lit(args, _load(args.scene))
    result = gi.render(
        scene,
        args.method,
        **_settings(args),  # type: ignore[arg-type]
        progress=not args.quiet,
        denoise=args.denoise,
    )
    written: list[Path] = []
    for out in args.output:
        written += save_result(out, result, aovs, tonemap=args.tonemap, exposure=args.exposure)
    if not args.quiet:
        s = result.stats
        files = ", ".join(map(str, written))
        print(f"wrote {files} ({s.method}, {s.total_seconds:.2f}s)", file=sys.stderr)
        _print_choices(args, result)
        _print_stages(args, result)
    return 0


def _print_choices(args: argparse.Namespace, result: gi.RenderResult) -> None:
    """``-v``: what ispm's automatic choices chose, and why."""
    s = result.stats
    if args.verbose and s.estimator:
        print(f"estimator {s.estimator}: {s.estimator_reason}", file=sys.stderr)
    if args.verbose and s.first_bounce:
        print(f"first bounce {s.first_bounce}: {s.first_bounce_reason}", file=sys.stderr)
    if args.verbose and s.photon_trace:
        print(f"photon trace {s.photon_trace}: {s.photon_trace_reason}", file=sys.stderr)
        if s.photon_records:
            print(f"photon records {s.photon_records}", file=sys.stderr)


def _progressive_settings(args: argparse.Namespace) -> dict[str, object]:
    """The options of one progressive pass: those given, else
    :data:`gi.presets.PROGRESSIVE_PASS`."""
    given = _settings(args)
    return {**with_preset(PROGRESSIVE_PASS.get(args.method, {}), given), "progressive": True}


#: The stages of the methods' frames in the order they run (the GPU's, timed by queries,
#: are reported after the CPU's); a stage not listed keeps its place after these.
PIPELINE = (
    "bvh build",
    "upload",
    "shadow maps",
    "rsm",
    "rsm readback",
    "vpl sampling",
    "vpls",
    "vpl shadow maps",
    "light subpaths",
    "ray bundles",
    "gbuffer",
    "gbuffer readback",
    "edges",
    "edge mask",
    "direct light",
    "edge shading",
    "camera paths",
    "light paths",
    "bounce maps",
    "bounce trace",
    "photon trace",
    "sky pilot",
    "cpu trace",
    "gpu trace upload",
    "gpu trace",
    "boundary compensation",
    "specular paths",
    "photon collect",
    "photon lists regrown",
    "kd-tree build",
    "photon map build",
    "photon upload",
    "cpu estimate",
    "radiance estimate",
    "bidir lighting",
    "upsample",
    "composite",
    "readback",
    "earlier passes",
)


def pipeline_order(stages: list[tuple[str, float]]) -> list[tuple[str, float]]:
    """``stats.stages`` in the order the frame runs them (:data:`PIPELINE`)."""
    rank = {name: i for i, name in enumerate(PIPELINE)}
    return sorted(stages, key=lambda s: rank.get(s[0], len(PIPELINE)))


def _print_stages(args: argparse.Namespace, result: gi.RenderResult) -> None:
    """``-v``: the time of each stage, in pipeline order, one a line."""
    if args.verbose:
        for name, seconds in pipeline_order(result.stats.stages):
            print(f"  {name:24} {seconds:7.3f} s", file=sys.stderr)


def _render_progressive(args: argparse.Namespace, aovs: list[str]) -> int:
    """``--progressive``: passes until ``--time`` or ``--passes``; Ctrl-C keeps the passes
    done so far and writes them."""
    scene = _lit(args, _load(args.scene))
    options = _progressive_settings(args)
    renderer = gi.Renderer(scene, args.method, **options)
    interrupted = False

    def on_interrupt(_sig: int, _frame: object) -> None:
        nonlocal interrupted
        interrupted = True
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGINT, on_interrupt)
    try:
        result = renderer.render_progressive(
            passes=args.passes,
            seconds=args.time,
            aovs=True,
            extras=any(a not in BASE for a in aovs),
            progress=not args.quiet,
        )
    finally:
        signal.signal(signal.SIGINT, previous)
    if args.denoise:
        result = gi.denoise(result)
    written: list[Path] = []
    for out in args.output:
        written += save_result(out, result, aovs, tonemap=args.tonemap, exposure=args.exposure)
    if not args.quiet or interrupted:
        files = ", ".join(map(str, written))
        why = "interrupted, " if interrupted else ""
        each = ", ".join(
            f"{k} {v}" for k, v in options.items() if k in ("spp", "photons", "subsample")
        )
        print(
            f"wrote {files} ({result.stats.method}, progressive: {why}{result.stats.passes}"
            f" passes{f' of {each}' if each else ''}, {result.stats.total_seconds:.1f}s)",
            file=sys.stderr,
        )
        _print_choices(args, result)
        _print_stages(args, result)
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


def _render_sequence(args: argparse.Namespace, outputs: list[_Output], aovs: list[str]) -> int:
    """Renders frames of the scene's animation to image sequences and videos: each frame's
    images are written like a still's (:func:`gi.save_result`), after every file of every
    frame was checked."""
    scene = _lit(args, _load(args.scene))
    if args.frames is None and scene.animation_duration is None:
        raise named_error(
            "frames", f"{args.scene} has no animation: give the frames (--frames START:END)"
        )
    frames = args.frames if args.frames is not None else default_frames(scene, args.fps)
    if args.frames is not None:
        _warn_past_the_end(scene, args.scene, frames, args.fps)
    _check_files(outputs, aovs, frames)
    renderer = gi.Renderer(scene, args.method, **_settings(args))
    videos = [o for o in outputs if o.video]
    w, h = renderer.size
    if videos and VideoWriter.padded_size(w, h) != (w, h):
        pw, ph = VideoWriter.padded_size(w, h)
        print(
            f"gi: warning: {', '.join(o.path for o in videos)}: H.264 (yuv420p) needs even"
            f" sizes: the {w}x{h} frames are padded to {pw}x{ph} by repeating the last"
            " column or row (give an even --size to avoid it)",
            file=sys.stderr,
        )
    sequence = renderer.render_animation(
        frames,
        args.fps,
        aovs=args.denoise or any(a in BASE for a in aovs),
        extras=any(a not in BASE and a != "noisy" for a in aovs),
        progress=not args.quiet,
    )
    writers = [VideoWriter(o.path, args.fps) for o in videos]
    start = time.monotonic()
    try:
        for n, result in sequence:
            if args.denoise:
                result = gi.denoise(result)
            for o in outputs:
                if not o.video:
                    save_result(o.at(n), result, aovs, tonemap=args.tonemap, exposure=args.exposure)
            frame = to_srgb8(result.radiance, args.exposure, args.tonemap)
            for w in writers:
                w.write(frame)
        for w in writers:
            w.close()
    except BaseException:
        for w in writers:
            w.abort()
        raise
    if not args.quiet:
        seconds = time.monotonic() - start
        files = ", ".join(o.path for o in outputs)
        print(
            f"wrote {len(frames)} frames ({frames[0]}..{frames[-1]}, {args.fps:g} fps) to"
            f" {files} ({renderer.method}, {seconds:.1f}s, {seconds / len(frames):.2f}s a frame)",
            file=sys.stderr,
        )
    return 0


def _view(args: argparse.Namespace) -> int:
    """``gi view``: serves the viewer until Ctrl-C."""
    from gi import viewer

    if args.method not in gi.methods():
        raise gi.SettingError(f"unknown method {args.method!r} (use {', '.join(gi.methods())})")
    scene = _lit(args, _load(args.scene))
    env_dir = args.env_dir
    if env_dir is None and args.env not in (None, "sky"):
        env_dir = str(Path(args.env).resolve().parent)
    return viewer.serve(
        scene,
        args.method,
        _settings(args),
        host=args.host,
        port=args.port,
        open_browser=not args.no_browser,
        exposure=args.exposure,
        tonemap=args.tonemap,
        env_dir=env_dir,
    )


def _footprints(args: argparse.Namespace) -> int:
    qs = [1.0, 5.0, 25.0, 50.0, 75.0, 95.0, 99.0]
    # footprint_radii takes unsigned integers and checks the ranges of photons and
    # smoothing: values outside them are passed as ones it refuses with its range.
    photons = min(max(args.photons, 0), U64_MAX)
    smoothing = args.smoothing if math.isfinite(args.smoothing) else 0.0
    seed = int_setting("seed", args.seed, U64_MAX)
    rows = gi.footprint_radii(_load(args.scene), photons, seed, smoothing, qs)
    # The count is of stored hits: one emitted photon stores a hit at each diffuse bounce,
    # so a kind may count more hits than photons were emitted.
    print(
        f"footprint radius (m) by percentile of the photon hits stored, by path kind;"
        f" {args.photons} photons emitted, s = {args.smoothing}"
    )
    print(f"{'kind':8} {'hits':>9} " + " ".join(f"{f'p{q:g}':>8}" for q in qs))
    for kind, (count, radii) in rows.items():
        print(f"{kind:8} {count:9d} " + " ".join(f"{r:8.4f}" for r in radii))
    return 0


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    with warnings.catch_warnings():
        for category in _GI_WARNINGS:
            warnings.simplefilter("always", category)
        warnings.showwarning = _show_warning
        try:
            return run(args)
        except (gi.GiError, OSError, ValueError) as e:
            # OSError: what the operating system refused outside gi's own checks; ValueError:
            # the viewer's (every render and output error is a gi.GiError, tests/
            # test_typed_errors.py).
            print(f"gi: error: {e}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:
            print("\ngi: interrupted", file=sys.stderr)
            return 130


def run(args: argparse.Namespace) -> int:
    """Runs a parsed command; errors are raised (:class:`gi.GiError` for every input error
    gi checks), :func:`main` prints them."""
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
    if args.command == "view":
        return _view(args)
    if args.command == "methods":
        # One line a method; the default's says so (of every entry point: gi.DEFAULT_METHOD).
        for name in gi.methods():
            default = "(the default) " if name == gi.DEFAULT_METHOD else ""
            print(f"{name:8} {default}{METHOD_SUMMARIES.get(name, '')}".rstrip())
        return 0
    return _render(args)


if __name__ == "__main__":
    sys.exit(main())
