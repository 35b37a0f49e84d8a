"""Batch rendering on Ray: the frames of a camera animation, or a sweep of scenes/settings.

A job (a dict, or a JSON file for ``gi batch JOB.json``)::

    {
      "scene": "cornell",                      # built-in name or scene file (relative to the job)
      "method": "path",                        # default: gi.DEFAULT_METHOD (ispm)
      "settings": {"spp": 16, "size": [64, 64], "seed": 0},   # gi.render keywords
      "frames": [0, 8],                        # frames 0..7; frame f uses seed + f
      "camera": [                              # optional keyframes, linearly interpolated
        {"frame": 0, "position": [0, 1, 3.4]},
        {"frame": 7, "position": [0.5, 1, 3.2], "look_at": [0, 1, 0]}
      ],
      "sweep": [{"method": "ispm"}, {"settings": {"spp": 64}}, {"scene": "cornell-glass"}],
      "output": "out/{scene}_{method}_{index:03d}.exr",   # or "outputs": [...]
      "aovs": ["albedo", "normal"], "tonemap": "clip", "exposure": 0, "denoise": false,
      "retries": 2, "cpus_per_frame": 1,
      "summary": "out/summary.json"
    }

Every ``sweep`` entry (default: one empty entry) is rendered for every frame; an entry
overrides ``scene``, ``method``, ``settings`` (merged), ``camera``, ``aovs`` or
``denoise``. Output patterns take ``{index}`` (0, 1, … over the whole batch), ``{frame}``,
``{variant}`` (the sweep entry), ``{scene}`` (the scene's file stem or name) and
``{method}``; the frame also as ``gi render`` writes it, ``%04d`` (:mod:`gi.patterns`).
Everything (outputs, formats, AOV names, settings names, scenes) is checked before a frame
starts.

Frames run as Ray tasks: on a local Ray started for the batch, or on the cluster that
``RAY_ADDRESS`` (or ``address=``) names. Each worker process keeps one ``gi.Renderer`` per
scene, method and settings warm across the frames it renders (the camera is updated per
frame, the seed set per frame, so a frame's image does not depend on the worker). Workers
return the images and the driver writes the files, so they land where the batch started.
A frame whose worker dies or that raises is submitted again up to ``retries`` times;
every frame is reported in the summary (status, attempts, errors, files, per-stage
seconds, worker).
"""

from __future__ import annotations

import json
import logging
import os
import socket
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gi
from gi._checks import named_error
from gi.aovs import check_aovs
from gi.display import check_tonemap
from gi.io import check_output_path, check_writable, planned_files, save_result
from gi.patterns import frame_path

CAMERA_FIELDS = ("position", "look_at", "up", "fov")
JOB_KEYS = {
    "scene",
    "method",
    "settings",
    "frames",
    "camera",
    "sweep",
    "output",
    "outputs",
    "aovs",
    "tonemap",
    "exposure",
    "denoise",
    "retries",
    "cpus_per_frame",
    "summary",
}
SWEEP_KEYS = {"scene", "method", "settings", "camera", "aovs", "denoise"}


@dataclass(frozen=True)
class Frame:
    """One render of a batch, as sent to a worker."""

    index: int
    frame: int
    variant: int
    scene: str  # a built-in name or an absolute scene-file path
    camera: dict[str, Any] | None  # camera fields of this frame (animation), else None
    method: str
    settings: dict[str, Any]
    denoise: bool
    outputs: list[str] = field(default_factory=list)
    aovs: list[str] = field(default_factory=list)


def _render_keywords() -> set[str]:
    """The render options a job's settings may name: the core's table, and ``size``."""
    return {row["name"] for row in gi.options_table()} | {"size"}


def _scene_label(scene: str) -> str:
    return Path(scene).stem if scene.endswith(".json") else scene


def _resolve(scene: str, base_dir: Path) -> str:
    """A scene file relative to the job, as an absolute path; a built-in name as it is."""
    path = base_dir / scene
    names = [n for n, _ in gi.builtin_scenes()]
    return scene if (not path.exists() and scene in names) else str(path.resolve())


