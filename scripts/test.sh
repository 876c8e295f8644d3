#!/usr/bin/env bash
# The project's test command (README): every Rust test in the workspace, then doc builds.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${OMNICAL_PYTHON:-}" ] && [ -x .venv/bin/python ]; then
  export OMNICAL_PYTHON="$PWD/.venv/bin/python"
fi
cargo test --workspace
RUSTDOCFLAGS=-Dwarnings cargo doc --workspace --no-deps --quiet
