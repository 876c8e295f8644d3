#!/usr/bin/env bash
# The project's test command (README): every test, Rust and Python, then the doc build. It keeps what it
# installs in the repository's own (git-ignored) folders:
#
# 1. .venv/: the Python test tools of requirements-dev.txt (rosbags writes real rosbag2 bags,
#    mcap-ros2-support decodes them as Foxglove does, evo checks the TUM export, pytest, mypy, dask),
#    unless OMNICAL_PYTHON already names a Python that has them;
# 2. cargo test over the workspace (the README's shell and Rust blocks included: crates/omni-cli/tests/readme.rs),
#    in the release profile: the dependencies it compiles are the ones the demo's `cargo run --release`
#    compiled and the ones the wheel's build takes next (one build for all three, issue 48);
# 3. the wheel built from this tree into that Python as the README installs it (`pip install ".[fleet]"`:
#    maturin, release) in the same target folder (CARGO_TARGET_DIR: pip's isolated build would otherwise
#    compile every dependency again in a temporary one), then pytest over crates/omni-py/tests (the binding,
#    its doctests, the README's Python blocks) and mypy's stubtest of the compiled module's stubs;
# 4. cargo doc with warnings as errors.
#
# A test that cannot run here (a Python tool or the real robot logs ../shared/data missing) is reported as
# ignored (cargo) or skipped (pytest, with -rs: the reason is listed) in the summary, never as passed. Every
# step runs even when an earlier one failed; the exit status is the first failure's.
set -uo pipefail
cd "$(dirname "$0")/.." || exit 2
status=0
step() {
  echo "== $*"
  "$@" || { s=$?; echo "== FAILED ($s): $*" >&2; [ "$status" -ne 0 ] || status=$s; }
}
if [ -z "${OMNICAL_PYTHON:-}" ]; then
  stamp=.venv/.requirements-dev.installed
  if [ ! -x .venv/bin/python ] || [ ! -f "$stamp" ] || [ requirements-dev.txt -nt "$stamp" ]; then
    echo "== setting up .venv with requirements-dev.txt (Python test tools)"
    python3 -m venv .venv && .venv/bin/pip install --quiet -r requirements-dev.txt && touch "$stamp" || exit 2
  fi
  export OMNICAL_PYTHON="$PWD/.venv/bin/python"
fi
# One target folder for the tests, the wheel and the demo (an absolute path: maturin builds from a copy).
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
# --no-fail-fast: one failing test binary does not hide the failures of the others.
step cargo test --release --workspace --no-fail-fast
step "$OMNICAL_PYTHON" -m pip install --quiet ".[fleet]"
step bash -c 'cd crates/omni-py && "$OMNICAL_PYTHON" -m pytest tests -q -rs -p no:cacheprovider'
step "$OMNICAL_PYTHON" -m mypy.stubtest omnical
RUSTDOCFLAGS=-Dwarnings step cargo doc --workspace --no-deps --quiet
exit "$status"
