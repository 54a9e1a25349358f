"""Shared pieces of the lab benchmarks (bench/lab_time_step.py, bench/lab_side_by_side.py): the
standard set-ups of bench/lab/setups.txt, one virtual test run by demdesign and read back, and
jobs run a few at a time, each on one core.

Python 3 standard library only.
"""

import concurrent.futures
import os
import re
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))


class Setup:
    """One standard set-up: id, test and its keys (numbers as floats, words as strings)."""

    def __init__(self, ident, test, values):
        self.id, self.test, self.values = ident, test, values

    def args(self):
        return [a for k, v in self.values.items() for a in ("--set", f"{k}={v}")]


def read_setups(path=os.path.join(HERE, "setups.txt")):
    setups = []
    with open(path) as f:
        for line in f:
            if not line.strip() or line.startswith("#"):
                continue
            ident, test, *pairs = line.split()
            values = {}
            for p in pairs:
                k, v = p.split("=", 1)
                try:
                    values[k] = float(v)
                except ValueError:
                    values[k] = v
            setups.append(Setup(ident, test, values))
    return setups


def select(setups, wanted):
    """The set-ups named in the comma-separated `wanted` ("all": every one), in file order."""
    if wanted in (None, "", "all"):
        return setups
    names = wanted.split(",")
    unknown = [n for n in names if n not in [s.id for s in setups]]
    if unknown:
        raise SystemExit(f"unknown set-up {', '.join(unknown)}; valid: {', '.join(s.id for s in setups)}")
    return [s for s in setups if s.id in names]


def binary():
    build = os.environ.get("BUILD", os.path.join(ROOT, "build"))
    exe = os.path.join(build, "app", "demdesign")
    if not os.access(exe, os.X_OK):
        raise SystemExit(f"no {exe}: build first (cmake --build build), or set BUILD")
    return exe


class Result:
    """What `demdesign test` printed: observables, outcome flags, time step, wall and simulated time."""

    def __init__(self):
        self.observables, self.flags = {}, []
        self.time_step = self.wall = self.simulated = float("nan")
        self.particles = 0
        self.text = ""


def run_demdesign(material, setup, seed=1, rayleigh_fraction=None, core=None, extra=()):
    """Runs one virtual test on one thread (pinned to `core` when given) and reads its output."""
    with tempfile.TemporaryDirectory(prefix="labbench_") as work:
        cmd = [binary(), "test", material, "--test", setup.test, *setup.args(), "--seed", str(seed), "--threads", "1",
               "--png", os.path.join(work, "final.png"), *extra]
        if rayleigh_fraction:
            cmd += ["--rayleigh-fraction", str(rayleigh_fraction)]
        if core is not None:
            cmd = ["taskset", "-c", str(core)] + cmd
        env = dict(os.environ, OMP_NUM_THREADS="1")
        done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    r = Result()
    r.text = done.stdout + done.stderr
    if done.returncode != 0:
        raise RuntimeError(f"{setup.id}: demdesign test failed ({done.returncode}):\n{r.text[-2000:]}")
    head = re.search(r"\((\d+) particles, ([0-9.e+-]+) s simulated, ([0-9.e+-]+) s wall\)", r.text)
    if head:
        r.particles, r.simulated, r.wall = int(head.group(1)), float(head.group(2)), float(head.group(3))
    for m in re.finditer(r"^  ([a-z_]+) = ([0-9.e+-]+)", r.text, re.M):
        r.observables[m.group(1)] = float(m.group(2))
    for m in re.finditer(r"^  outcome: (.*)$", r.text, re.M):
        r.flags += m.group(1).split(", ")
    step = re.search(r"note: time step ([0-9.e+-]+) s", r.text)
    if step:
        r.time_step = float(step.group(1))
    return r


def run_jobs(jobs, workers=2, on_done=None):
    """Runs callables `workers` at a time (each pinned to its own core by the caller's `core`
    argument: job(core)); returns their results in job order. on_done(k, result) as each ends."""
    results = [None] * len(jobs)
    free = list(range(workers))
    with concurrent.futures.ThreadPoolExecutor(max_workers=workers) as pool:
        pending = {}
        queue = list(enumerate(jobs))
        while queue or pending:
            while queue and free:
                k, job = queue.pop(0)
                core = free.pop(0)
                pending[pool.submit(job, core)] = (k, core)
            finished, _ = concurrent.futures.wait(pending, return_when=concurrent.futures.FIRST_COMPLETED)
            for fut in finished:
                k, core = pending.pop(fut)
                free.append(core)
                try:
                    results[k] = fut.result()
                except Exception as err:  # a failed job is reported, the others go on
                    results[k] = err
                    print(f"job {k}: {err}", file=sys.stderr, flush=True)
                if on_done:
                    on_done(k, results[k])
    return results


def commit():
    try:
        return subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip() or "unknown"
    except OSError:
        return "unknown"


def machine():
    model = ""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{os.cpu_count()} cores, {model}"
