#!/bin/sh
# Public LIGGGHTS tutorials (Debian package liggghts-doc) run by demdesign and by LIGGGHTS on the
# same machine, and their figures side by side (bench/tutorials_compare.py prints the table).
#   bench/tutorials_side_by_side.sh [chute_wear|conveyor|moving_mesh]
# chute_wear: cases/liggghts_chute_wear.yaml (the tutorial's own chute mesh) against
# bench/liggghts/chute_wear.in (the tutorial's deck, 3 s instead of 1 s, with thermo figures);
# averages over 1.5 to 3 s. conveyor: cases/liggghts_conveyor.yaml against
# bench/liggghts/conveyor.in, averages over 0.3 to 1.1 s (while the feed runs). moving_mesh:
# cases/liggghts_moving_mesh.yaml against bench/liggghts/moving_mesh.in (movingMeshGran), a
# transient run, so each code runs SEEDS fills (default 12) and the figures are their means. Appends
# the figures to bench/results/tutorials_side_by_side.csv.
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
# KEEP=DIR keeps the runs in DIR; otherwise they go to a temporary folder removed at the end.
if [ -n "$KEEP" ]; then WORK=$KEEP; mkdir -p "$WORK"; else WORK=$(mktemp -d); trap 'rm -rf "$WORK"' EXIT; fi
COMMIT=$(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)
CSV="$HERE/results/tutorials_side_by_side.csv"
[ -f "$CSV" ] || echo "date,commit,tutorial,figure,demdesign,demdesign_std_error,liggghts,liggghts_std_error" > "$CSV"
echo "commit $COMMIT, $(nproc) cores, load $(cut -d' ' -f1-3 /proc/loadavg); demdesign on 1 thread, LIGGGHTS on 1 process"
# side TUTORIAL T0 T1: both codes, then the figures averaged over [T0, T1] s
side() {
  start=$(date +%s)
  "$ROOT/$BUILD/app/demdesign" "$ROOT/cases/liggghts_$1.yaml" --threads 1 --no-report --quiet --overwrite --out "$WORK/$1_demdesign" > "$WORK/$1_dem.log" 2>&1 ||
    { tail -20 "$WORK/$1_dem.log"; exit 1; }
  mid=$(date +%s)
  (cd "$WORK" && liggghts -in "$HERE/liggghts/$1.in" -var dir "$TUTORIALS/$1" -log none -echo none > "$1_lig.txt" 2>&1) ||
    { tail -20 "$WORK/$1_lig.txt"; exit 1; }
  end=$(date +%s)
  echo "$1: wall time demdesign $((mid - start)) s, LIGGGHTS $((end - mid)) s"
  python3 "$HERE/tutorials_compare.py" "$1" "$WORK/$1_demdesign" "$WORK/$1_lig.txt" "$2" "$3" > "$WORK/$1_table.txt"
  grep -v '^csv,' "$WORK/$1_table.txt"
  grep '^csv,' "$WORK/$1_table.txt" | sed "s/^csv,/$(date +%F),$COMMIT,/" >> "$CSV"
}
# replicas TUTORIAL FOLDER: a transient case (FOLDER: its folder among the tutorials), both codes
# filled with SEEDS different seeds each
replicas() {
  dem_runs=""; lig_runs=""; start=$(date +%s); dem_time=0
  for seed in $SEEDS; do
    sed "s/^  seed: 1$/  seed: $seed/" "$ROOT/cases/liggghts_$1.yaml" > "$WORK/$1_$seed.yaml"
    t0=$(date +%s)
    "$ROOT/$BUILD/app/demdesign" "$WORK/$1_$seed.yaml" --threads 1 --no-report --quiet --overwrite --out "$WORK/$1_dem_$seed" > "$WORK/$1_dem.log" 2>&1 ||
      { tail -20 "$WORK/$1_dem.log"; exit 1; }
    t1=$(date +%s); dem_time=$((dem_time + t1 - t0))
    # LIGGGHTS seeds must be primes above 10000: the seed-th prime after the deck's own
    prime=$(python3 -c "import sys
n, k = 32452843, int(sys.argv[1]) - 1
isp = lambda m: m > 1 and all(m % d for d in range(2, int(m ** 0.5) + 1))
while k > 0:
    n += 2
    k -= isp(n)
print(n)" "$seed")
    (cd "$WORK" && liggghts -in "$HERE/liggghts/$1.in" -var dir "$TUTORIALS/$2" -var seed "$prime" -log none -echo none > "$1_lig_$seed.txt" 2>&1) ||
      { tail -20 "$WORK/$1_lig_$seed.txt"; exit 1; }
    dem_runs="$dem_runs${dem_runs:+,}$WORK/$1_dem_$seed"; lig_runs="$lig_runs${lig_runs:+,}$WORK/$1_lig_$seed.txt"
  done
  end=$(date +%s)
  echo "$1: wall time per run demdesign $((dem_time / $(echo $SEEDS | wc -w))) s, LIGGGHTS $(((end - start - dem_time) / $(echo $SEEDS | wc -w))) s"
  python3 "$HERE/tutorials_compare.py" "$1" "$dem_runs" "$lig_runs" > "$WORK/$1_table.txt"
  grep -v '^csv,' "$WORK/$1_table.txt"
  grep '^csv,' "$WORK/$1_table.txt" | sed "s/^csv,/$(date +%F),$COMMIT,/" >> "$CSV"
}
SEEDS=${SEEDS:-"1 2 3 4 5 6 7 8 9 10 11 12"}
case "${1:-all}" in
  chute_wear) side chute_wear 1.5 3.0 ;;
  conveyor) side conveyor 0.3 1.1 ;;
  moving_mesh) replicas moving_mesh movingMeshGran ;;
  *) side chute_wear 1.5 3.0; side conveyor 0.3 1.1; replicas moving_mesh movingMeshGran ;;
esac
