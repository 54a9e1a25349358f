#!/usr/bin/env python3
"""Figures of a LIGGGHTS tutorial run by both codes, side by side (bench/tutorials_side_by_side.sh).

  tutorials_compare.py chute_wear|conveyor DEMDESIGN_RUN_FOLDER LIGGGHTS_THERMO_LOG T0 T1
  tutorials_compare.py moving_mesh DEMDESIGN_RUN_FOLDERS LIGGGHTS_THERMO_LOGS   (comma-separated, one per seed)

conveyor: the mass on the belt, the belt's power on the material (LIGGGHTS: -F . v_belt from the
belt's mesh/surface/stress force), the force on the belt, and the mass-weighted velocity of the
material in the box it is thrown through (x -0.3 to -0.1 m); LIGGGHTS thermo rows of
bench/liggghts/conveyor.in (step atoms mass Fx Fy Fz belt_mass box_mass box_mvx box_mvz).

moving_mesh: see moving_mesh_figures; demdesign: box sensors `bed` (its offset across z is the mean
height) and `lifted`, mesh `bucket`; LIGGGHTS: the thermo rows of bench/liggghts/moving_mesh.in.

chute_wear: averages over [T0, T1] s: particles and their mass in the domain, the mass flow out of the domain
(slope of the mass that left), the particles' force on the chute by component, and the
mass-weighted velocity of the particles in the box after the chute's lip. demdesign: scalars.csv
(outlet `exit` with region: domain, mesh `chute`, box sensor `falling`); LIGGGHTS: the thermo
rows of bench/liggghts/chute_wear.in (step atoms mass inserted_mass Fx Fy Fz box_mass box_mvx
box_mvz), time = step x 1e-5 s. Prints a table and one CSV row per figure.
"""
import csv
import sys


def slope(t, y):
    n = len(t)
    mt, my = sum(t) / n, sum(y) / n
    sxx = sum((a - mt) ** 2 for a in t)
    return sum((a - mt) * (b - my) for a, b in zip(t, y)) / sxx if sxx > 0 else float("nan")


def mean(v):
    return sum(v) / len(v) if v else float("nan")


