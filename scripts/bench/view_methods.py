#!/usr/bin/env python3
"""`gi view` in every method, measured in the browser: headless Chromium (Debian's
`chromium`, driven by Playwright) on the page the viewer serves, at the defaults of
`gi view SCENE --method M --size WxH` (the interactive settings of `gi.presets`).

Per method:

- **first frame**: from `gi.view(...)` being called (the renderer made, the server started)
  to the page having drawn its first frame, the page opened at once;
- **refined**: from the same start to the first progressive pass drawn at the full size;
- **orbit**: from the page sending an orbit step while the view is still (it cancels the
  pass under way) to the page having drawn the frame that shows it, median of `--samples`;
  beside it, that frame's own render time (`stats.total_seconds`) and its size.

    .venv/bin/python scripts/bench/view_methods.py --out docs/bench/view.md

writes the table and its note between the `<!-- view_methods -->` and
`<!-- /view_methods -->` lines of an existing file (docs/bench/view.md), or a new file.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import sys
import time
from pathlib import Path

import gi

PANEL = 250  # px: the page's side panel (viewer.css #panel)

ORBIT_JS = """async ([n, pause]) => {
  const out = [];
  for (let i = 0; i < n; i++) {
    await new Promise((r) => setTimeout(r, pause));
    const t0 = performance.now();
    const s = giViewer.orbit(0.05, 0);
    const t1 = await giViewer.waitSeq(s);
    // The frame that showed the step (a refining frame may already have replaced it).
    const m = giViewer.metas.find((m) => m.seq !== null && m.seq >= s);
    out.push([t1 - t0, m.total_seconds * 1000, m.width]);
  }
  return out;
}"""


def measure(browser, scene: str, method: str, size: tuple[int, int], samples: int) -> dict:
    w, h = size
    start = time.monotonic()
    url = gi.view(scene, method, size=size)
    try:
        page = browser.new_page(viewport={"width": PANEL + 3 * w, "height": 3 * h})
        page.set_default_timeout(300_000)
        page.goto(url)
        page.wait_for_function("giViewer.frames > 0")
        first = time.monotonic() - start
        # The page keeps every frame's meta: refining frames may follow before this looks.
        first_meta = page.evaluate("giViewer.metas[0]")
        refined = float("nan")
        if (
            "progressive" in {row["name"] for row in gi.options_table(method)}
            and method != "photon"
        ):
            page.wait_for_function(f"giViewer.metas.some(m => m.progressive && m.width === {w})")
            refined = time.monotonic() - start
        orbits = page.evaluate(ORBIT_JS, [samples, 1500])
        page.close()
    finally:
        gi.viewer.stop(url)
    return {
        "first": first,
        "first_size": f"{first_meta['width']}×{first_meta['height']}",
        "doing": first_meta.get("doing", ""),
        "refined": refined,
        "orbit": statistics.median(t for t, _, _ in orbits),
        "orbit_render": statistics.median(r for _, r, _ in orbits),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default="cornell-glass")
    p.add_argument("--size", default="320x240")
    p.add_argument("--methods", default=",".join(gi.methods()))
    p.add_argument("--samples", type=int, default=5, help="orbit steps per method")
    p.add_argument("--chromium", default=os.environ.get("GI_CHROMIUM") or shutil.which("chromium"))
    p.add_argument("--out", type=Path, help="write the markdown table here")
    args = p.parse_args(argv)
    from playwright.sync_api import sync_playwright

    size = tuple(int(v) for v in args.size.split("x"))
    rows = []
    load = os.getloadavg()
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=args.chromium, headless=True)
        for method in args.methods.split(","):
            r = measure(browser, args.scene, method, size, args.samples)  # type: ignore[arg-type]
            refined = "–" if r["refined"] != r["refined"] else f"{r['refined']:.1f}"
            row = (
                f"| {method} | {r['first']:.1f} | {r['doing'].removeprefix('moving: ')}"
                f" | {refined} | {r['orbit'] / 1000:.2f} | {r['orbit_render'] / 1000:.2f}"
                f" | {os.getloadavg()[0]:.1f} |"
            )
            print(row, flush=True)
            rows.append(row)
        browser.close()
    load_after = os.getloadavg()
    head = [
        "| method | first frame (s) | interactive frame | refined at full size (s)"
        " | orbit → drawn (s) | its render (s) | load average |",
        "|---|---:|---|---:|---:|---:|---:|",
    ]
    note = (
        f"`{' '.join(['scripts/bench/view_methods.py', *(argv or sys.argv[1:])])}`: scene"
        f" {args.scene}, view {args.size}, {args.samples} orbit steps each after 1.5 s"
        f" still; {gi.adapter_report(None).splitlines()[0]}; {os.cpu_count()} CPU cores"
        f" ({platform.processor() or platform.machine()}), load average {load[0]:.1f}"
        f" before, {load_after[0]:.1f} after; {time.strftime('%Y-%m-%d')}"
    )
    text = "\n".join(head + rows)
    print(note)
    if args.out:
        write(args.out, text + "\n\n" + note + "\n")
    return 0


BEGIN, END = "<!-- view_methods -->", "<!-- /view_methods -->"


def write(out: Path, block: str) -> None:
    """`block` between the markers of `out` when it has them, else as the whole file."""
    old = out.read_text() if out.is_file() else ""
    if BEGIN in old and END in old:
        before, rest = old.split(BEGIN, 1)
        after = rest.split(END, 1)[1]
        out.write_text(f"{before}{BEGIN}\n{block}{END}{after}")
    else:
        out.write_text(block)


if __name__ == "__main__":
    sys.exit(main())