def _base_camera(scene: str) -> dict[str, Any]:
    """The scene's own camera fields (scene-format defaults where the file has none)."""
    if Path(scene).is_absolute():
        desc = json.loads(Path(scene).read_text(encoding="utf-8"))
    else:
        desc = json.loads(gi.builtin_json(scene))
    camera = desc.get("camera", {}) if isinstance(desc, dict) else {}
    base = {"up": [0.0, 1.0, 0.0], "fov": 40.0}
    return {**base, **{k: camera[k] for k in CAMERA_FIELDS if k in camera}}


def _interpolate(
    keys: list[dict[str, Any]], frame: int, base: dict[str, Any] | None = None
) -> dict[str, Any]:
    """Camera fields at ``frame``: linear between the keyframes around it, held outside;
    fields no keyframe sets come from ``base``. All four fields are always given so that a
    renderer's camera update is absolute (a partial update keeps the renderer's previous,
    re-orthogonalised ``up``, and images would depend on the frames rendered before)."""
    keys = sorted(keys, key=lambda k: k["frame"])
    out: dict[str, Any] = dict(base or {})
    for name in CAMERA_FIELDS:
        have = [k for k in keys if name in k]
        if not have:
            continue
        before = [k for k in have if k["frame"] <= frame]
        after = [k for k in have if k["frame"] >= frame]
        a = before[-1] if before else after[0]
        b = after[0] if after else before[-1]
        t = 0.0 if a["frame"] == b["frame"] else (frame - a["frame"]) / (b["frame"] - a["frame"])
        va, vb = a[name], b[name]
        if isinstance(va, list):
            out[name] = [float(x) + t * (float(y) - float(x)) for x, y in zip(va, vb, strict=True)]
        else:
            out[name] = float(va) + t * (float(vb) - float(va))
    return out


def _check_camera(keys: Any) -> list[dict[str, Any]]:
    if not isinstance(keys, list) or not keys:
        raise named_error("job", "camera: expected a list of keyframes")
    for i, k in enumerate(keys):
        if not isinstance(k, dict) or not isinstance(k.get("frame"), int):
            raise named_error("job", f"camera[{i}]: each keyframe needs an integer 'frame'")
        unknown = set(k) - {"frame", *CAMERA_FIELDS}
        if unknown:
            raise named_error("job", f"camera[{i}]: unknown field {sorted(unknown)[0]!r}")
    return keys


