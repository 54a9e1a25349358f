#!/usr/bin/env python3
"""Observables of the virtual lab tests against their time step.

Each standard set-up of bench/lab/setups.txt (the drop test runs at its own step and is left out)
runs at time steps of --fractions of the Rayleigh time, each with --seeds packings, two
simulations at a time, one core each. Printed per test and observable: the mean and the scatter
between packings (the replica noise) at each step, and the shift of the mean from the smallest
step, in units of the noise, with its standard error (four packings a step resolve a shift of
about 0.7 of the noise, eight about 0.5: the printed error says how far the data can tell). The
lab tests' rule (materials/lab/virtual_tests.h, kLabRayleighFraction) is the largest step whose
shift stays under a quarter of the noise for every observable, as far as the packings resolve
it. Rows are appended to bench/results/lab_time_step.csv.

    bench/lab_time_step.py [--material bench/lab/beads_plain.yaml] [--seeds 4]
                           [--fractions 0.1,0.15,0.2,0.25] [--tests all] [--workers 2] [--first-seed 1]
                           [--summary COMMITS]   (no runs: the summary of the csv's rows)
"""

import argparse
import datetime
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "lab"))
import labbench  # noqa: E402

QUARTER = 0.25  # [noise] the largest shift a step may cause


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--material", default=os.path.join(labbench.HERE, "beads_plain.yaml"))
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--first-seed", type=int, default=1, help="packing seeds first-seed .. first-seed + seeds - 1")
    ap.add_argument("--fractions", default="0.1,0.15,0.2,0.25")
    ap.add_argument("--tests", default="all", help="comma-separated set-up ids of bench/lab/setups.txt")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--csv", default=os.path.join(labbench.ROOT, "bench", "results", "lab_time_step.csv"))
    ap.add_argument("--summary", metavar="COMMITS", help="no runs: summarise the csv rows of these commits (comma-separated; 'all': every row)")
    args = ap.parse_args()
    fractions = [float(f) for f in args.fractions.split(",")]
    setups = [s for s in labbench.select(labbench.read_setups(), args.tests) if s.test != "drop_rebound"]
    name = os.path.splitext(os.path.basename(args.material))[0]
    if args.summary:
        commits = [] if args.summary == "all" else args.summary.split(",")
        summarise(from_csv(args.csv, name, commits, [s.id for s in setups], fractions), [s.id for s in setups], fractions)
        return
    jobs, keys = [], []
    for s in setups:
        for f in fractions:
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                keys.append((s, f, seed))
                jobs.append(lambda core, s=s, f=f, seed=seed: labbench.run_demdesign(args.material, s, seed, f, core))
    commit, today = labbench.commit(), datetime.date.today().isoformat()
    print(f"{len(jobs)} simulations of {name}, {args.workers} at a time; {labbench.machine()}; commit {commit}", flush=True)
    new = not os.path.exists(args.csv)
    with open(args.csv, "a") as csv:
        if new:
            csv.write("date,commit,material,id,rayleigh_fraction,seed,observable,value,flags,time_step_s,wall_s\n")

        def done(k, r):
            s, f, seed = keys[k]
            if isinstance(r, Exception):
                return
            for obs, v in r.observables.items():
                csv.write(f"{today},{commit},{name},{s.id},{f},{seed},{obs},{v:.6g},{'+'.join(r.flags)},{r.time_step:.4g},{r.wall:.1f}\n")
            csv.flush()
            print(f"  {s.id} at {f:g} T_R, seed {seed}: " + ", ".join(f"{o} {v:.4g}" for o, v in r.observables.items())
                  + (f" [{', '.join(r.flags)}]" if r.flags else "") + f" (step {r.time_step:.3g} s, {r.wall:.0f} s)", flush=True)

        results = labbench.run_jobs(jobs, args.workers, done)

    summarise([(s.id, f, r.observables, r.flags, r.wall) for (s, f, _), r in zip(keys, results) if not isinstance(r, Exception)],
              [s.id for s in setups], fractions)


def summarise(rows, ids, fractions):
    """rows: (set-up id, fraction, observables, flags, wall seconds) per run."""
    print("\nper test and observable: mean +- scatter between packings at each step [mean wall s]; the shift of the mean from the "
          "smallest step in units of the scatter (the replica noise), +- its standard error")
    largest_ok = max(fractions)
    for ident in ids:
        runs = [(f, obs, flags, wall) for i, f, obs, flags, wall in rows if i == ident]
        if not runs:
            continue
        for name in runs[0][1]:
            by_f = {f: [obs[name] for ff, obs, _, _ in runs if ff == f and name in obs] for f in fractions}
            spreads = [statistics.stdev(v) for v in by_f.values() if len(v) > 1]
            noise = math.sqrt(statistics.mean([v * v for v in spreads])) if spreads else float("nan")
            print(f"{ident:13s} {name:20s} noise {noise:.4g}")
            base = by_f[fractions[0]]
            for f in fractions:
                v = by_f[f]
                if not v:
                    continue
                walls = [w for ff, _, _, w in runs if ff == f]
                flags = sorted({fl for ff, _, fls, _ in runs if ff == f for fl in fls})
                shift = (statistics.mean(v) - statistics.mean(base)) / noise if noise > 0 else float("nan")
                error = math.sqrt(1 / len(v) + 1 / len(base)) if f != fractions[0] else 0.0
                ok = f == fractions[0] or noise == 0 or abs(shift) < QUARTER
                if not ok:
                    largest_ok = min(largest_ok, max([g for g in fractions if g < f], default=fractions[0]))
                print(f"    {f:5.3f} T_R: {statistics.mean(v):10.4g} +- {statistics.stdev(v) if len(v) > 1 else 0:<8.3g} n {len(v):2d} "
                      f"[{statistics.mean(walls):4.0f} s]  shift {shift:+.2f} +- {error:.2f} noise{'' if ok else '  > a quarter'}"
                      + (f"  {', '.join(flags)}" if flags else ""))
    print(f"\nlargest step whose shift stays under {QUARTER} of the noise for every observable: {largest_ok:g} of the Rayleigh time "
          "(the standard errors say how small a shift the packings can resolve)")


def from_csv(path, material, commits, ids, fractions):
    rows = {}
    with open(path) as f:
        next(f)
        for line in f:
            date, commit, mat, ident, fraction, seed, name, value, flags, step, wall = line.rstrip("\n").split(",")
            if mat != material or (commits and commit not in commits) or ident not in ids or float(fraction) not in fractions:
                continue
            # A packing run again by a later commit (the same seed and step) counts once: the last row.
            key = (ident, float(fraction), seed)
            if key not in rows or rows[key][5] != commit:
                rows[key] = (ident, float(fraction), {}, flags.split("+") if flags else [], float(wall), commit)
            rows[key][2][name] = float(value)
    return [r[:5] for r in rows.values()]


if __name__ == "__main__":
    main()
