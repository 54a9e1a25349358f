#!/bin/sh
# Benchmark B2 "mesh chute" in demdesign and in LIGGGHTS on the same machine, alternating the two
# codes, and the ratio of their particle time steps per second (timed phase only) and peak memory
# per particle.
#   bench/b2_side_by_side.sh [REPETITIONS=3] [FILL_STEPS=30000] [RUN_STEPS=3000]
# demdesign: 2 OpenMP threads (build/bench/bench_b2_chute); LIGGGHTS: 2 MPI ranks (mpirun -np 2,
# the project's deck bench/liggghts/b2_chute.in, split along the chute). Same chute STL (written
# by bench_b2_chute), contact law, feed, time step, skin and phases. The physics check compares,
# over the timed phase, the mean particle count in the chute, touching particle pairs per particle
# and the mass flow off the spoon lip (particles that left the domain x m / duration); on the
# full-length phases they should agree within a few percent (short fills are not yet steady).
set -e
REPS=${1:-3}
FILL=${2:-30000}
RUN=${3:-3000}
BUILD=${BUILD:-build}
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/liggghts/ensure_installed.sh"
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
"$BUILD/bench/bench_b2_chute" --write-stl "$WORK/chute.stl"
echo "B2 fill $FILL steps, timed $RUN steps, $REPS repetitions alternating; machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'); load average $(cut -d' ' -f1-3 /proc/loadavg)"
# m = 2500 kg/m^3 x pi/6 x (8 mm)^3, dt = 3e-5 s (the spec's).
MASS=6.70206432e-4
DT=3.0e-5
printf 'rep,code,particle_steps_per_s,mean_particles,pairs_per_particle,mass_flow_kg_s,peak_bytes_per_particle\n' > "$WORK/rows.csv"
rep=1
while [ "$rep" -le "$REPS" ]; do
  # demdesign: the csv line of the benchmark program; peak memory from /usr/bin/time.
  /usr/bin/time -f "peakKB %M" -o "$WORK/dem_time.txt" "$BUILD/bench/bench_b2_chute" --threads 2 \
    --fill-steps "$FILL" --run-steps "$RUN" > "$WORK/dem.txt"
  peak=$(awk '/peakKB/ {print $2}' "$WORK/dem_time.txt")
  awk -F, -v rep="$rep" -v peak="$peak" '$1 == "csv" && $2 == "run" {printf "%s,demdesign,%s,%s,%s,%s,%.0f\n", rep, $7, $8, $9, $10, peak * 1024 / $8}' \
    "$WORK/dem.txt" >> "$WORK/rows.csv"
  # LIGGGHTS: the thermo rows of the second (timed) run every 500 steps: step atoms ke pairs
  # inserted; inserted - atoms = particles that left the domain. "Loop time of T on P procs for
  # S steps with A atoms" closes each run. Each rank's peak memory from /usr/bin/time, summed.
  (cd "$WORK" && mpirun --allow-run-as-root --oversubscribe -np 2 /usr/bin/time -f "peakKB %M" -a -o lig_time.txt \
     liggghts -in "$HERE/liggghts/b2_chute.in" -log none -echo none -var stl chute.stl -var nfill "$FILL" -var nrun "$RUN" \
     > lig.txt 2>&1) || { tail -20 "$WORK/lig.txt"; exit 1; }
  peak=$(awk '/peakKB/ {s += $2} END {print s}' "$WORK/lig_time.txt"); rm -f "$WORK/lig_time.txt"
  awk -v rep="$rep" -v peak="$peak" -v mass="$MASS" -v dt="$DT" '
    $1 == "Step" {inrun = 1; next}
    inrun && runs == 1 && $1 ~ /^[0-9]+$/ && NF >= 5 {
      rows++; atoms += $2; pairs += ($2 > 0 ? $4 / $2 : 0)
      if (rows == 1) left0 = $5 - $2
      left1 = $5 - $2
    }
    /^Loop time of/ {
      runs++; inrun = 0
      if (runs == 2) {
        n = atoms / rows
        printf "%s,liggghts,%.6g,%.1f,%.4f,%.4f,%.0f\n", rep, n * $9 / $4, n, pairs / rows, (left1 - left0) * mass / ($9 * dt), peak * 1024 / n
      }
    }
  ' "$WORK/lig.txt" >> "$WORK/rows.csv"
  rep=$((rep + 1))
done
# Medians per code, the ratio, and the physics check (relative difference of the medians).
awk -F, 'NR > 1 {c = $2; r[c] = r[c] " " $3; n[c] = n[c] " " $4; p[c] = p[c] " " $5; q[c] = q[c] " " $6; m[c] = m[c] " " $7}
  function median(list,   a, k, i, j, t) {
    k = split(list, a, " ")
    for (i = 1; i <= k; i++) for (j = i + 1; j <= k; j++) if (a[j] < a[i]) {t = a[i]; a[i] = a[j]; a[j] = t}
    return (k % 2) ? a[(k + 1) / 2] : (a[k / 2] + a[k / 2 + 1]) / 2
  }
  function check(name, d, l,   diff) {
    diff = (l != 0) ? (d - l) / l : (d == 0 ? 0 : 1)
    printf "  %-24s %12.4g %12.4g %+8.1f %%  %s\n", name, d, l, 100 * diff, (diff < 0.05 && diff > -0.05) ? "ok" : "DIFFERS (> 5 %)"
  }
  END {
    d = "demdesign"; l = "liggghts"
    printf "\n%-20s %-20s %-8s %-16s\n", "demdesign p-steps/s", "LIGGGHTS p-steps/s", "ratio", "bytes/p d | L"
    printf "%-20.4g %-20.4g %-8.2f %-16s\n", median(r[d]), median(r[l]), median(r[d]) / median(r[l]), median(m[d]) " | " median(m[l])
    printf "\nphysics check (timed phase)  demdesign     LIGGGHTS   difference\n"
    check("particles in the chute", median(n[d]), median(n[l]))
    check("pairs per particle", median(p[d]), median(p[l]))
    check("mass flow off the lip kg/s", median(q[d]), median(q[l]))
  }' "$WORK/rows.csv"
echo "(medians over the repetitions; memory = peak resident set of the whole process(es) / mean particle count;"
echo " feed 20.11 kg/s; the check applies to full-length runs, a short fill is not yet steady)"
echo "load average at the end: $(cut -d' ' -f1-3 /proc/loadavg) (timings are only comparable on an otherwise idle machine)"
cp "$WORK/rows.csv" "${RESULTS:-$WORK/rows.csv}" 2>/dev/null || true
