"""`gi batch` on a local Ray: the frames equal one-process renders, and a worker killed
mid-batch loses no frame. Each test starts (and stops) its own local Ray, ~10 s."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import gi
from gi import batch
from gi.scene import scene_from_desc

CAMERA = [
    # Frame 0 is the built-in camera; the eye then moves right and closer by frame 7.
    {"frame": 0, "position": [0, 1, 3.4], "look_at": [0, 1, 0]},
    {"frame": 7, "position": [0.6, 1.1, 3.0]},
]


def job(**extra):
    return {
        "scene": "cornell",
        "method": "path",
        "settings": {"spp": 2, "size": [24, 24], "seed": 3},
        "frames": [0, 8],
        "camera": CAMERA,
        "output": "frames/f{frame:02d}.exr",
        "aovs": ["depth"],
        "summary": "frames/summary.json",
        **extra,
    }


def write_job(tmp_path: Path, desc: dict) -> Path:
    path = tmp_path / "job.json"
    path.write_text(json.dumps(desc))
    return path


def run_batch(job_path: Path, **kw):
    return subprocess.Popen(
        [sys.executable, "-m", "gi.cli", "batch", str(job_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kw,
    )


def test_batch_frames_equal_single_process_renders(tmp_path):
    desc = job()
    p = run_batch(write_job(tmp_path, desc))
    out, err = p.communicate(timeout=300)
    assert p.returncode == 0, err
    assert "Token authentication" not in err  # Ray's notice on every start (issue 46)
    summary = json.loads((tmp_path / "frames" / "summary.json").read_text())
    assert summary["ok"] == 8 and summary["failed"] == 0
    assert [e["frame"] for e in summary["frames"]] == list(range(8))
    assert all(e["stages"] and e["worker"] for e in summary["frames"])

    frames = batch.plan(desc, tmp_path)
    images = []
    for f in reversed(frames):  # another order than the workers': the result must not care
        local, _ = batch.render_frame(f)
        channels = gi.read_channels(f.outputs[0])
        got = np.stack([channels[c] for c in "RGB"], axis=-1)
        # The same seed gives the same image on any worker: exact equality.
        assert np.array_equal(got, local.radiance), f.index
        assert np.array_equal(channels["Z"], local.depth), f.index
        images.append(got)
    images.reverse()
    # Independently of the batch code: frame 0 is the built-in camera (the first keyframe)
    # with seed 3 + 0, and frame 7 the last keyframe, set in the scene file, with seed 3 + 7.
    plain = gi.render(gi.load_scene("cornell"), "path", spp=2, size=(24, 24), seed=3)
    assert np.array_equal(images[0], plain.radiance)
    desc7 = json.loads(gi.builtin_json("cornell"))
    desc7["camera"].update(position=[0.6, 1.1, 3.0], look_at=[0, 1, 0])
    scene7 = scene_from_desc(desc7, "cornell-7", tmp_path)
    last = gi.render(scene7, "path", spp=2, size=(24, 24), seed=10)
    assert np.array_equal(images[7], last.radiance)
    assert not np.allclose(images[0], images[7], atol=0.05)


def _ray_task_pids(name: str) -> list[int]:
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            cmdline = Path(f"/proc/{entry}/cmdline").read_bytes()
        except OSError:
            continue
        if cmdline.startswith(f"ray::{name}".encode()):
            pids.append(int(entry))
    return pids


def test_killed_worker_still_yields_all_frames(tmp_path):
    # Frames of ~1 s each, so that one is surely running when its worker is killed.
    desc = job(settings={"spp": 48, "size": [48, 48], "seed": 3}, retries=2)
    p = run_batch(write_job(tmp_path, desc))
    killed = None
    deadline = time.monotonic() + 120
    while killed is None and time.monotonic() < deadline and p.poll() is None:
        pids = _ray_task_pids("render_frame")
        if pids:
            killed = pids[0]
            os.kill(killed, signal.SIGKILL)
        else:
            time.sleep(0.02)
    out, err = p.communicate(timeout=300)
    assert killed is not None, "no Ray worker was seen running a frame"
    assert p.returncode == 0, err
    summary = json.loads((tmp_path / "frames" / "summary.json").read_text())
    assert summary["ok"] == 8 and summary["failed"] == 0, summary
    retried = [e for e in summary["frames"] if e["attempts"] > 1]
    assert len(retried) >= 1 and "Worker" in retried[0]["errors"][0], summary
    assert "attempt 2" in err
    for e in summary["frames"]:
        assert Path(e["files"][0]).is_file()


def test_bad_jobs_are_refused_before_any_frame(tmp_path):
    with pytest.raises(ValueError, match="two frames"):
        batch.plan(job(output="same.exr"), tmp_path)
    with pytest.raises(ValueError, match="no AOV 'indirect'"):
        batch.plan(job(aovs=["indirect"]), tmp_path)
    with pytest.raises(ValueError, match="unknown 'spp_typo'"):
        batch.plan(job(settings={"spp_typo": 1}), tmp_path)
    with pytest.raises(ValueError, match="unknown job field"):
        batch.plan({**job(), "frame": [0, 2]}, tmp_path)
    with pytest.raises(gi.SceneError):
        batch.plan(job(scene="missing.json"), tmp_path)
    # A sweep renders every entry for every frame, with its own method and settings.
    frames = batch.plan(
        job(frames=[0, 2], output="s/{index}.exr", sweep=[{}, {"method": "ispm", "aovs": []}]),
        tmp_path,
    )
    assert [(f.method, f.frame) for f in frames] == [
        ("path", 0),
        ("path", 1),
        ("ispm", 0),
        ("ispm", 1),
    ]
    assert not list(tmp_path.iterdir())
