#!/usr/bin/env bash
# Loading speed (issue 17): builds the release binary and prints `omnical eval` wall times on the
# paper-size simulated set as bare MCAP, rosbag2 sqlite3 and rosbag2 MCAP (benches/loading.py).
#   bash benches/loading.sh [DATA_DIR]     (default target/bench-loading; reused when present)
set -euo pipefail
cd "$(dirname "$0")/.."
python=${OMNICAL_PYTHON:-.venv/bin/python}
cargo build --release --quiet -p omni-cli --bin omnical
"$python" benches/loading.py target/release/omnical "${1:-target/bench-loading}"
