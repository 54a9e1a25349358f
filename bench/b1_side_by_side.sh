#!/bin/sh
# Benchmark B1 in demdesign and in LIGGGHTS on the same machine, alternating the two codes, and the
# ratio of their particle time steps per second (timed loops only) and peak memory per particle.
#   bench/b1_side_by_side.sh [N=20000|100000] [REPETITIONS=3] [PHASE1_STEPS] [PHASE2_STEPS]
# demdesign: 2 OpenMP threads (build/bench/bench_b1_settle); LIGGGHTS: 2 MPI ranks (mpirun -np 2).
# Same lattice (written by bench_b1_settle), same contact law, time step, skin and phases. The
# physics check compares touching pairs per particle and the bed height at the end of each phase.
set -e
N=${1:-20000}
REPS=${2:-3}
S1=${3:-20000}
if [ "$N" = 20000 ]; then L=0.125; S2=${4:-4000}; else L=0.25; S2=${4:-1000}; fi
BUILD=${BUILD:-build}
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/liggghts/ensure_installed.sh"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
"$BUILD/bench/bench_b1_settle" --n "$N" --liggghts-data "$WORK/lattice.data"
echo "B1 N=$N, phase 1 $S1 steps, phase 2 $S2 steps, $REPS repetitions alternating; machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
printf 'rep,code,phase,particle_steps_per_s,pairs_per_particle,bed_height_m,peak_bytes_per_particle\n' > "$WORK/rows.csv"
rep=1
while [ "$rep" -le "$REPS" ]; do
  # demdesign: the csv lines of the benchmark program; peak memory from /usr/bin/time.
  /usr/bin/time -f "peakKB %M" -o "$WORK/dem_time.txt" "$BUILD/bench/bench_b1_settle" --n "$N" --threads 2 \
    --phase1-steps "$S1" --phase2-steps "$S2" > "$WORK/dem.txt"
  peak=$(awk '/peakKB/ {print $2}' "$WORK/dem_time.txt")
  awk -F, -v rep="$rep" -v peak="$peak" -v n="$N" '/^csv,[0-9]/ {printf "%s,demdesign,%s,%s,%s,%s,%.0f\n", rep, $3, $7, $9, $10, peak*1024/n}' \
    "$WORK/dem.txt" >> "$WORK/rows.csv"
  # LIGGGHTS: "Loop time of T on P procs for S steps with A atoms" per run; thermo rows give the
  # pairs and the top; each rank's peak memory from /usr/bin/time, summed.
  (cd "$WORK" && mpirun --allow-run-as-root --oversubscribe -np 2 /usr/bin/time -f "peakKB %M" -a -o lig_time.txt \
     liggghts -in "$HERE/liggghts/b1.in" -log none -echo none -var data lattice.data -var lx "$L" -var ly "$L" \
     -var n1 "$S1" -var n2 "$S2" > lig.txt 2>&1)
  peak=$(awk '/peakKB/ {s += $2} END {print s}' "$WORK/lig_time.txt"); rm -f "$WORK/lig_time.txt"
  awk -v rep="$rep" -v peak="$peak" -v n="$N" '
    $1 == "Step" {inrun = 1; next}
    inrun && $1 ~ /^[0-9]+$/ && NF >= 5 {atoms = $2; pairs = $4; top = $5}
    /^Loop time of/ {phase++; printf "%s,liggghts,%s,%.6g,%.4f,%.5f,%.0f\n", rep, (phase == 1 ? "settle" : "dense"), $12 * $9 / $4, pairs / atoms, top + 0.002, peak * 1024 / n; inrun = 0}
  ' "$WORK/lig.txt" >> "$WORK/rows.csv"
  rep=$((rep + 1))
done
cat "$WORK/rows.csv" > "${OUT:-/dev/null}" 2>/dev/null || true
# Medians per code and phase, and the ratios.
awk -F, 'NR > 1 {key = $2 "," $3; v[key] = v[key] " " $4; p[key] = $5; h[key] = $6; m[key] = $7}
  END {
    for (k in v) { n = split(v[k], a, " "); for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++) if (a[j] < a[i]) {t = a[i]; a[i] = a[j]; a[j] = t}
                   med[k] = (n % 2) ? a[(n + 1) / 2] : (a[n / 2] + a[n / 2 + 1]) / 2 }
    printf "\n%-8s %-20s %-20s %-8s %-22s %-18s %-14s\n", "phase", "demdesign p-steps/s", "LIGGGHTS p-steps/s", "ratio", "pairs/particle d | L", "bed [m] d | L", "bytes/p d | L"
    split("settle dense", ph, " ")
    for (i = 1; i <= 2; i++) {
      d = "demdesign," ph[i]; l = "liggghts," ph[i]
      printf "%-8s %-20.4g %-20.4g %-8.2f %-22s %-18s %-14s\n", ph[i], med[d], med[l], med[d] / med[l], p[d] " | " p[l], h[d] " | " h[l], m[d] " | " m[l]
    }
  }' "$WORK/rows.csv"
echo "(medians over the repetitions; memory = peak resident set of the whole process(es) / N)"
cp "$WORK/rows.csv" "${RESULTS:-$WORK/rows.csv}" 2>/dev/null || true
