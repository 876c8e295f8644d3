#!/usr/bin/env bash
# Speed of the science (issue 25, item 10): `diagnose`, `diagnose --auto`, `explore`, `report` and
# `train --effect E` against plain `train` on the same runs, release build, 2 threads. Prints a markdown table:
# wall seconds (CPU seconds, user + system), and the wall time as a multiple of `train`'s.
#
#   bash benches/science.sh [BIN] [WORK_DIR]    (defaults: target/release/omnical, built here; target/bench-science)
#   ONLY_SIM=1 bash benches/science.sh …         (the simulated sets only)
#
# Sets: the shared OptiOdom omni4 squares (train on 231220200521, validate on 080920201715, and the reverse);
# a simulated 108-run omni4 set (3 runs of each of the 36 flower commands, 4 wheels at the corners of a
# square, a hidden clock lag of 60 ms and wheel b 1.5 % large; validation: its 108-run twin); and the
# paper-size 180 + 180 simulated runs (`omnical simulate` defaults: `train` and `report` only).
# On a shared machine run it as root: each command then runs under `chrt -f 50` (the other processes wait).
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-}
if [ -z "$bin" ]; then
    cargo build --release --quiet -p omni-cli --bin omnical
    bin=target/release/omnical
fi
work=${2:-target/bench-science}
omni4=${OMNI4:-/work/shared/data/optiodom-omni4-square}
mkdir -p "$work"
rt=()
if [ "$(id -u)" = 0 ] && command -v chrt > /dev/null; then rt=(chrt -f 50); fi

# The simulated sets (written once).
if [ ! -d "$work/sim4/train" ]; then
    cat > "$work/omni4.toml" <<'EOF'
name = "omni4 bench base"
kind = "omni"
[[wheels]]
joint = "w0"
distance_m = 0.21
angle_deg = 45.0
radius_m = 0.0508
[[wheels]]
joint = "w1"
distance_m = 0.21
angle_deg = 135.0
radius_m = 0.0508
[[wheels]]
joint = "w2"
distance_m = 0.21
angle_deg = 225.0
radius_m = 0.0508
[[wheels]]
joint = "w3"
distance_m = 0.21
angle_deg = 315.0
radius_m = 0.0508
EOF
    "$bin" -q simulate --robot "$work/omni4.toml" --runs-per-command 3 --seed 1 \
        --effect time_offset=0.06 --effect wheel_radius:b=0.015 --out "$work/sim4" > /dev/null
fi
[ -d "$work/sim180/train" ] || "$bin" -q simulate --out "$work/sim180" > /dev/null

# time_of ARGS…: runs `omnical --threads 2 -q ARGS`, prints "wall cpu" seconds.
time_of() {
    if ! /usr/bin/time -o "$work/time.txt" -f "%e %U %S" "${rt[@]}" "$bin" --threads 2 -q "$@" \
        > /dev/null 2> "$work/stderr.txt"; then
        echo "failed: omnical $*" >&2
        cat "$work/stderr.txt" >&2
        exit 1
    fi
    awk '{printf "%.2f %.2f\n", $1, $2 + $3}' "$work/time.txt"
}

# bench NAME TRAIN VALIDATE COMMANDS…: the table rows of one set.
bench() {
    local name=$1 train=$2 validate=$3
    shift 3
    local fit="$work/$name.fit.toml"
    read -r tw tc < <(time_of train "$train" --out "$fit")
    printf '| %s | train | %s s (%s) | 1.0 |\n' "$name" "$tw" "$tc"
    for cmd in "$@"; do
        local args
        case $cmd in
            diagnose) args=(diagnose --model "$fit" "$train" --validate "$validate") ;;
            diagnose-auto) args=(diagnose --auto --model "$fit" "$train" --validate "$validate") ;;
            explore) args=(explore --model "$fit" "$train" --validate "$validate") ;;
            report) args=(report --model "$fit" "$train" --validate "$validate" --out "$work/$name.html") ;;
            effect:*) args=(train "$train" --effect "${cmd#effect:}") ;;
        esac
        read -r w c < <(time_of "${args[@]}")
        printf '| %s | %s | %s s (%s) | %.1f |\n' "$name" "${cmd/effect:/train --effect }" "$w" "$c" \
            "$(awk -v a="$w" -v b="$tw" 'BEGIN { print a / b }')"
    done
}

all=(diagnose diagnose-auto explore report effect:time_offset effect:wheel_eccentricity effect:learned:body)
echo "| set | command | wall (CPU) | × train |"
echo "|---|---|---|---|"
[ -n "${ONLY_SIM:-}" ] || bench omni4-A "$omni4/231220200521" "$omni4/080920201715" "${all[@]}"
[ -n "${ONLY_SIM:-}" ] || bench omni4-B "$omni4/080920201715" "$omni4/231220200521" "${all[@]}"
bench sim4-108 "$work/sim4/train" "$work/sim4/validation" "${all[@]}"
bench sim-180 "$work/sim180/train" "$work/sim180/validation" report
