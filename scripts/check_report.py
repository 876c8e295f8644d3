#!/usr/bin/env python3
"""Open an omnical HTML report in headless Chromium and check that it renders.

Fails (exit 1) when the browser console has errors, when the page asks for any resource (the report must be
self-contained), or when a figure did not render: every <figure data-figure> needs a visible <svg> with a
non-empty bounding box and drawn content. Saves a full-page screenshot.

Needs Debian's `chromium` and `chromium-driver` and the `selenium` package (requirements-dev.txt).

    python scripts/check_report.py REPORT.html --screenshot shot.png [--expect ladder,growth,...]
"""

import argparse
import base64
import json
import pathlib
import shutil
import sys
import tempfile

from selenium import webdriver
from selenium.webdriver.chrome.service import Service

# Measured in the page: per figure, the SVG's size on screen and how much it draws.
FIGURE_PROBE = """
return Array.from(document.querySelectorAll('figure[data-figure]')).map(f => {
  const svg = f.querySelector('svg');
  if (!svg) return {id: f.dataset.figure, svg: false};
  const r = svg.getBoundingClientRect();
  const b = svg.getBBox();
  return {id: f.dataset.figure, svg: true, width: r.width, height: r.height,
          bbox_width: b.width, bbox_height: b.height,
          shapes: svg.querySelectorAll('path, polyline, line, rect, circle, polygon').length,
          texts: svg.querySelectorAll('text').length};
});
"""


def chromium_binary():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    sys.exit("check_report: no chromium found (apt-get install chromium chromium-driver)")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("report", type=pathlib.Path)
    ap.add_argument("--screenshot", type=pathlib.Path, required=True)
    ap.add_argument("--expect", default="", help="comma-separated figure ids that must be present")
    ap.add_argument("--width", type=int, default=1100)
    args = ap.parse_args()
    if not args.report.is_file():
        sys.exit(f"check_report: {args.report}: no such file")

    profile = tempfile.mkdtemp(prefix="omnical-chromium-")
    opts = webdriver.ChromeOptions()
    opts.binary_location = chromium_binary()
    for flag in ("--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync",
                 f"--user-data-dir={profile}", f"--window-size={args.width},1200"):
        opts.add_argument(flag)
    opts.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    driver_path = shutil.which("chromedriver") or "/usr/bin/chromedriver"
    driver = webdriver.Chrome(service=Service(executable_path=driver_path), options=opts)
    problems = []
    try:
        driver.get(args.report.resolve().as_uri())
        state = driver.execute_script("return document.readyState")
        if state != "complete":
            problems.append(f"page not loaded (readyState {state})")
        for entry in driver.get_log("browser"):
            if entry.get("level") in ("SEVERE", "ERROR"):
                problems.append(f"console error: {entry.get('message')}")
        fetched = driver.execute_script(
            "return performance.getEntriesByType('resource').map(e => e.name)")
        for url in fetched:
            problems.append(f"the report fetched {url} (it must be self-contained)")
        figures = driver.execute_script(FIGURE_PROBE)
        ids = [f["id"] for f in figures]
        for want in filter(None, args.expect.split(",")):
            if want not in ids:
                problems.append(f"figure {want!r} missing (found {', '.join(ids) or 'none'})")
        for f in figures:
            if not f["svg"]:
                problems.append(f"figure {f['id']}: no <svg>")
            elif f["width"] < 100 or f["height"] < 100 or f["bbox_width"] < 50 or f["bbox_height"] < 50:
                problems.append(f"figure {f['id']}: rendered too small: {json.dumps(f)}")
            elif f["shapes"] < 5 or f["texts"] < 1:
                problems.append(f"figure {f['id']}: nearly empty: {json.dumps(f)}")
        height = driver.execute_script("return document.documentElement.scrollHeight")
        shot = driver.execute_cdp_cmd("Page.captureScreenshot", {
            "format": "png", "captureBeyondViewport": True,
            "clip": {"x": 0, "y": 0, "width": args.width, "height": height, "scale": 1}})
        args.screenshot.parent.mkdir(parents=True, exist_ok=True)

        tmp = args.screenshot.with_suffix(".png.tmp")
        tmp.write_bytes(base64.b64decode(shot["data"]))
        tmp.replace(args.screenshot)
    finally:
        driver.quit()
        shutil.rmtree(profile, ignore_errors=True)

    for f in figures:
        print(f"figure {f['id']:<16} {f.get('width', 0):5.0f}×{f.get('height', 0):<5.0f} px, "
              f"{f.get('shapes', 0)} shapes, {f.get('texts', 0)} texts")
    print(f"screenshot: {args.screenshot} ({args.width}×{height} px)")
    if problems:
        for p in problems:
            print(f"FAIL: {p}", file=sys.stderr)
        sys.exit(1)
    print(f"report OK: {len(figures)} figures rendered, no console errors, no fetches")


if __name__ == "__main__":
    main()
