#!/bin/sh
# B1 scaling series: cost per particle step from 10,000 to 1,000,000 particles (the 20k bed's 32
# lattice layers on a wider footprint, see bench_b1_settle), on 2 threads, and the thread
# speed-up from 1 to 2 cores at 100,000. Phases are shortened (the settle phase's first STEPS1
# steps: free fall and first impacts; then STEPS2 steps), the same for every size, so the cost per
# particle step compares across sizes.
#   bench/b1_scaling.sh [STEPS1=2000] [STEPS2=200]      (RESULTS=file.csv keeps the rows)
set -e
S1=${1:-2000}
S2=${2:-200}
BUILD=${BUILD:-build}
OUT=$(mktemp)
trap 'rm -f "$OUT"' EXIT
echo "B1 scaling, phase 1 $S1 steps, phase 2 $S2 steps; machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "csv,N,phase,steps,threads,seconds,particle_steps_per_s,contacts_per_particle,pp_contacts_per_particle,bed_height_m,max_overlap_ratio,kinetic_J,rebuilds,peak_MiB,peak_bytes_per_particle,hot_bytes_per_particle,engine_bytes_per_particle" > "$OUT"
for threads in 2 1; do
  sizes="10000 30000 100000 300000 1000000"
  [ "$threads" = 1 ] && sizes="100000"
  for n in $sizes; do
    OMP_NUM_THREADS=$threads "$BUILD/bench/bench_b1_settle" --n "$n" --threads "$threads" --phase1-steps "$S1" --phase2-steps "$S2" |
      grep '^csv,[0-9]' >> "$OUT"
  done
done
awk -F, 'NR > 1 {printf "%-8s %-7s %-8s %-12.4g %-14.1f %-10.0f\n", $2, $3, $5, $7, 1e9 * $5 / $7, $15}
  BEGIN {printf "%-8s %-7s %-8s %-12s %-14s %-10s\n", "N", "phase", "threads", "p-steps/s", "ns/p-step/core", "peak B/p"}' "$OUT"
awk -F, '$2 > 99000 && $2 < 101000 {r[$3 "," $5] = $7} END {printf "speed-up 1 -> 2 threads at 100k: settle %.2f, dense %.2f\n", r["settle,2"] / r["settle,1"], r["dense,2"] / r["dense,1"]}' "$OUT"
[ -n "$RESULTS" ] && cp "$OUT" "$RESULTS"
exit 0
