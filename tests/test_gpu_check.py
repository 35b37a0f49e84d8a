"""The GPU check's summary (scripts/ci/gpu_summary.py) reads what scripts/ci/gpu_check.sh
writes, and its pytest plugin turns only "no lavapipe" failures into skips (docs/gpu-check.md)."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

SCRIPTS = Path(__file__).resolve().parent.parent / "scripts" / "ci"
FRAME_HEAD = (
    "| scene | size | photons | one-shot frame (ms) | engine frame (ms) | speed-up | "
    "serial frame (ms) | CPU photon trace (ms) | CPU specular paths (ms) | splat (ms) | "
    "direct light (ms) | bounce maps (ms) | upsampling (ms) | rest (ms) | "
    "share of all but splat and photon trace | share of all but splat and CPU traces | "
    "still frame (ms) | estimator/first bounce: stages of the engine frame (ms) |"
)


def frame_row(size: str, photons: int, engine: float) -> str:
    return (
        f"| cornell | {size} | {photons} | 74 | {engine} | 1.79× | 41 | 3 | 0 | 13 | 22 | 0 | 2 "
        "| 1 | 61.1% | 61.1% | 0.7 | tiled/raster: gbuffer 0.50, tiled shading 2.00 |"
    )


def write_output(out: Path, *, broken: bool) -> None:
    """A check's output folder: everything passed, or (``broken``) one of each problem."""
    (out / "cargo").mkdir(parents=True)
    (out / "frame").mkdir()
    (out / "images").mkdir()
    (out / "logs").mkdir()
    (out / "BUNDLE").write_text("gi 0.1.0 at abc1234, bundled 2026-01-01\n")
    (out / "adapter.txt").write_text("gi 0.1.0 python 3.12.3\nadapter: NVIDIA H100\n")
    parts = [("cargo-tests", "ok"), ("images", "ok"), ("frame-bench", "ok")]
    if broken:
        parts[2] = ("frame-bench", "TIMED OUT")
    (out / "status.tsv").write_text(
        "part\tstatus\tseconds\tdetail\n" + "".join(f"{p}\t{s}\t3\t-\n" for p, s in parts)
    )
    ok = "test result: ok. {} passed; 0 failed; 0 ignored; 0 measured; {} filtered out"
    (out / "cargo" / "gpu_direct.log").write_text(ok.format(6, 0) + "\nrc 0, 3s\n")
    (out / "cargo" / "listed.log").write_text(
        "a: test\nb: test\n\n2 tests, 0 benchmarks\nrc 0, 0s\n"
    )
    if broken:
        (out / "cargo" / "ispm.log").write_text(
            "test shadow_edges ... FAILED\ntest result: FAILED. 3 passed; 1 failed; 0 ignored; "
            "0 measured; 0 filtered out\nrc 101, 9s\n"
        )
        (out / "cargo" / "focus.log").write_text("running 3 tests\nrc 124, 40s\n")
        (out / "cargo" / "frame.log").write_text(ok.format(0, 9) + "\nrc 0, 1s\n")
    cases = [
        '<testcase classname="tests.test_api" name="test_a" time="1"/>',
        '<testcase classname="tests.test_bidir" name="test_b" time="1">'
        "<skipped message=\"needs lavapipe (adapter='cpu'), which this machine lacks\"/>"
        "</testcase>",
    ]
    if broken:
        cases.append(
            '<testcase classname="tests.test_api" name="test_c" time="1">'
            '<failure message="assert 1 == 2"/></testcase>'
        )
    (out / "pytest.xml").write_text(
        f'<testsuites><testsuite name="pytest">{"".join(cases)}</testsuite></testsuites>'
    )
    rows = [{"case": "cornell.path", "verdict": "agrees", "mean": 0.001, "flip": 0.0}]
    if broken:
        rows.append({"case": "cornell.direct", "verdict": "DIFFERS (FLIP)", "mean": 0.0})
    expected = ["cornell.path"] + (["cornell.direct", "cornell.bidir"] if broken else [])
    (out / "images" / "expected.txt").write_text("\n".join(expected) + "\n")
    (out / "images" / "images.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    (out / "frame" / "ispm-tiled-1920x1080.md").write_text(
        "adapter: NVIDIA H100\n\n"
        + "\n".join([FRAME_HEAD, "|---|", frame_row("1920×1080", 20000, 9.5)])
        + "\n"
        + frame_row("1920×1080", 200000, 21.25)
        + "\n<!-- rc 0, 30s: ok -->\n"
    )


def summarise(tmp_path: Path, broken: bool) -> tuple[str, dict]:
    out = tmp_path / "out"
    write_output(out, broken=broken)
    subprocess.run([sys.executable, SCRIPTS / "gpu_summary.py", out, "--total", "99"], check=True)
    return (out / "summary.md").read_text(), json.loads((out / "summary.json").read_text())


def test_summary_of_a_clean_run_is_ok(tmp_path):
    md, s = summarise(tmp_path, broken=False)
    assert md.rstrip().endswith("overall: ok"), md
    assert "6 passed, 0 failed" in md
    assert "1 skipped for lack of lavapipe" in md
    assert "images: 1 of 1 rendered, 1 agree" in md
    assert s["frame"]["key"]["engine_frame_ms"] == 21.25
    assert s["frame"]["key"]["photons"] == 200000
    assert "misses the 60 Hz goal" in md


def test_summary_names_every_problem(tmp_path):
    md, s = summarise(tmp_path, broken=True)
    assert md.rstrip().endswith("overall: NOT OK"), md
    assert "FAILED ispm::shadow_edges" in md
    assert "focus: TIMED OUT after 40 s" in md
    assert "frame: its filter matched no test" in md
    assert "problem: frame-bench: TIMED OUT" in md
    assert "FAILED tests.test_api::test_c" in md
    assert "cornell.direct: DIFFERS (FLIP)" in md
    assert "not rendered: cornell.bidir" in md
    assert s["cargo"]["listed only"] == 1


def test_plugin_skips_only_failures_for_lack_of_lavapipe(tmp_path):
    (tmp_path / "test_x.py").write_text(
        textwrap.dedent(
            """
            def test_needs_lavapipe():
                raise RuntimeError("no GPU adapter matches Cpu (adapters found: NVIDIA H100)")

            def test_other_failure():
                raise RuntimeError("something else")
            """
        )
    )
    p = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "gpu_pytest_plugin", "-rs", "-p", "no:cacheprovider"]
        + ["test_x.py"],
        cwd=tmp_path,
        env={"PYTHONPATH": str(SCRIPTS), "PATH": "/usr/bin:/bin"},
        capture_output=True,
        text=True,
    )
    assert "1 failed, 1 skipped" in p.stdout, p.stdout
    assert "needs lavapipe" in p.stdout
