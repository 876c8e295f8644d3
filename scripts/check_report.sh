#!/usr/bin/env bash
# Browser check of the HTML report, run by .ci/run: the README's main job (`omnical demo`) writes a report,
# headless Chromium opens it (no console errors, no fetches, every figure drawn) and saves a screenshot; a
# deliberately broken page must be rejected, so the check itself can fail.
set -euo pipefail
cd "$(dirname "$0")/.."
PY="${OMNICAL_PYTHON:-.venv/bin/python}"
out=target/report-check
figures=ladder,overlay-worst,overlay-typical,flower,heat-map,growth,trust-ellipses,trust-growth,ranking
cargo run --release --quiet -p omni-cli -- demo --out "$out" --force --quiet
"$PY" scripts/check_report.py "$out/report.html" --screenshot "$out/screenshot.png" --expect "$figures"
if "$PY" scripts/check_report.py scripts/testdata/broken_report.html --screenshot "$out/broken.png" \
    --expect "$figures" >"$out/broken.log" 2>&1; then
  echo "check_report.py accepted scripts/testdata/broken_report.html" >&2
  exit 1
fi
grep -q "console error" "$out/broken.log" && grep -q "no <svg>" "$out/broken.log" && grep -q "fetched" "$out/broken.log" \
  || { cat "$out/broken.log" >&2; echo "check_report.py rejected the broken page for the wrong reasons" >&2; exit 1; }
echo "browser check passed (and rejects a broken page)"
