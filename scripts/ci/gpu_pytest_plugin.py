"""pytest plugin of scripts/ci/gpu_check.sh: on a machine without lavapipe, a test that fails
only because it asked for the CPU adapter (``adapter="cpu"``) is reported as skipped with the
reason "needs lavapipe", so that the GPU run's failures are the GPU's. The check's summary
counts those skips on their own line; every other failure stays a failure."""

from __future__ import annotations

import pytest

NO_LAVAPIPE = "no GPU adapter matches Cpu"
REASON = "needs lavapipe (adapter='cpu'), which this machine lacks"


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    if report.failed and call.excinfo is not None and NO_LAVAPIPE in str(call.excinfo.value):
        report.outcome = "skipped"
        report.longrepr = (str(item.path), item.location[1] or 0, f"Skipped: {REASON}")
