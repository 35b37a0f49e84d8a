#!/usr/bin/env python3
"""Summarises a scripts/ci/gpu_check.sh output folder into ``summary.md`` and ``summary.json``
(compact enough for the device call's returned files and its output tail), and gathers the
frame_bench tables into ``frame.md``. Standard library only: it runs on the GPU machine.

    scripts/ci/gpu_summary.py OUT_DIR [--total SECONDS]

The overall line is ``overall: ok`` only when every part that ran finished in time, every
test passed (skips for lack of lavapipe are counted apart), every image agrees and no work
was left out for lack of time.
"""

from __future__ import annotations

import argparse
import csv
import json
import re
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

CARGO_RESULT = re.compile(
    r"test result: (\w+)\. (\d+) passed; (\d+) failed; (\d+) ignored; (\d+) measured; "
    r"(\d+) filtered out"
)
CARGO_FAILED = re.compile(r"^test (\S+) \.\.\. FAILED", re.M)
LAVAPIPE = "needs lavapipe"
GOAL_MS = 1000 / 60


def parts(out: Path) -> list[dict[str, str]]:
    with (out / "status.tsv").open() as f:
        return list(csv.DictReader(f, delimiter="\t"))


def cargo(out: Path) -> dict | None:
    d = out / "cargo"
    if not d.is_dir():
        return None
    res = {"binaries": 0, "listed only": 0, "passed": 0, "failed": 0, "ignored": 0}
    res.update(failures=[], problems=[])
    for log in sorted(d.glob("*.log")):
        text = log.read_text(errors="replace")
        res["binaries"] += 1
        name = log.stem
        tail = text.strip().splitlines()[-1] if text.strip() else ""
        if text.startswith("NOT RUN"):
            res["problems"].append(f"{name}: NOT RUN (budget)")
            continue
        rc = re.search(r"^rc (\d+), (\d+)s$", tail)
        results = list(CARGO_RESULT.finditer(text))
        for m in results:
            res["passed"] += int(m[2])
            res["failed"] += int(m[3])
            res["ignored"] += int(m[4])
            if int(m[2]) + int(m[3]) == 0 and int(m[6]) > 0:
                res["problems"].append(f"{name}: its filter matched no test")
        if not results and re.search(r"^\d+ tests?, \d+ benchmarks?$", text, re.M):
            res["listed only"] += 1
        res["failures"] += [f"{name}::{t}" for t in CARGO_FAILED.findall(text)]
        if rc is None:
            res["problems"].append(f"{name}: no exit status")
        elif rc[1] in ("124", "137"):
            res["problems"].append(f"{name}: TIMED OUT after {rc[2]} s")
        elif rc[1] != "0" and not CARGO_FAILED.search(text):
            res["problems"].append(f"{name}: exit {rc[1]} with no failed test (crash?)")
    return res


PYTEST_LINE = re.compile(
    r"(?:^|\s)(PASSED|FAILED|ERROR|SKIPPED)\s+(\S+::\S+)|(\S+::\S+) (PASSED|FAILED|ERROR|SKIPPED)"
)


def pytest_log(log: Path) -> dict | None:
    """The outcomes of a pytest run cut off before its report: from its ``-v`` lines."""
    if not log.is_file():
        return None
    res = {"tests": 0, "passed": 0, "failed": 0, "skipped": 0, "lavapipe": 0, "failures": []}
    res["skip_reasons"] = {}
    for m in PYTEST_LINE.finditer(log.read_text(errors="replace")):
        outcome, name = (m[1], m[2]) if m[1] else (m[4], m[3])
        res["tests"] += 1
        if outcome in ("FAILED", "ERROR"):
            res["failed"] += 1
            res["failures"].append(name)
        elif outcome == "SKIPPED":
            res["skipped"] += 1
        else:
            res["passed"] += 1
    if res["skipped"]:
        res["skip_reasons"]["(a run cut off: reasons not in the log)"] = res["skipped"]
    return res


def pytest(out: Path) -> dict | None:
    xml = out / "pytest.xml"
    if not xml.is_file():
        return pytest_log(out / "logs" / "pytest.log")
    root = ET.parse(xml).getroot()
    res = {"tests": 0, "passed": 0, "failed": 0, "skipped": 0, "lavapipe": 0, "failures": []}
    skip_reasons: dict[str, int] = {}
    for case in root.iter("testcase"):
        res["tests"] += 1
        name = f"{case.get('classname')}::{case.get('name')}"
        if case.find("failure") is not None or case.find("error") is not None:
            res["failed"] += 1
            res["failures"].append(name)
        elif (s := case.find("skipped")) is not None:
            msg = s.get("message") or ""
            if LAVAPIPE in msg:
                res["lavapipe"] += 1
            else:
                res["skipped"] += 1
                skip_reasons[msg[:80]] = skip_reasons.get(msg[:80], 0) + 1
        else:
            res["passed"] += 1
    res["skip_reasons"] = skip_reasons
    return res


def images(out: Path) -> dict | None:
    d = out / "images"
    if not (d / "images.jsonl").is_file():
        return None
    rows = [json.loads(line) for line in (d / "images.jsonl").read_text().splitlines() if line]
    expected = (d / "expected.txt").read_text().split() if (d / "expected.txt").is_file() else []
    done = {r["case"] for r in rows}
    bad = [r for r in rows if r["verdict"] != "agrees"]
    worst = sorted((r for r in rows if "flip" in r), key=lambda r: -abs(r["mean"]))[:3]
    return {
        "expected": len(expected),
        "rendered": len(rows),
        "agree": len(rows) - len(bad),
        "differ": [f"{r['case']}: {r['verdict']}" for r in bad],
        "not_rendered": [c for c in expected if c not in done],
        "largest_mean_diff": [f"{r['case']} {100 * r['mean']:+.3f}%" for r in worst],
    }


