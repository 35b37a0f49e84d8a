"""README.md's shell commands, pasted in order into a new shell with the environment active
(scripts/ci/readme_commands.py), in its fast mode: the same commands on 32×24 images and two
frames of each animation. `make`, `pip install` and `curl` lines are left out (the set-up and
the viewer's routes, tested elsewhere); `gi view` lines are started, fetched and stopped."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def environment(tmp_path: Path) -> Path:
    """The environment to activate: the one running the tests. Where gi is not installed
    into it (a worktree testing its python/ through PYTHONPATH), a copy of its activation
    that also puts a `gi` running this gi on the PATH."""
    venv = Path(sys.prefix)
    if (venv / "bin" / "gi").exists():
        return venv
    shim = tmp_path / "venv"
    (shim / "bin").mkdir(parents=True)
    gi = shim / "bin" / "gi"
    gi.write_text(f'#!/bin/sh\nexec {sys.executable} -m gi.cli "$@"\n')
    gi.chmod(0o755)
    (shim / "bin" / "activate").write_text(
        f"source {venv / 'bin' / 'activate'}\nexport PATH={shim / 'bin'}:$PATH\n"
    )
    return shim


def test_readme_commands_run_in_order(tmp_path):
    script = ROOT / "scripts" / "ci" / "readme_commands.py"
    venv = environment(tmp_path)
    p = subprocess.run(
        [sys.executable, str(script), "--fast", "--venv", str(venv)],
        capture_output=True,
        text=True,
        timeout=1200,
    )
    assert p.returncode == 0, p.stdout + p.stderr
    ran = [line for line in p.stdout.splitlines() if line.startswith("ok ")]
    assert any("gi render docs/scenes/cornell-box/cornell-box.xml" in line for line in ran)
    assert any(line.startswith("ok    gi view") for line in ran), p.stdout
