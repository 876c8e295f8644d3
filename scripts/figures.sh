#!/usr/bin/env bash
# The README's and docs' figures (issue 48): each names the command and data it comes from in
# crates/omni-cli/tests/figures.rs, which reruns them and fails when one drifts beyond its tolerance.
# `cargo test` runs the fast ones (small simulated sets; `eval` on ../shared/data); this script runs them
# all, the slow ones too (a `train` on the real logs, the 180 + 180-run simulated set), in release.
#
#   bash scripts/figures.sh           check every figure
#   bash scripts/figures.sh --write   rewrite each drifted figure in its document with the regenerated value
#
# Timings (load and fit times) are not figures here: they depend on the machine and are measured in
# benches/README.md.
set -euo pipefail
cd "$(dirname "$0")/.." || exit 2
if [ "${1:-}" = "--write" ]; then
  export OMNICAL_FIGURES=write
fi
exec cargo test --release -p omni-cli --test figures -- --include-ignored