MAIN_HEAD = "| scene | size | photons | one-shot frame (ms) | engine frame (ms) |"
TABLE_ROW = re.compile(r"^\| (\S+) \| (\d+)×(\d+) \| (\d+) \| ")


def frame(out: Path) -> dict | None:
    d = out / "frame"
    if not d.is_dir():
        return None
    md, res = [], {"invocations": {}, "key": None}
    best = None  # the largest (pixels, photons) cornell row of the tiled estimator
    jobs = d / "jobs.txt"
    names = jobs.read_text().split() if jobs.is_file() else sorted(p.stem for p in d.glob("*.md"))
    for f in (d / f"{n}.md" for n in names):
        if not f.is_file():
            res["invocations"][f.stem] = "missing"
            continue
        text = f.read_text(errors="replace")
        status = re.search(r"<!-- rc (\d+), (\d+)s: (.*) -->", text)
        res["invocations"][f.stem] = status[3] if status else text.strip()[:40]
        md += [f"## {f.stem}", "", text.strip(), ""]
        if not f.stem.startswith("ispm-tiled"):
            continue
        main_table = False
        for line in text.splitlines():
            if not line.startswith("|"):
                main_table = False
            elif line.startswith(MAIN_HEAD):
                main_table = True
            elif main_table and (m := TABLE_ROW.match(line)) and m[1] == "cornell":
                engine_ms = float(line.strip("|").split("|")[4])
                key = (int(m[2]) * int(m[3]), int(m[4]))
                if best is None or key > best[0]:
                    best = (key, f"{m[2]}×{m[3]}", int(m[4]), engine_ms)
    (out / "frame.md").write_text("\n".join(md))
    if best:
        _, size, photons, ms = best
        res["key"] = {
            "scene": "cornell",
            "size": size,
            "photons": photons,
            "engine_frame_ms": ms,
            "meets_60hz": ms <= GOAL_MS,
        }
    return res


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--total", type=int, default=None, help="seconds the whole check took")
    args = ap.parse_args()
    out: Path = args.out
    s = {
        "bundle": (out / "BUNDLE").read_text().splitlines()[0]
        if (out / "BUNDLE").is_file()
        else "?",
        "adapter": [ln for ln in (out / "adapter.txt").read_text().splitlines() if ln.strip()][:3]
        if (out / "adapter.txt").is_file()
        else [],
        "total_seconds": args.total,
        "parts": parts(out),
        "cargo": cargo(out),
        "pytest": pytest(out),
        "images": images(out),
        "frame": frame(out),
    }
    problems = [f"{p['part']}: {p['status']}" for p in s["parts"] if p["status"] != "ok"]
    if (c := s["cargo"]) and (c["failed"] or c["problems"]):
        problems.append(f"cargo tests: {c['failed']} failed, {len(c['problems'])} problems")
    if (p := s["pytest"]) and p["failed"]:
        problems.append(f"pytest: {p['failed']} failed")
    if (i := s["images"]) and (i["differ"] or i["not_rendered"]):
        problems.append(f"images: {len(i['differ'])} differ, {len(i['not_rendered'])} not rendered")
    s["problems"] = problems
    s["overall"] = "ok" if not problems else "NOT OK"

    lines = [f"# GPU check: {s['bundle']}", ""]
    lines += [f"    {a}" for a in s["adapter"]]
    lines += ["", "| part | status | seconds | detail |", "|---|---|---|---|"]
    lines += [
        f"| {p['part']} | {p['status']} | {p['seconds']} | {p['detail']} |" for p in s["parts"]
    ]
    lines.append("")
    if c := s["cargo"]:
        lines.append(
            f"cargo tests: {c['binaries']} binaries ({c['listed only']} only listed their tests), "
            f"{c['passed']} passed, {c['failed']} failed, {c['ignored']} ignored"
        )
        lines += [f"  FAILED {t}" for t in c["failures"][:20]]
        lines += [f"  {t}" for t in c["problems"][:20]]
    if p := s["pytest"]:
        lines.append(
            f"pytest: {p['tests']} tests, {p['passed']} passed, {p['failed']} failed, "
            f"{p['skipped']} skipped, {p['lavapipe']} skipped for lack of lavapipe"
        )
        lines += [f"  FAILED {t}" for t in p["failures"][:20]]
        lines += [f"  skipped {n}: {r}" for r, n in p["skip_reasons"].items()]
    if i := s["images"]:
        lines.append(
            f"images: {i['rendered']} of {i['expected']} rendered, {i['agree']} agree with "
            f"lavapipe; largest mean differences: {', '.join(i['largest_mean_diff'])}"
        )
        lines += [f"  {t}" for t in i["differ"][:30]]
        if i["not_rendered"]:
            lines.append(f"  not rendered: {', '.join(i['not_rendered'])}")
    if f := s["frame"]:
        lines.append("frame_bench: " + ", ".join(f"{k} {v}" for k, v in f["invocations"].items()))
        if k := f["key"]:
            lines.append(
                f"  {k['scene']} {k['size']} {k['photons']} photons (tiled): engine frame "
                f"{k['engine_frame_ms']:.1f} ms ({'meets' if k['meets_60hz'] else 'misses'} "
                f"the 60 Hz goal, {GOAL_MS:.1f} ms)"
            )
    if s["total_seconds"] is not None:
        lines.append(f"total: {s['total_seconds']} s")
    lines += [f"problem: {t}" for t in problems]
    lines.append(f"overall: {s['overall']}")
    (out / "summary.md").write_text("\n".join(lines) + "\n")
    (out / "summary.json").write_text(json.dumps(s, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
