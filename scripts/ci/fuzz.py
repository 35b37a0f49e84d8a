#!/usr/bin/env python3
"""Fuzzes gi with hostile scenes, mesh files and settings (strategies in tests/fuzz/).

Cases run in groups, each group in its own worker process (tests/fuzz/worker.py), so that
a crash (a signal, an abort) or a hang (a case running longer than --case-timeout) is
recorded against the case that caused it and the run goes on with the next group.

    nice -n 19 .venv/bin/python scripts/ci/fuzz.py --cases 10000 --all-methods \\
        --summary docs/fuzz-summary.json

The summary counts outcomes per group: ok, typed (a gi.GiError), untyped (any other
exception), nan (an accepted render with a non-finite pixel), crash and hang (no result
after --hang-timeout seconds: the worker is killed); the last four must be zero. Cases that
took longer than --case-timeout (20 s) of wall time are listed as `slow` with their CPU
time, which tells a slow input from a worker starved by other load (`nice -n 19` on a busy
machine). The exit status is 1 when any failure or slow case occurred.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
WORKER = ROOT / "tests" / "fuzz" / "worker.py"
GROUPS = ["scenes", "meshes", "settings"]
FAILURES = ["untyped", "nan", "crash", "hang"]
#: Seconds a worker may take to import gi and start its first case.
STARTUP_TIMEOUT = 120.0


def read_log(path: Path) -> list[dict]:
    if not path.exists():
        return []
    records = []
    for line in path.read_text(encoding="utf-8").splitlines():
        try:
            records.append(json.loads(line))
        except json.JSONDecodeError:
            pass  # a line cut by a crash
    return records


def run_group(
    group: str, seed: int, cases: int, hang_timeout: float, all_methods: bool, tmp: Path
) -> list[dict]:
    """Runs one worker; returns its cases as end records, a crash or hang included."""
    log = tmp / f"{group}-{seed}.jsonl"
    cmd = [sys.executable, str(WORKER), "--group", group, "--seed", str(seed)]
    cmd += ["--cases", str(cases), "--log", str(log)]
    if all_methods:
        cmd.append("--all-methods")
    # stderr to a file: a pipe nobody reads would block the worker once full.
    err_path = tmp / f"{group}-{seed}.stderr"
    err_file = err_path.open("w")
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err_file)
    hung = None
    started = time.time()
    while proc.poll() is None:
        time.sleep(0.2)
        records = read_log(log)
        if records and records[-1]["event"] == "start":
            if time.time() - records[-1]["t"] > hang_timeout:
                hung = records[-1]
                proc.kill()
                break
        elif not records and time.time() - started > STARTUP_TIMEOUT:
            proc.kill()  # stuck before its first case: reported as a crash below
            break
    proc.wait()
    err_file.close()
    stderr = err_path.read_text(errors="replace")
    records = read_log(log)
    ends = [r for r in records if r["event"] == "end"]
    starts = {r["case"]: r for r in records if r["event"] == "start"}
    unfinished = [starts[c] for c in starts if c not in {e["case"] for e in ends}]
    for r in ends:
        r["input"] = starts.get(r["case"], {}).get("input")
    for r in unfinished:
        status = "hang" if hung is not None and r["case"] == hung["case"] else "crash"
        detail = (
            f"no result after {hang_timeout:.0f} s"
            if status == "hang"
            else f"worker exited with {proc.returncode}: {stderr[-1500:]}"
        )
        ends.append({**r, "event": "end", "status": status, "detail": detail})
    if proc.returncode != 0 and hung is None and not unfinished:
        # Died outside a case (start-up or hypothesis itself): count it as a crash.
        ends.append(
            {
                "case": -1,
                "group": group,
                "status": "crash",
                "detail": f"worker exited with {proc.returncode}: {stderr[-1500:]}",
                "input": None,
            }
        )
    for r in ends:
        r["seed"] = seed
    return ends


def run(
    cases: int,
    group_size: int,
    case_timeout: float,
    all_methods: bool,
    seed: int = 0,
    jobs: int = 1,
    hang_timeout: float = 300.0,
) -> dict:
    """Runs at least `cases` cases, groups cycling through scenes, meshes and settings."""
    t0 = time.monotonic()
    results: list[dict] = []
    with tempfile.TemporaryDirectory(prefix="gi-fuzz-run-") as d:
        tmp = Path(d)
        plan = []
        n, i = 0, 0
        while n < cases:
            plan.append((GROUPS[i % len(GROUPS)], seed * 100_003 + i))
            n += group_size
            i += 1
        if jobs <= 1:
            for group, s in plan:
                results += run_group(group, s, group_size, hang_timeout, all_methods, tmp)
                done = len(results)
                bad = sum(r["status"] in FAILURES for r in results)
                print(f"{done} cases, {bad} failures, {time.monotonic() - t0:.0f} s", flush=True)
        else:
            from concurrent.futures import ThreadPoolExecutor

            with ThreadPoolExecutor(jobs) as pool:
                futures = [
                    pool.submit(run_group, g, s, group_size, hang_timeout, all_methods, tmp)
                    for g, s in plan
                ]
                for f in futures:
                    results += f.result()
    counts = {g: dict(Counter(r["status"] for r in results if r["group"] == g)) for g in GROUPS}
    totals = dict(Counter(r["status"] for r in results))
    slowest = sorted(results, key=lambda r: -float(r.get("seconds") or 0))[:5]
    slow = [r for r in results if float(r.get("seconds") or 0) > case_timeout]
    return {
        "cases": len(results),
        "seconds": round(time.monotonic() - t0, 1),
        "all_methods": all_methods,
        "case_timeout_s": case_timeout,
        "hang_timeout_s": hang_timeout,
        "totals": {k: totals.get(k, 0) for k in ["ok", "typed", *FAILURES]},
        "per_group": counts,
        "slowest_cases_s": [(r.get("seconds"), r.get("cpu_seconds")) for r in slowest],
        "slow": [
            {k: r.get(k) for k in ["group", "seconds", "cpu_seconds", "status", "input"]}
            for r in slow
        ],
        "failures": [r for r in results if r["status"] in FAILURES],
    }


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    p.add_argument("--cases", type=int, default=10_000)
    p.add_argument("--group-size", type=int, default=250)
    p.add_argument("--case-timeout", type=float, default=20.0, help="a case slower is `slow`")
    p.add_argument("--hang-timeout", type=float, default=300.0, help="a case slower is killed")
    p.add_argument("--all-methods", action="store_true", help="render every case with all five")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--jobs", type=int, default=1, help="worker processes at a time")
    p.add_argument("--summary", type=Path, help="write the summary JSON here")
    args = p.parse_args()
    os.environ.setdefault("GI_ADAPTER", "cpu")
    summary = run(
        args.cases,
        args.group_size,
        args.case_timeout,
        args.all_methods,
        args.seed,
        args.jobs,
        args.hang_timeout,
    )
    summary["command"] = " ".join(["scripts/ci/fuzz.py", *sys.argv[1:]])
    text = json.dumps(summary, indent=1, default=repr)
    if args.summary:
        args.summary.write_text(text + "\n")
    print(json.dumps({k: v for k, v in summary.items() if k != "failures"}, indent=1))
    for f in summary["failures"][:20]:
        print(f["status"], f["group"], f.get("detail", "")[:300], file=sys.stderr)
    return 1 if summary["failures"] or summary["slow"] else 0


if __name__ == "__main__":
    sys.exit(main())