def plan(job: dict[str, Any], base_dir: str | Path = ".") -> list[Frame]:
    """Expands and checks a job (see the module doc) into its frames, rendering nothing.

    Raises ``ValueError``/``OSError`` (bad job, outputs, formats or AOV names) or
    :class:`gi.SceneError` (a scene that does not load).
    """
    base = Path(base_dir)
    if not isinstance(job, dict):
        raise named_error("job", "a job is a JSON object")
    unknown = set(job) - JOB_KEYS
    if unknown:
        raise named_error(
            "job", f"unknown job field {sorted(unknown)[0]!r} (known: {sorted(JOB_KEYS)})"
        )
    frames_field = job.get("frames", [0, 1])
    if (
        not isinstance(frames_field, list)
        or len(frames_field) != 2
        or not all(isinstance(v, int) for v in frames_field)
        or frames_field[1] <= frames_field[0]
    ):
        raise named_error("job", "frames: expected [start, end) with end > start")
    sweep = job.get("sweep", [{}])
    if not isinstance(sweep, list) or not sweep:
        raise named_error("job", "sweep: expected a non-empty list of overrides")
    outputs = job.get("outputs", [job["output"]] if "output" in job else [])
    if not outputs or not all(isinstance(o, str) for o in outputs):
        raise named_error("job", "output: give an output pattern ('output' or 'outputs')")
    check_tonemap(job.get("tonemap", "clip"))
    keywords = _render_keywords()
    methods = gi.methods()

    frames: list[Frame] = []
    planned: set[Path] = set()
    scenes: set[str] = set()
    cameras: dict[str, dict[str, Any]] = {}
    for variant, entry in enumerate(sweep):
        if not isinstance(entry, dict) or set(entry) - SWEEP_KEYS:
            raise named_error(
                "job", f"sweep[{variant}]: expected an object with fields {sorted(SWEEP_KEYS)}"
            )
        scene = str(entry.get("scene", job.get("scene", "cornell")))
        method = str(entry.get("method", job.get("method", gi.DEFAULT_METHOD)))
        if method not in methods:
            raise named_error(
                "job", f"sweep[{variant}]: unknown method {method!r} (use {', '.join(methods)})"
            )
        settings = {**job.get("settings", {}), **entry.get("settings", {})}
        bad = set(settings) - keywords
        if bad:
            raise named_error(
                "job", f"settings: unknown {sorted(bad)[0]!r} (gi.render takes {sorted(keywords)})"
            )
        if "size" in settings:
            settings["size"] = tuple(settings["size"])
        denoise = bool(entry.get("denoise", job.get("denoise", False)))
        aovs = list(entry.get("aovs", job.get("aovs", [])))
        check_aovs(method, aovs, denoise)
        camera = entry.get("camera", job.get("camera"))
        if camera is not None:
            _check_camera(camera)
        scene = _resolve(scene, base)
        if scene not in scenes:
            gi.load_scene(scene)  # a SceneError now rather than in every worker
            scenes.add(scene)
            cameras[scene] = _base_camera(scene)
        for f in range(*frames_field):
            index = len(frames)
            names = {
                "index": index,
                "frame": f,
                "variant": variant,
                "scene": _scene_label(scene),
                "method": method,
            }
            try:
                # The frame number as gi render writes it too (%04d), else str.format's.
                outs = [str(base / frame_path(o, f).format(**names)) for o in outputs]
            except (KeyError, IndexError, ValueError) as e:
                raise named_error("job", f"output pattern: {e} (use {sorted(names)})") from None
            for o in outs:
                for p in planned_files(o, aovs):
                    check_output_path(p)
                    key = p.resolve()
                    if key in planned:
                        raise named_error(
                            "job",
                            f"{p} would be written by two frames: put {{index}} or {{frame}}"
                            " in the output pattern",
                        )
                    planned.add(key)
            seed = int(settings.get("seed", 0)) + f
            frames.append(
                Frame(
                    index=index,
                    frame=f,
                    variant=variant,
                    scene=scene,
                    camera=_interpolate(camera, f, cameras[scene]) if camera else None,
                    method=method,
                    settings={**settings, "seed": seed},
                    denoise=denoise,
                    outputs=outs,
                    aovs=aovs,
                )
            )
    return frames


_RENDERERS: dict[str, gi.Renderer] = {}


def _renderer(frame: Frame) -> gi.Renderer:
    """This worker's renderer for the frame's scene, method and settings, made on its
    first such frame and kept warm (GPU state, BVH) for the next ones."""
    settings = {k: v for k, v in frame.settings.items() if k != "seed"}
    key = json.dumps([frame.scene, frame.method, settings], sort_keys=True, default=list)
    if key not in _RENDERERS:
        while len(_RENDERERS) >= 4:
            _RENDERERS.pop(next(iter(_RENDERERS)))
        _RENDERERS[key] = gi.Renderer(gi.load_scene(frame.scene), frame.method, **settings)
    return _RENDERERS[key]


def render_frame(frame: Frame) -> tuple[gi.RenderResult, str]:
    """Renders one frame (what a Ray task runs); returns the result and ``host:pid``.

    The frame's seed is set explicitly and its camera (when animated) completely, so the
    image does not depend on which frames this worker rendered before.
    """
    renderer = _renderer(frame)
    if frame.camera is not None:
        renderer.update(camera=frame.camera)
    result = renderer.render(aovs=True, extras=True, seed=int(frame.settings.get("seed", 0)))
    if frame.denoise:
        result = gi.denoise(result)
    return result, f"{socket.gethostname()}:{os.getpid()}"


def _ray():  # type: ignore[no-untyped-def]
    try:
        import ray
    except ImportError as e:
        raise gi.SettingError("batch rendering needs Ray: pip install 'gi[batch]'") from e
    return ray


def _drop_token_auth_notice(record: logging.LogRecord) -> bool:
    return not record.getMessage().startswith("Token authentication is enabled")


