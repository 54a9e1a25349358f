#!/usr/bin/env python3
"""Observables of the virtual lab tests against their time step.

Each standard set-up of bench/lab/setups.txt (the drop test runs at its own step and is left out)
runs at time steps of --fractions of the Rayleigh time, each with --seeds packings, two
simulations at a time, one core each. Printed per test and observable: the mean and the scatter
between packings (the replica noise) at each step, and the least-squares line of the observable
against the step with the shift it predicts from the smallest step to each larger one, in units of
the noise, with its standard error (a line through 16 runs resolves a shift of about half the
noise: the printed error says how far the data can tell). The lab tests' rule
(materials/virtual_tests.h, kLabRayleighFraction) is the largest step whose predicted shift stays
under a quarter of the noise for every observable. Rows are appended to bench/results/lab_time_step.csv.

    bench/lab_time_step.py [--material bench/lab/beads_plain.yaml] [--seeds 4]
                           [--fractions 0.1,0.15,0.2,0.25] [--tests all] [--workers 2]
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


def line_fit(x, y):
    """Least-squares line y = a + b x: (a, b, standard error of b)."""
    n = len(x)
    mx, my = sum(x) / n, sum(y) / n
    sxx = sum((v - mx) ** 2 for v in x)
    if n < 3 or sxx == 0:
        return my, 0.0, float("inf")
    b = sum((u - mx) * (v - my) for u, v in zip(x, y)) / sxx
    a = my - b * mx
    srr = sum((v - a - b * u) ** 2 for u, v in zip(x, y))
    return a, b, math.sqrt(srr / (n - 2) / sxx)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--material", default=os.path.join(labbench.HERE, "beads_plain.yaml"))
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--fractions", default="0.1,0.15,0.2,0.25")
    ap.add_argument("--tests", default="all", help="comma-separated set-up ids of bench/lab/setups.txt")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--csv", default=os.path.join(labbench.ROOT, "bench", "results", "lab_time_step.csv"))
    args = ap.parse_args()
    fractions = [float(f) for f in args.fractions.split(",")]
    setups = [s for s in labbench.select(labbench.read_setups(), args.tests) if s.test != "drop_rebound"]
    name = os.path.splitext(os.path.basename(args.material))[0]
    jobs, keys = [], []
    for s in setups:
        for f in fractions:
            for seed in range(1, args.seeds + 1):
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

    print("\nper test and observable: mean +- scatter between packings at each step [wall s]; the line's shift "
          "from the smallest step, in units of the noise (+- its standard error)")
    largest_ok = max(fractions)
    for s in setups:
        runs = [(f, r) for (ss, f, _), r in zip(keys, results) if ss is s and not isinstance(r, Exception)]
        if not runs:
            continue
        for obs in runs[0][1].observables:
            by_f = {f: [r.observables[obs] for ff, r in runs if ff == f] for f in fractions}
            walls = {f: statistics.mean([r.wall for ff, r in runs if ff == f] or [float("nan")]) for f in fractions}
            spreads = [statistics.stdev(v) for v in by_f.values() if len(v) > 1]
            noise = math.sqrt(statistics.mean([v * v for v in spreads])) if spreads else float("nan")
            x = [f for f, v in by_f.items() for _ in v]
            y = [u for v in by_f.values() for u in v]
            _, b, se = line_fit(x, y)
            print(f"{s.id:13s} {obs:20s} noise {noise:.4g}")
            for f in fractions:
                v = by_f[f]
                if not v:
                    continue
                shift = b * (f - fractions[0]) / noise if noise > 0 else float("nan")
                shift_se = se * (f - fractions[0]) / noise if noise > 0 else float("nan")
                flags = sorted({fl for ff, r in runs if ff == f for fl in r.flags})
                ok = abs(shift) < QUARTER or f == fractions[0] or noise == 0
                if not ok:
                    largest_ok = min(largest_ok, max([g for g in fractions if g < f], default=fractions[0]))
                print(f"    {f:5.3f} T_R: {statistics.mean(v):10.4g} +- {statistics.stdev(v) if len(v) > 1 else 0:.3g}"
                      f" [{walls[f]:.0f} s]  shift {shift:+.2f} +- {shift_se:.2f} noise{'' if ok else '  > a quarter'}"
                      + (f"  {', '.join(flags)}" if flags else ""))
    print(f"\nlargest step whose shift stays under {QUARTER} of the noise for every observable: "
          f"{largest_ok:g} of the Rayleigh time")


if __name__ == "__main__":
    main()
