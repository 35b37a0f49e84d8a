#!/usr/bin/env python3
"""Latency and frame rate of `gi view`, measured in the browser: headless Chromium (Debian's
`chromium`, driven by Playwright) on the page the viewer serves.

- **latency**: from the page sending a camera message (an orbit step) to the page having
  drawn the first frame that shows it (the frame's `seq`): render, PNG encoding, WebSocket,
  decoding and drawing. "Moving": each message right after the previous one's frame was
  drawn, as while the user drags. "From still": each message after 1.5 s without input, so
  it lands on a progressive pass under way, which it cancels.
- **frames per second delivered**: the page orbits the camera a little every 16 ms for
  `--seconds` and counts the frames it draws (the server renders the newest camera each time
  and drops none it could send, sends none the page has not asked for).

Latencies are medians (and 90th percentiles); beside them, the median render time of the
frames measured (the renderer's `stats.total_seconds`) and the server's tone mapping and
PNG encoding per frame.
The page's window is sized so that the view keeps the asked size exactly.

    .venv/bin/python scripts/bench/bench_view.py            # the table of docs/bench/view.md
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

LATENCY_JS = """async ([n, pause]) => {
  const out = [];
  for (let i = 0; i < n; i++) {
    await new Promise((r) => setTimeout(r, pause));
    const t0 = performance.now();
    const s = giViewer.orbit(0.03, 0);
    const t1 = await giViewer.waitSeq(s);
    out.push([t1 - t0, giViewer.meta.total_seconds * 1000]);
  }
  return out;
}"""

FPS_JS = """async (ms) => {
  const renders = [];
  const f0 = giViewer.frames;
  const t0 = performance.now();
  const timer = setInterval(() => giViewer.orbit(0.004, 0), 16);
  let last = giViewer.meta.id;
  while (performance.now() - t0 < ms) {
    await new Promise((r) => setTimeout(r, 5));
    if (giViewer.meta.id !== last) {
      last = giViewer.meta.id;
      renders.push([giViewer.meta.total_seconds * 1000, giViewer.meta.encode_seconds * 1000]);
    }
  }
  clearInterval(timer);
  return [(giViewer.frames - f0) / ((performance.now() - t0) / 1000), renders];
}"""


def measure(browser, scene: str, size: tuple[int, int], options: dict, args) -> dict:
    w, h = size
    url = gi.view(scene, "ispm", size=size, **options)
    try:
        page = browser.new_page(viewport={"width": PANEL + 3 * w, "height": 3 * h})
        page.set_default_timeout(120_000)
        page.goto(url)
        page.wait_for_function(
            "([w, h]) => giViewer.frames > 0 && giViewer.meta.width === w"
            " && giViewer.meta.height === h",
            arg=[w, h],
        )
        page.evaluate(LATENCY_JS, [3, 0])  # warm-up
        moving = page.evaluate(LATENCY_JS, [args.samples, 0])
        still = page.evaluate(LATENCY_JS, [args.samples, 1500])
        fps, renders = page.evaluate(FPS_JS, args.seconds * 1000)
        page.close()
    finally:
        gi.viewer.stop(url)
    return {
        "moving": [t for t, _ in moving],
        "moving_render": statistics.median(r for _, r in moving),
        "still": [t for t, _ in still],
        "fps": fps,
        "fps_render": statistics.median(r[0] for r in renders),
        "encode": statistics.median(r[1] for r in renders),
    }


def pct(values: list[float], q: float) -> float:
    v = sorted(values)
    return v[min(int(q * len(v)), len(v) - 1)]


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--scene", default="cornell")
    p.add_argument("--sizes", default="320x240,640x480")
    p.add_argument("--photons", default="default,20000", help="comma-separated; 'default'")
    p.add_argument("--samples", type=int, default=15, help="camera messages per latency")
    p.add_argument("--seconds", type=float, default=10.0, help="length of the fps run")
    p.add_argument("--chromium", default=os.environ.get("GI_CHROMIUM") or shutil.which("chromium"))
    p.add_argument("--out", type=Path, help="write the markdown table here")
    args = p.parse_args(argv)
    from playwright.sync_api import sync_playwright

    sizes = [tuple(int(v) for v in s.split("x")) for s in args.sizes.split(",")]
    rows = []
    load = os.getloadavg()
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=args.chromium, headless=True)
        for size in sizes:
            for photons in args.photons.split(","):
                options = {} if photons == "default" else {"photons": int(photons)}
                r = measure(browser, args.scene, size, options, args)
                row = (
                    f"| {size[0]}×{size[1]} | {photons}"
                    f" | {statistics.median(r['moving']):.0f} | {pct(r['moving'], 0.9):.0f}"
                    f" | {r['moving_render']:.0f}"
                    f" | {statistics.median(r['still']):.0f} | {pct(r['still'], 0.9):.0f}"
                    f" | {r['fps']:.1f} | {r['fps_render']:.0f} | {r['encode']:.1f} |"
                )
                print(row, flush=True)
                rows.append(row)
        browser.close()
    load_after = os.getloadavg()
    head = [
        "| size | photons | latency, moving (ms) | p90 | its frames' render (ms)"
        " | latency, from still (ms) | p90 | frames/s delivered | their render (ms)"
        " | tone map + PNG (ms) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    text = "\n".join(head + rows)
    note = (
        f"scene {args.scene}, method ispm, {args.samples} camera messages per latency,"
        f" {args.seconds:g} s per frame rate; {gi.adapter_report(None).splitlines()[0]};"
        f" {os.cpu_count()} CPU cores ({platform.processor() or platform.machine()}),"
        f" load average {load[0]:.1f} before, {load_after[0]:.1f} after;"
        f" {time.strftime('%Y-%m-%d')}"
    )
    print(note)
    if args.out:
        args.out.write_text(text + "\n\n" + note + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
