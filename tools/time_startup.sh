#!/usr/bin/env bash
# Start-up time of commands that touch no image: the median wall time of N runs of
# `candela --version` and of `candela info` on a small scene, with the load average.
#   bash tools/time_startup.sh [CANDELA] [N]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
candela="${1:-$root/build/candela}"
n="${2:-20}"
median() { sort -n | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }
time_runs() {
    for _ in $(seq "$n"); do
        local t0 t1
        t0=$(date +%s.%N)
        "$@" > /dev/null 2>&1
        t1=$(date +%s.%N)
        echo "$t1 - $t0" | bc -l
    done | median
}
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
printf 'candela --version                          median of %s: %.3f s\n' "$n" \
    "$(time_runs "$candela" --version)"
printf 'candela info scenes/cornell-box.dae        median of %s: %.3f s\n' "$n" \
    "$(time_runs "$candela" info "$root/scenes/cornell-box.dae")"
