#!/bin/sh
# Public LIGGGHTS tutorials (Debian package liggghts-doc) run by demdesign and by LIGGGHTS on the
# same machine, and their figures side by side (bench/tutorials_compare.py prints the table).
#   bench/tutorials_side_by_side.sh
# chute_wear: cases/liggghts_chute_wear.yaml (the tutorial's own chute mesh) against
# bench/liggghts/chute_wear.in (the tutorial's deck, 3 s instead of 1 s, with thermo figures);
# averages over 1.5 to 3 s. Appends the figures to bench/results/tutorials_side_by_side.csv.
set -e
BUILD=${BUILD:-build}
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/.." && pwd)
. "$HERE/liggghts/ensure_installed.sh"
TUTORIALS=/usr/share/doc/liggghts/examples/LIGGGHTS/Tutorials_public
if [ ! -d "$TUTORIALS/chute_wear" ]; then
  echo "installing the Debian package liggghts-doc (the tutorials' decks and meshes)"
  sudo_cmd=""; [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get install -y -q liggghts-doc >/dev/null
fi
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
echo "chute_wear: demdesign (1 thread) and LIGGGHTS (1 process), 3 s each; commit $COMMIT, $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg)"
start=$(date +%s)
"$ROOT/$BUILD/app/demdesign" "$ROOT/cases/liggghts_chute_wear.yaml" --threads 1 --no-report --quiet --out "$WORK/demdesign" > "$WORK/dem.log" 2>&1 ||
  { tail -20 "$WORK/dem.log"; exit 1; }
mid=$(date +%s)
(cd "$WORK" && liggghts -in "$HERE/liggghts/chute_wear.in" -var dir "$TUTORIALS/chute_wear" -log none -echo none > lig.txt 2>&1) ||
  { tail -20 "$WORK/lig.txt"; exit 1; }
end=$(date +%s)
echo "wall time: demdesign $((mid - start)) s, LIGGGHTS $((end - mid)) s"
python3 "$HERE/tutorials_compare.py" chute_wear "$WORK/demdesign" "$WORK/lig.txt" 1.5 3.0 > "$WORK/table.txt"
grep -v '^csv,' "$WORK/table.txt"
CSV="$HERE/results/tutorials_side_by_side.csv"
[ -f "$CSV" ] || echo "date,commit,tutorial,figure,demdesign,demdesign_std_error,liggghts,liggghts_std_error" > "$CSV"
grep '^csv,' "$WORK/table.txt" | sed "s/^csv,/$(date +%F),$COMMIT,/" >> "$CSV"
