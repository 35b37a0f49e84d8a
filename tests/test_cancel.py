"""Ctrl-C and a progress callback returning False stop every method quickly.

Issue 15 asks for bounds on the cancellation latency (a correctness property of the polling,
not a speed benchmark): the CLI exits with 130 within 1.5 s of SIGINT, and a render raises
`gi.RenderCancelled` within 0.5 s of its callback returning False. The renders below would
each run for many seconds (tens of millions of samples or photon lookups), so a render that
ignored the request could not meet either bound.
"""

import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import gi

# Settings that keep each method busy in one long stage for far longer than the test waits.
LONG = {
    "path": ["--spp", "100000", "--size", "32x32"],
    "photon": ["--photons", "100000", "--spp", "1024", "--size", "64x64"],
    "gather": ["--photons", "100000", "--spp", "1024", "--size", "64x64"],
    "direct": ["--spp", "1000000", "--size", "64x64"],
    "ispm": ["--photons", "20000", "--spp", "1000000", "--size", "64x64"],
}


@pytest.mark.parametrize("method", list(LONG))
def test_ctrl_c_exits_130_quickly(method, tmp_path):
    out = tmp_path / "x.png"
    cmd = [sys.executable, "-m", "gi.cli", "render", "cornell", "-o", str(out), "--method", method]
    with subprocess.Popen([*cmd, *LONG[method]], stderr=subprocess.PIPE) as proc:
        assert proc.stderr is not None
        try:
            # Python start-up, scene loading and the first stage take well under 3 s (the
            # progress bar is quiet when stderr is not a terminal, so there is nothing to
            # read); the render itself would run for minutes.
            time.sleep(3.0)
            assert proc.poll() is None, "the render finished too soon to test"
            t0 = time.monotonic()
            proc.send_signal(signal.SIGINT)
            rc = proc.wait(timeout=30)
            latency = time.monotonic() - t0
        finally:
            proc.kill()
        rest = proc.stderr.read().decode(errors="replace")
    print(f"{method}: exit {rc} {latency:.3f} s after SIGINT")
    assert rc == 130, rest
    assert "interrupted" in rest and "Traceback" not in rest
    # The bound: exit within 1.5 s of Ctrl-C, process teardown included.
    assert latency < 1.5, f"{method}: exited {latency:.2f} s after SIGINT"
    assert not out.exists()


# (method, settings, stage to cancel in): every long stage each method reports.
STAGES = [
    ("path", {"spp": 100_000, "size": (32, 32)}, "path"),
    ("photon", {"photons": 5_000_000, "max_depth": 2, "size": (8, 8)}, "photon trace"),
    ("photon", {"photons": 100_000, "spp": 1024, "size": (64, 64)}, "radiance estimate"),
    ("gather", {"photons": 3_000_000, "max_depth": 2, "size": (8, 8)}, "photon trace"),
    ("gather", {"photons": 100_000, "spp": 1024, "size": (64, 64)}, "radiance estimate"),
    ("direct", {"spp": 1_000_000, "size": (64, 64)}, "direct"),
    ("ispm", {"photons": 20_000, "spp": 1_000_000, "size": (64, 64)}, "direct"),
    ("ispm", {"photons": 2_000_000, "spp": 1, "size": (16, 16)}, "cpu trace"),
]


@pytest.mark.parametrize(("method", "settings", "stage"), STAGES)
def test_callback_cancels_within_half_a_second(method, settings, stage):
    scene = gi.load_scene("cornell")
    asked = []

    def progress(name, fraction):
        # Cancel once the stage has run for a while (0.3 s), mid-way through it.
        if name == stage:
            asked.append(time.monotonic())
            if asked[-1] - asked[0] > 0.3:
                return False
        return True

    with pytest.raises(gi.RenderCancelled):
        gi.render(scene, method, progress=progress, **settings)
    latency = time.monotonic() - asked[-1]
    print(f"{method}/{stage}: cancelled {latency:.3f} s after the callback")
    assert latency < 0.5, f"{method}/{stage}: stopped {latency:.2f} s after the callback"
    # The process renders again.
    img = gi.render(scene, method, spp=1, size=(8, 8), photons=2000).radiance
    assert np.isfinite(img).all() and img.max() > 0
