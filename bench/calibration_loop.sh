#!/bin/sh
# Wall time of the calibration loop a user runs with the default settings: compare, calibrate and
# diagnose of the cross-engine glass-bead material on one shipped 7-experiment measurement file
# (measured by LIGGGHTS, tests/data/cross_engine/), each command in a fresh output folder (no
# stored simulations), then the three again in one folder (compare -> calibrate -> diagnose: the
# later commands take the earlier ones' simulations from OUT/simulations/).
#   bench/calibration_loop.sh [SET=control] [EXTRA OPTIONS...]
# Prints the seconds of each command and appends a row per command to
# bench/results/calibration_loop.csv (date, commit, machine, set, command, mode, seconds, chi^2/n).
set -e
SET=${1:-control}
[ $# -gt 0 ] && shift
EXTRA="$*"
BUILD=${BUILD:-build}
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/.." && pwd)
BIN="$BUILD/app/demdesign"
MATERIAL="$ROOT/tests/data/cross_engine/glass_beads_6mm.yaml"
MEASURED="$ROOT/tests/data/cross_engine/$SET.yaml"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
CSV="$HERE/results/calibration_loop.csv"
[ -f "$CSV" ] || echo "date,commit,machine,set,command,mode,seconds,chi2_per_n" > "$CSV"
COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
MACHINE="$(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "calibration loop on $SET ($MEASURED), defaults${EXTRA:+ plus $EXTRA}; $MACHINE; commit $COMMIT"
run() {  # run MODE COMMAND OUT
  start=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$BIN" "$2" "$MATERIAL" "$MEASURED" --out "$3" --no-renders $EXTRA > "$WORK/$2.log" 2>&1 || { tail -20 "$WORK/$2.log"; exit 1; }
  seconds=$(awk -v a="$start" -v b="$(date +%s.%N)" 'BEGIN { print b - a }')
  chi=$(grep -o 'chi^2/n = [0-9.]*\|chi^2/n from [0-9.]* at the start to [0-9.]*\|chi^2/n falls from [0-9.]*' "$WORK/$2.log" | tail -1 | grep -o '[0-9.]*$')
  printf '%-10s %-8s %7.0f s   chi^2/n %s\n' "$2" "$1" "$seconds" "${chi:-?}"
  echo "$(date +%F),$COMMIT,\"$MACHINE\",$SET,$2,$1,$seconds,${chi:-}" >> "$CSV"
}
for command in compare calibrate diagnose; do run fresh "$command" "$WORK/fresh_$command"; done
for command in compare calibrate diagnose; do run chained "$command" "$WORK/chained"; done
