#!/usr/bin/env python3
"""The virtual lab tests in demdesign and in LIGGGHTS 3.8, side by side.

Each standard set-up of bench/lab/setups.txt (the benchmark laboratory file: drop, bulk density,
lifted cylinder, drum at 10 and 30 rpm, silo with 30 and 40 mm orifices) runs in demdesign
(`demdesign test`, one thread) and in LIGGGHTS (the inputs of calibration/liggghts/, through
make_measurements.py's runners, one process), the same particles and protocol, --packings
packings each, alternating the two codes on one core (nothing else should run). Printed per test:
wall time, time step and particle steps per second in both codes, the observable in both (mean
and scatter over the packings) with their difference in units of the combined noise, and the
ratio of the wall times. Rows go to bench/results/lab_side_by_side.csv.

    bench/lab_side_by_side.py [--pair plain|rolling] [--packings 2] [--tests all] [--core 0]

--pair plain: demdesign's bench/lab/beads_plain.yaml against LIGGGHTS' control material at E 1e7
Pa (the same contact law: observables must agree). --pair rolling: bench/lab/beads_rolling.yaml
(demdesign's epsd, mu_r 0.25) against LIGGGHTS' epsd2 at mu_r 0.25, similar laws that differ in
the rolling spring and damping (calibration/liggghts/README.md), so the observables are shown but
not expected to agree; the heap forms there, which the plain beads do not.
"""

import argparse
import datetime
import glob
import json
import math
import os
import re
import shutil
import statistics
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "lab"))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "calibration", "liggghts"))
import labbench  # noqa: E402
import make_measurements as mm  # noqa: E402

PAIRS = {
    "plain": ("beads_plain.yaml", {"rolling": "off", "rolling_friction": 0.0}),
    "rolling": ("beads_rolling.yaml", {"rolling": "epsd2", "rolling_friction": 0.25}),
}


def liggghts_material(pair, folder):
    """The LIGGGHTS material of a pair: calibration/liggghts/materials/control.json at E 1e7 Pa
    with the pair's rolling resistance."""
    with open(os.path.join(mm.HERE, "materials", "control.json")) as f:
        m = json.load(f)
    m["particles"]["youngs_modulus"] = 1.0e7
    extra = PAIRS[pair][1]
    m["contact"]["rolling"] = extra["rolling"]
    if extra["rolling_friction"]:
        m["particle_pairs"]["rolling_friction"] = m["wall_pairs"]["rolling_friction"] = extra["rolling_friction"]
    path = os.path.join(folder, f"{pair}.json")
    with open(path, "w") as f:
        json.dump(m, f)
    return mm.Material(path)


def liggghts_steps(folder):
    """Particle steps and loop seconds of every `run` of the LIGGGHTS logs in folder."""
    steps, seconds = 0.0, 0.0
    for log in glob.glob(os.path.join(folder, "*.log")):
        for m in re.finditer(r"Loop time of ([0-9.e+-]+) on \d+ procs for (\d+) steps with (\d+) atoms", open(log).read()):
            seconds += float(m.group(1))
            steps += float(m.group(2)) * float(m.group(3))
    return steps, seconds


def liggghts_step_size(mat, test):
    """The step calibration/liggghts/material.in sets: 20 % of the Rayleigh time of the smallest
    class (2 % for the drop test)."""
    fraction = 0.02 if test == "drop_rebound" else 0.2
    d = min(mat.sizes)
    return fraction * math.pi * 0.5 * d * math.sqrt(mat.density * 2 * (1 + mat.poisson) / mat.youngs) / (0.1631 * mat.poisson + 0.8766)


