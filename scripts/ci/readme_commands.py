#!/usr/bin/env python3
"""Runs the shell commands of README.md's ```sh blocks in order, each in a new bash with the
virtual environment active (`source .venv/bin/activate`, as the README says), in a scratch
directory that sees the checkout's `docs/` (the examples' scene files), and says which
failed.

The README's `source .venv/bin/activate` is what every command runs with (`--venv`). Left
out, each said so when run: `make` (the set-up, run before this), `pip install`
(a network install; the viewer's dependency is checked instead), `gi view` (serves until
Ctrl-C: started, its page fetched, then stopped) and `curl` (the viewer's routes, which
tests/test_view.py drives).

`--fast` runs the same commands on smaller images: `--size 32x24`, and `--frames 0:2` for
animations (argparse takes the last of a repeated option), so that the test suite can run
it (tests/test_readme.py); without it the commands run as written (minutes).

    .venv/bin/python scripts/ci/readme_commands.py [--fast] [--venv .venv]
"""

from __future__ import annotations

import argparse
import re
import shlex
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def commands(readme: Path) -> list[str]:
    """The command lines of the README's ```sh blocks, in order (comments dropped)."""
    out = []
    for block in re.findall(r"^\s*```sh\n(.*?)^\s*```", readme.read_text(), re.M | re.S):
        for line in block.splitlines():
            line = line.strip()
            if line and not line.startswith("#"):
                out.append(shlex.join(shlex.split(line, comments=True)))
    return out


def faster(line: str) -> str:
    """``line`` on small images (argparse: the last of a repeated option wins)."""
    words = shlex.split(line)
    if words[:2] == ["gi", "render"]:
        words += ["--size", "32x24"]
        if "--frames" in words or any(w.endswith(".mp4") or "%0" in w for w in words):
            words += ["--frames", "0:2"]
    return shlex.join(words)


def view(venv: Path, line: str, cwd: Path) -> str | None:
    """Starts a `gi view` line, fetches its page, stops it; the error, or None."""
    words = shlex.split(line)
    if "--port" not in words:
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            words += ["--port", str(s.getsockname()[1])]
    words += ["--no-browser"] if "--no-browser" not in words else []
    port = words[words.index("--port") + 1]
    script = f"source {shlex.quote(str(venv / 'bin' / 'activate'))}\nexec {shlex.join(words)}"
    p = subprocess.Popen(["bash", "-c", script], cwd=cwd, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if p.poll() is not None:
                return f"exited {p.returncode}: {p.stderr.read() if p.stderr else ''}"
            try:
                with urllib.request.urlopen(f"http://127.0.0.1:{port}/frame.png", timeout=60):
                    return None
            except OSError:
                time.sleep(0.5)
        return "no frame within 2 minutes"
    finally:
        p.terminate()
        p.wait(timeout=30)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fast", action="store_true", help="smaller images, two frames")
    ap.add_argument("--venv", type=Path, default=ROOT / ".venv")
    ap.add_argument("--readme", type=Path, default=ROOT / "README.md")
    args = ap.parse_args(argv)
    venv = args.venv.resolve()
    failed = []
    with tempfile.TemporaryDirectory(prefix="gi-readme-") as tmp:
        cwd = Path(tmp)
        (cwd / "docs").symlink_to(ROOT / "docs")
        for line in commands(args.readme):
            first = shlex.split(line)[:2]
            if first[0] in ("make", "curl") or first == ["pip", "install"]:
                print(f"skip  {line}", flush=True)
                continue
            if first[0] == "source" and line.endswith("/activate"):
                print(f"each  {line} (every command below runs with it)", flush=True)
                continue
            if first == ["gi", "view"]:
                if args.fast:
                    line = shlex.join([*shlex.split(line), "--size", "32x24"])
                error = view(venv, line, cwd)
            else:
                run = faster(line) if args.fast else line
                script = f"source {shlex.quote(str(venv / 'bin' / 'activate'))}\n{run}"
                p = subprocess.run(["bash", "-c", script], cwd=cwd, capture_output=True, text=True)
                error = None if p.returncode == 0 else f"exit {p.returncode}: {p.stderr[-2000:]}"
            print(f"{'ok' if error is None else 'FAIL':5} {line}", flush=True)
            if error is not None:
                print(error, flush=True)
                failed.append(line)
    print(f"{len(failed)} failed" if failed else "every command ran", flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
