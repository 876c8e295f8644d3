#!/usr/bin/env bash
# Report speed (issue 19): `omnical report` against `diagnose` (with and without --auto) and the drawing
# alone (`report --no-diagnose`) on the paper-size simulated set (180 + 180 runs, `omnical simulate`
# defaults), release build, 2 threads. Prints wall and CPU (user + system) seconds of each command.
#   bash benches/report.sh [DATA_DIR] [MODEL]   (default target/bench-report, model `design`)
# On a shared machine run it under `chrt -f 50` (as root) so the other processes wait.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --quiet -p omni-cli --bin omnical
bin=target/release/omnical
data=${1:-target/bench-report}
model=${2:-design}
[ -d "$data/train" ] || "$bin" -q simulate --out "$data" > /dev/null
runs=("$data/train" --validate "$data/validation")
for args in "diagnose --model $model" "diagnose --auto --model $model" \
    "report --model $model --out $data/report.html" "report --no-diagnose --model $model --out $data/report0.html"; do
    # shellcheck disable=SC2086
    /usr/bin/time -f "%e s wall, %U + %S s CPU: $args" "$bin" --threads 2 -q $args "${runs[@]}" > /dev/null
done
