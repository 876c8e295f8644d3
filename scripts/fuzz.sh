#!/usr/bin/env bash
# Fuzz the dataset readers: `scripts/fuzz.sh [SECONDS] [TARGET...]` runs each cargo-fuzz target (default:
# all of fuzz/fuzz_targets) for SECONDS (default 600) and prints libFuzzer's final figures.
#
# Toolchain: only stable Rust is needed. `-s none` (no sanitizer) avoids the `-Zsanitizer` flag, the one
# nightly-only flag cargo-fuzz passes; libFuzzer's coverage instrumentation (`-Cpasses=sancov-module`,
# `-Cllvm-args=-sanitizer-coverage-*`) is stable. Panics, overflow checks (on: cargo-fuzz's default
# `--debug-assertions`), out-of-memory (-rss_limit_mb) and hangs (-timeout) are what it finds.
#
# Corpus: fuzz/seeds/<target>/ (committed) and, for the readers, tests/data/bad/ seed the run; what
# libFuzzer adds goes to fuzz/corpus/<target>/ (not committed). A crash lands in fuzz/artifacts/<target>/:
# reproduce it with `cargo fuzz run -s none <target> <file>`, fix the reader, and add the file to
# tests/data/bad/ (with its expected message) so `cargo test` replays it from then on.
# Costs (2 shared cores): installing cargo-fuzz ~1 min, building the targets cold ~7 min. cargo-fuzz is
# installed into the repository's .tools/ (git-ignored), not the home folder, when no `cargo fuzz` is found.
set -euo pipefail
cd "$(dirname "$0")/../fuzz"
export PATH="$PWD/../.tools/bin:$PATH"
SECONDS_PER_TARGET="${1:-600}"
shift || true
TARGETS=("$@")
if [ ${#TARGETS[@]} -eq 0 ]; then
  TARGETS=($(cd fuzz_targets && ls *.rs | sed 's/\.rs$//'))
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
  cargo install cargo-fuzz --locked --root ../.tools
fi
cargo fuzz build -s none
for t in "${TARGETS[@]}"; do
  mkdir -p "corpus/$t" "seeds/$t"
  seeds=("seeds/$t")
  case "$t" in
    mcap_read) ext=mcap ;;
    csv_read) ext=csv ;;
    *) ext="" ;;
  esac
  if [ -n "$ext" ]; then
    mkdir -p "target/bad-$ext"
    find ../tests/data/bad -name "*.$ext" -exec cp {} "target/bad-$ext/" \; 2>/dev/null || true
    seeds+=("target/bad-$ext")
  fi
  echo "== fuzz $t for ${SECONDS_PER_TARGET} s"
  cargo fuzz run -s none "$t" "corpus/$t" "${seeds[@]}" -- \
    -max_total_time="$SECONDS_PER_TARGET" -rss_limit_mb=2048 -timeout=10 -max_len=262144 \
    -print_final_stats=1 2>&1 | tee "target/fuzz-$t.log" | grep -E '(INITED|DONE) +cov|^(Done|stat::|==|SUMMARY)|panicked' || true
  crashes=$(ls "artifacts/$t" 2>/dev/null | wc -l)
  echo "corpus/$t: $(ls "corpus/$t" | wc -l) inputs; crashes: $crashes"
  found=$((${found:-0} + crashes))
done
if [ "${found:-0}" -gt 0 ]; then
  echo "fuzzing found ${found} crashing inputs: see fuzz/artifacts/" >&2
  exit 1
fi
