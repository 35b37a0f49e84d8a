"""The hand-maintained stubs of the native module match it (mypy.stubtest)."""

import subprocess
import sys


def test_stubtest_native_module():
    p = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "gi._gi", "--ignore-missing-stub"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert p.returncode == 0, p.stdout + p.stderr
