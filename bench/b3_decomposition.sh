#!/bin/sh
# Benchmark B3 "split box" (bench/b3_domain.cpp): B1 on one process (1 and 2 OpenMP threads) and
# split into slabs over 2 MPI ranks of 1 thread each, on this machine, alternating, REPS times.
# Prints particle-steps/s, the speed-up of the split run over one thread, and rank 0's
# communication figures; appends the csv lines to bench/results/b3_decomposition.csv with the machine.
# SPLIT_OPTIONS go to the split runs alone and into the csv's last column: "--balance time" cuts
# the slabs by measured computing time, "--frames DIR" writes a frame after each phase together
# and gathered (bench/b3_domain.cpp), "--rank-grid 2x2x1" asks for a grid.
#
# BED (a file name) measures one settled bed in every configuration: when the file is missing, the
# settle phase runs once on one process with 2 threads and writes it (bench/b3_domain.cpp --bed);
# then each configuration times the dense phase from it alone. CONFIGS lists the configurations
# as "ranks threads" pairs separated by commas (default "1 1,1 2,2 1"; "4 1" oversubscribes 2 cores).
#
# Usage: [BED=FILE] [CONFIGS="1 1,1 2,2 1,4 1"] sh bench/b3_decomposition.sh [BUILD_DIR] [N] [PHASE1_STEPS] [PHASE2_STEPS] [REPS] [SPLIT_OPTIONS]
set -eu
build=${1:-build}
n=${2:-20000}
s1=${3:-20000}
s2=${4:-4000}
reps=${5:-1}
split_options=${6:-}
bin="$build/bench/bench_b3_domain"
[ -x "$bin" ] || { echo "no $bin: build with -DDEMDESIGN_MPI=ON (cmake --build $build --target bench_b3_domain)"; exit 2; }
out=$(dirname "$0")/results/b3_decomposition.csv
machine="$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //') x $(nproc)"
[ -f "$out" ] || echo "date,machine,N,phase,steps,ranks,threads_per_rank,seconds,particle_steps_per_s,contacts_per_particle,bed_height_m,split_options" > "$out"
configs=${CONFIGS:-1 1,1 2,2 1}
log=$(mktemp)
bed_option=
if [ -n "${BED:-}" ]; then
  bed_option="--bed $BED"
  if [ ! -f "$BED" ]; then
    echo "== the settled bed: settle phase on 1 rank x 2 threads, written to $BED"
    OMP_NUM_THREADS=2 "$bin" --n "$n" --threads 2 --phase1-steps "$s1" --phase2-steps 0 --bed "$BED" | grep -v ',dense,' | tee -a "$log"
  fi
fi
for rep in $(seq "$reps"); do
  echo "$configs" | tr ',' '\n' | while read -r ranks threads; do
    echo "== repetition $rep: $ranks rank(s) x $threads thread(s)"
    if [ "$ranks" = 1 ]; then
      OMP_NUM_THREADS=$threads "$bin" --n "$n" --threads "$threads" --phase1-steps "$s1" --phase2-steps "$s2" $bed_option | tee -a "$log"
    else
      mpirun --allow-run-as-root --oversubscribe -np "$ranks" -x OMP_NUM_THREADS="$threads" "$bin" --n "$n" --threads "$threads" \
        --phase1-steps "$s1" --phase2-steps "$s2" $bed_option $split_options < /dev/null | tee -a "$log"
    fi
  done
done
grep '^csv,[0-9]' "$log" | awk -v opts="$split_options" -v bed="${BED:+from a settled bed}" -F, \
  '{o = ($5 > 1 ? opts : ""); b = ($3 == "settle" ? "writes the settled bed" : bed);
    if (bed != "") o = (o == "" ? b : o " " b); print $0 "," o}' |
  sed "s/^csv,/$(date -u +%Y-%m-%d),\"$machine\",/" >> "$out"
echo
echo "N = $n: median particle-steps/s per configuration and phase (speed-up over 1 rank x 1 thread)"
for phase in settle dense; do
  grep -q "^csv,[0-9]*,$phase," "$log" || continue
  base=$(grep "^csv,[0-9]*,$phase,[0-9]*,1,1," "$log" | cut -d, -f8 | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
  for config in $(echo "$configs" | tr ',' '\n' | tr ' ' ','); do
    rate=$(grep "^csv,[0-9]*,$phase,[0-9]*,$config," "$log" | cut -d, -f8 | sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}')
    [ -n "$rate" ] && [ -n "$base" ] || continue
    echo "$phase ranks,threads=$config: $rate ($(awk -v r="$rate" -v b="$base" 'BEGIN {printf "%.2f", r / b}')x)"
  done
done
rm -f "$log"