def batches(t, f, n=10):
    """f over n consecutive batches of the rows (t, indices) -> the standard error of the whole
    figure from the spread of its batch values (correlated rows do not shrink it)."""
    m = len(t)
    values = [f(list(range(m * b // n, m * (b + 1) // n))) for b in range(n)]
    values = [v for v in values if v == v]
    if len(values) < 2:
        return float("nan")
    mu = sum(values) / len(values)
    return (sum((v - mu) ** 2 for v in values) / (len(values) - 1) / len(values)) ** 0.5


def figure(t, f):
    """(value over all rows, standard error from batches)"""
    return f(list(range(len(t)))), batches(t, f)


def demdesign_figures(folder, t0, t1):
    rows = [r for r in csv.DictReader(open(folder + "/scalars.csv")) if t0 <= float(r["time_s"]) <= t1]
    t = [float(r["time_s"]) for r in rows]
    col = lambda name: [float(r[name]) for r in rows]
    held = [i - o - l for i, o, l in zip(col("inserted_mass_kg"), col("outlet_exit_kg"), col("lost_mass_kg"))]
    box = col("sensor_falling_mass_kg")
    return figures(t, col("particles"), held, col("outlet_exit_kg"), col("mesh_chute_fx_N"), col("mesh_chute_fy_N"),
                   col("mesh_chute_fz_N"), box, [m * v for m, v in zip(box, col("sensor_falling_vx_m_s"))],
                   [m * v for m, v in zip(box, col("sensor_falling_vz_m_s"))])


def figures(t, count, held, out, fx, fy, fz, box, box_mvx, box_mvz):
    """Each figure with its standard error; out is the cumulative mass that left."""
    avg = lambda v: (lambda rows: mean([v[i] for i in rows]))
    ratio = lambda a, b: (lambda rows: sum(a[i] for i in rows) / sum(b[i] for i in rows) if sum(b[i] for i in rows) > 0 else float("nan"))
    rate = lambda rows: slope([t[i] for i in rows], [out[i] for i in rows])
    return {
        "particles in the domain": figure(t, avg(count)),
        "mass in the domain [kg]": figure(t, avg(held)),
        "mass flow out of the domain [kg/s]": figure(t, rate),
        "force on the chute Fx [N]": figure(t, avg(fx)),
        "force on the chute Fy [N]": figure(t, avg(fy)),
        "force on the chute Fz [N]": figure(t, avg(fz)),
        "falling stream vx [m/s]": figure(t, ratio(box_mvx, box)),
        "falling stream vz [m/s]": figure(t, ratio(box_mvz, box)),
    }


def conveyor_demdesign(folder, t0, t1):
    rows = [r for r in csv.DictReader(open(folder + "/scalars.csv")) if t0 <= float(r["time_s"]) <= t1]
    t = [float(r["time_s"]) for r in rows]
    col = lambda name: [float(r[name]) for r in rows]
    box = col("sensor_thrown_mass_kg")
    return conveyor_figures(t, col("sensor_on_belt_mass_kg"), col("mesh_belt_power_W"), col("mesh_belt_fx_N"), col("mesh_belt_fz_N"),
                            box, [m * v for m, v in zip(box, col("sensor_thrown_vx_m_s"))], [m * v for m, v in zip(box, col("sensor_thrown_vz_m_s"))])


def conveyor_liggghts(log, t0, t1, dt=1e-5):
    rows = thermo_rows(log, t0, t1, dt)
    t = [r[0] * dt for r in rows]
    c = lambda k: [r[k] for r in rows]
    # The belt's power on the material: -F . v_belt with v_belt = (-4.5, 0, 0).
    return conveyor_figures(t, c(6), [4.5 * r[3] for r in rows], c(3), c(5), c(7), c(8), c(9))


def conveyor_figures(t, on_belt, power, fx, fz, box, box_mvx, box_mvz):
    avg = lambda v: (lambda rows: mean([v[i] for i in rows]))
    ratio = lambda a, b: (lambda rows: sum(a[i] for i in rows) / sum(b[i] for i in rows) if sum(b[i] for i in rows) > 0 else float("nan"))
    return {
        "mass on the belt [kg]": figure(t, avg(on_belt)),
        "belt power on the material [W]": figure(t, avg(power)),
        "force on the belt Fx [N]": figure(t, avg(fx)),
        "force on the belt Fz [N]": figure(t, avg(fz)),
        "thrown material vx [m/s]": figure(t, ratio(box_mvx, box)),
        "thrown material vz [m/s]": figure(t, ratio(box_mvz, box)),
    }


def thermo_rows(log, t0, t1, dt, columns=10):
    """The thermo rows of `columns` numbers with their step in [t0, t1] s, in step order. A step
    printed twice, at the end of one run and at the set-up of the next, counts once: the first.
    The set-up row's mesh/surface/stress force is about twice the step's (movingMeshGran, at the
    switch to the turn: 2193 N against 1121 N a row before and -1163 N a row after)."""
    rows = {}
    for line in open(log):
        f = line.split()
        if len(f) == columns and f[0].isdigit() and t0 <= int(f[0]) * dt <= t1:
            rows.setdefault(int(f[0]), [float(x) for x in f])
    return [rows[k] for k in sorted(rows)]


def liggghts_figures(log, t0, t1, dt=1e-5):
    rows = thermo_rows(log, t0, t1, dt)
    t = [r[0] * dt for r in rows]
    c = lambda k: [r[k] for r in rows]
    return figures(t, c(1), c(2), [r[3] - r[2] for r in rows], c(4), c(5), c(6), c(7), c(8), c(9))


def moving_mesh_figures(t, bed_z, lifted, fx, fz):
    """One run of movingMeshGran: the bed's mean height before the bucket moves (1.4-1.5 s), the
    bucket's mean force while it digs in (1.5-2.25 s) and while it turns (2.25-3.5 s), and the mass
    it lifts clear of the bed (above z = -0.1 m): mean over 2.5-3.5 s and peak while it turns."""
    def over(v, a, b):
        return mean([x for ti, x in zip(t, v) if a - 1e-9 <= ti <= b + 1e-9])
    return {
        "bed mean height at 1.4-1.5 s [m]": over(bed_z, 1.4, 1.5),
        "bucket Fx while digging [N]": over(fx, 1.5, 2.25),
        "bucket Fz while digging [N]": over(fz, 1.5, 2.25),
        "bucket Fx while turning [N]": over(fx, 2.25, 3.5),
        "bucket Fz while turning [N]": over(fz, 2.25, 3.5),
        "mass lifted (mean 2.5-3.5 s) [kg]": over(lifted, 2.5, 3.5),
        "mass lifted (peak after 2.25 s) [kg]": max(x for ti, x in zip(t, lifted) if ti >= 2.25),
    }


def moving_mesh_demdesign(folder):
    rows = list(csv.DictReader(open(folder + "/scalars.csv")))
    col = lambda name: [float(r[name]) for r in rows]
    return moving_mesh_figures(col("time_s"), col("sensor_bed_offset_m"), col("sensor_lifted_mass_kg"), col("mesh_bucket_fx_N"),
                               col("mesh_bucket_fz_N"))


def moving_mesh_liggghts(log, dt=5e-5):
    """Thermo rows of bench/liggghts/moving_mesh.in: step atoms mass sum(m z) lifted_mass
    lifted_sum(m z) Fx Fy Fz."""
    rows = thermo_rows(log, 0.0, float("inf"), dt, columns=9)
    t = [r[0] * dt for r in rows]
    return moving_mesh_figures(t, [r[3] / r[2] if r[2] > 0 else float("nan") for r in rows], [r[4] for r in rows], [r[6] for r in rows],
                               [r[8] for r in rows])


def over_replicas(runs):
    """{figure: (mean over the runs, its standard error)} from one dict per run."""
    out = {}
    for k in runs[0]:
        v = [r[k] for r in runs]
        mu = mean(v)
        out[k] = (mu, (sum((x - mu) ** 2 for x in v) / (len(v) - 1) / len(v)) ** 0.5 if len(v) > 1 else float("nan"))
    return out


def main():
    case, folder, log = sys.argv[1], sys.argv[2], sys.argv[3]
    if case == "moving_mesh":
        # Comma-separated run folders and logs, one per seed: a transient run, so the figures' noise
        # is their spread over independent fills, not over batches of one run.
        d = over_replicas([moving_mesh_demdesign(f) for f in folder.split(",")])
        g = over_replicas([moving_mesh_liggghts(f) for f in log.split(",")])
        print(f"{case}: means over {len(folder.split(','))} and {len(log.split(','))} runs with different fills")
    else:
        t0, t1 = float(sys.argv[4]), float(sys.argv[5])
        if case == "conveyor":
            d, g = conveyor_demdesign(folder, t0, t1), conveyor_liggghts(log, t0, t1)
        else:
            d, g = demdesign_figures(folder, t0, t1), liggghts_figures(log, t0, t1)
        print(f"{case}: averages over {t0:g} to {t1:g} s")
    print(f"  {'figure':36s} {'demdesign':>20s} {'LIGGGHTS':>20s} {'difference':>11s} {'in std errors':>13s}")
    for k in d:
        (a, sa), (b, sb) = d[k], g[k]
        diff = (a - b) / abs(b) * 100 if b else float("nan")
        sigmas = (a - b) / (sa * sa + sb * sb) ** 0.5 if sa == sa and sb == sb and sa + sb > 0 else float("nan")
        print(f"  {k:36s} {a:11.5g} +- {sa:<6.2g} {b:11.5g} +- {sb:<6.2g} {diff:+10.1f} % {sigmas:+12.1f}")
    for k in d:
        print(f"csv,{case},{k},{d[k][0]:.6g},{d[k][1]:.3g},{g[k][0]:.6g},{g[k][1]:.3g}")


if __name__ == "__main__":
    main()
