#!/usr/bin/env bash
# The project's test command (README): every Rust test in the workspace, then doc builds.
#
# It first sets up what the tests need: the Python test tools of requirements-dev.txt (rosbags writes real
# rosbag2 bags, mcap-ros2-support decodes them as Foxglove does, evo checks the TUM export) in .venv,
# unless OMNICAL_PYTHON already names a Python that has them. A test whose tool is still missing is
# reported as ignored (with the reason) in cargo's summary, never as passed.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${OMNICAL_PYTHON:-}" ]; then
  stamp=.venv/.requirements-dev.installed
  if [ ! -x .venv/bin/python ] || [ ! -f "$stamp" ] || [ requirements-dev.txt -nt "$stamp" ]; then
    echo "== setting up .venv with requirements-dev.txt (Python test tools)"
    python3 -m venv .venv
    .venv/bin/pip install --quiet -r requirements-dev.txt
    touch "$stamp"
  fi
  export OMNICAL_PYTHON="$PWD/.venv/bin/python"
fi
# --no-fail-fast: one failing test binary does not hide the failures of the others.
cargo test --workspace --no-fail-fast
RUSTDOCFLAGS=-Dwarnings cargo doc --workspace --no-deps --quiet
