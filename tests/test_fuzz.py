"""The CI-sized fuzz run: hostile scenes, mesh files and settings (tests/fuzz/strategies.py),
each group of cases in a subprocess with a per-case time limit, so that a crash or a hang is
a test failure naming the input instead of a dead test run. The long run and its committed
summary are in docs/fuzz.md."""

import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def load_driver():
    spec = importlib.util.spec_from_file_location("gi_fuzz", ROOT / "scripts" / "ci" / "fuzz.py")
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_fuzz_ci_run():
    fuzz = load_driver()
    # 6 groups of 90 cases (scenes, meshes, settings twice): 540 cases, one method each.
    # A case that runs past 60 s is killed and fails the test as a hang; one past 20 s is
    # listed as slow (CI machines are shared: a starved case is not a hang).
    summary = fuzz.run(
        cases=540, group_size=90, case_timeout=20.0, all_methods=False, seed=15, hang_timeout=60.0
    )
    assert summary["cases"] >= 500, summary["cases"]
    failures = json.dumps(summary["failures"][:5], indent=1, default=repr)
    assert not summary["failures"], failures
    for group in fuzz.GROUPS:
        counts = summary["per_group"][group]
        # Both outcomes occur in every group: the strategies reach renders and errors.
        assert counts.get("ok", 0) > 0 and counts.get("typed", 0) > 0, (group, counts)