def run_liggghts(mat, setup, seed, core):
    folder = tempfile.mkdtemp(prefix="lab_liggghts_")
    try:
        # The silo's wall as LIGGGHTS' exact zcylinder primitive, as demdesign's exact walls: the
        # best each code offers (a triangulated wall costs LIGGGHTS twice the time).
        args = argparse.Namespace(seed=seed, liggghts="liggghts", nice=None, keep=False, primitive_walls=True)
        # LIGGGHTS inherits this process's affinity: pinned to the core for its run.
        os.sched_setaffinity(0, {core})
        try:
            obs, notes, elapsed, particles = mm.TESTS[setup.test](args, mat, {k: v for k, v in setup.values.items()}, folder)
        finally:
            os.sched_setaffinity(0, set(range(os.cpu_count())))
        r = labbench.Result()
        r.observables = obs
        r.flags = [n[len("flag "):] for n in notes if n.startswith("flag ")]
        r.wall, r.particles = elapsed, particles
        r.psteps, _ = liggghts_steps(folder)
        r.time_step = liggghts_step_size(mat, setup.test)
        return r
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pair", choices=sorted(PAIRS), default="plain")
    ap.add_argument("--packings", type=int, default=2)
    ap.add_argument("--tests", default="all", help="comma-separated set-up ids of bench/lab/setups.txt")
    ap.add_argument("--core", type=int, default=0, help="the core both codes run on, one after the other")
    ap.add_argument("--csv", default=os.path.join(labbench.ROOT, "bench", "results", "lab_side_by_side.csv"))
    args = ap.parse_args()
    if shutil.which("liggghts") is None:
        raise SystemExit("'liggghts' not found: apt-get install -y liggghts openmpi-bin")
    setups = labbench.select(labbench.read_setups(), args.tests)
    work = tempfile.mkdtemp(prefix="lab_side_by_side_")
    mat = liggghts_material(args.pair, work)
    dem_material = os.path.join(labbench.HERE, PAIRS[args.pair][0])
    commit, today = labbench.commit(), datetime.date.today().isoformat()
    print(f"lab tests side by side, pair {args.pair}, {args.packings} packings, alternating on core {args.core}; "
          f"{labbench.machine()}; commit {commit}; {mm.liggghts_version('liggghts', work)}", flush=True)
    new = not os.path.exists(args.csv)
    rows = []
    with open(args.csv, "a") as csv:
        if new:
            csv.write("date,commit,pair,id,code,packing,wall_s,time_step_s,particle_steps_per_s,observable,value,flags\n")
        for s in setups:
            packings = 1 if s.test == "drop_rebound" else args.packings
            for k in range(packings):
                seed_dem, seed_lig = k + 1, mm.placement_seeds(15485863, packings)[k]
                for code in ("demdesign", "liggghts"):
                    if code == "demdesign":
                        r = labbench.run_demdesign(dem_material, s, seed_dem, core=args.core)
                        steps = r.simulated / r.time_step if r.time_step > 0 else 0
                        r.psteps = steps * r.particles
                    else:
                        r = run_liggghts(mat, s, seed_lig, args.core)
                    rate = r.psteps / r.wall if r.wall > 0 else float("nan")
                    rows.append((s, code, k, r))
                    for obs, v in r.observables.items():
                        csv.write(f"{today},{commit},{args.pair},{s.id},{code},{k + 1},{r.wall:.2f},{r.time_step:.4g},{rate:.4g},{obs},{v:.6g},"
                                  f"{'+'.join(r.flags)}\n")
                    csv.flush()
                    print(f"  {s.id} {code:9s} packing {k + 1}: {r.wall:7.1f} s, step {r.time_step:.3g} s, {rate:.3g} p-steps/s; "
                          + ", ".join(f"{o} {v:.4g}" for o, v in r.observables.items()) + (f" [{', '.join(r.flags)}]" if r.flags else ""),
                          flush=True)
    shutil.rmtree(work, ignore_errors=True)

    print(f"\n{'test':13s} {'wall s d | L':>17s} {'step s d | L':>19s} {'p-steps/s d | L':>19s} {'observable':18s} "
          f"{'demdesign':>15s} {'LIGGGHTS':>15s} {'diff/noise':>10s} {'ratio':>6s}")
    for s in setups:
        mine = [r for ss, c, _, r in rows if ss is s and c == "demdesign"]
        theirs = [r for ss, c, _, r in rows if ss is s and c == "liggghts"]
        if not mine or not theirs:
            continue
        wd, wl = statistics.median(r.wall for r in mine), statistics.median(r.wall for r in theirs)
        rd = statistics.median(r.psteps / r.wall for r in mine)
        rl = statistics.median(r.psteps / r.wall for r in theirs)
        for obs in mine[0].observables:
            a = [r.observables[obs] for r in mine]
            b = [r.observables.get(obs, float("nan")) for r in theirs]
            sa = statistics.stdev(a) if len(a) > 1 else 0.0
            sb = statistics.stdev(b) if len(b) > 1 else 0.0
            noise = math.sqrt((sa * sa + sb * sb) / 2) if (sa or sb) else 0.0
            diff = (statistics.mean(a) - statistics.mean(b)) / math.sqrt(noise * noise * (1 / len(a) + 1 / len(b))) if noise else float("nan")
            flags_d = sorted({f for r in mine for f in r.flags})
            flags_l = sorted({f for r in theirs for f in r.flags})
            print(f"{s.id:13s} {wd:7.1f} | {wl:7.1f} {mine[0].time_step:9.3g} | {theirs[0].time_step:7.3g} {rd:9.3g} | {rl:7.3g} {obs:18s} "
                  f"{statistics.mean(a):8.4g} +- {sa:<5.2g}{statistics.mean(b):8.4g} +- {sb:<5.2g}{diff:+8.2f}   {wl / wd:6.2f}"
                  + (f"  outcomes {'+'.join(flags_d) or '-'} | {'+'.join(flags_l) or '-'}" if flags_d or flags_l else ""))
    print("(medians of the wall times; diff/noise: difference of the means over its standard error from the packings' scatter; "
          "ratio: LIGGGHTS wall time / demdesign's)")


if __name__ == "__main__":
    main()