def _quiet_token_auth_notice() -> None:
    """Ray (2.5x) announces on every start that the local cluster it starts uses token
    authentication, the secure default; a batch prints its frames, not that. Its warning
    that authentication is *disabled* is kept."""
    logger = logging.getLogger("ray._private.authentication.authentication_token_setup")
    if _drop_token_auth_notice not in logger.filters:
        logger.addFilter(_drop_token_auth_notice)


def render_batch(
    job: dict[str, Any] | str | Path,
    *,
    address: str | None = None,
    retries: int | None = None,
    base_dir: str | Path | None = None,
    on_frame: Any = None,
) -> dict[str, Any]:
    """Renders a batch job (a dict or a JSON job file) as Ray tasks; returns its summary.

    ``address`` is a Ray cluster (default: ``RAY_ADDRESS``, else a local Ray started for
    this batch and stopped after it). ``retries`` overrides the job's (default 2).
    ``on_frame(entry)`` is called with each frame's summary entry as it completes. The
    summary is also written to the job's ``summary`` file when it names one.
    """
    if not isinstance(job, dict):
        path = Path(job)
        try:
            job = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, json.JSONDecodeError) as e:
            raise named_error("job", f"cannot read job {path}: {e}") from e
        base_dir = path.parent if base_dir is None else base_dir
    assert isinstance(job, dict)
    base = Path(base_dir if base_dir is not None else ".")
    frames = plan(job, base)
    summary_path = job.get("summary")
    if summary_path is not None:
        check_writable(base / summary_path)
    retries = int(job.get("retries", 2)) if retries is None else retries
    tonemap, exposure = job.get("tonemap", "clip"), float(job.get("exposure", 0.0))

    ray = _ray()
    started_here = not ray.is_initialized()
    if started_here:
        _quiet_token_auth_notice()
        ray.init(
            address=address or os.environ.get("RAY_ADDRESS"),
            include_dashboard=False,
            log_to_driver=False,
            logging_level=logging.WARNING,
            configure_logging=True,
        )
    task = ray.remote(num_cpus=float(job.get("cpus_per_frame", 1)), max_retries=0)(render_frame)
    t0 = time.perf_counter()
    entries: dict[int, dict[str, Any]] = {
        f.index: {
            "index": f.index,
            "frame": f.frame,
            "variant": f.variant,
            "scene": f.scene,
            "method": f.method,
            "status": "pending",
            "attempts": 0,
            "errors": [],
            "files": [],
        }
        for f in frames
    }
    try:
        pending: dict[Any, Frame] = {}

        def submit(f: Frame) -> None:
            entries[f.index]["attempts"] += 1
            pending[task.remote(f)] = f

        for f in frames:
            submit(f)
        while pending:
            done, _ = ray.wait(list(pending), num_returns=1)
            f = pending.pop(done[0])
            entry = entries[f.index]
            try:
                result, worker = ray.get(done[0])
            except Exception as e:  # a dead worker, a lost node, or the frame's own error
                entry["errors"].append(f"{type(e).__name__}: {str(e).splitlines()[0][:300]}")
                if entry["attempts"] <= retries:
                    submit(f)
                    continue
                entry["status"] = "failed"
            else:
                files = []
                for out in f.outputs:
                    files += save_result(out, result, f.aovs, tonemap=tonemap, exposure=exposure)
                s = result.stats
                entry.update(
                    status="ok",
                    worker=worker,
                    files=[str(p) for p in files],
                    seconds=s.total_seconds,
                    stages=[[n, t] for n, t in s.stages],
                    samples_per_pixel=s.samples_per_pixel,
                )
            if on_frame is not None:
                on_frame(entry)
    finally:
        if started_here:
            ray.shutdown()
    ordered = [entries[i] for i in sorted(entries)]
    summary = {
        "gi": gi.__version__,
        "frames": ordered,
        "ok": sum(e["status"] == "ok" for e in ordered),
        "failed": sum(e["status"] == "failed" for e in ordered),
        "retried": sum(e["attempts"] > 1 for e in ordered),
        "wall_seconds": time.perf_counter() - t0,
    }
    if summary_path is not None:
        target = base / summary_path
        target.parent.mkdir(parents=True, exist_ok=True)
        tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
        tmp.write_text(json.dumps(summary, indent=2))
        os.replace(tmp, target)
    return summary
