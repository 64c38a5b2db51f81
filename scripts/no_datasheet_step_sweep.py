#!/usr/bin/env python3
"""Bias steps of a unit with neither datasheet nor unit type (the a-priori model is its Allan fit).

With `--unit-type INS-2000` the file names that type instead: a unit of
another class labelled with it.

Each run is the independent simulator's (tests/benchsim) unit of `--preset`
with a bias step of 5 drift σ: run i is a gyro step when i is even, an
accelerometer step when odd; its axis, sign, onset (30–80 % of the run),
profile (static, positions, turns, mixed) and rate (10, 50, 100 Hz) come
from the run's own seeded generator (seed 5000 + i). Per run, from
`insdiag analyze --json`: the verdict and the first candidate significant
at family-wise 1 %. Per sensor: the runs whose first significant candidate
is the right step, those with its onset within 60 s, and the FAULTY ones;
a first candidate that names the right step as a look-alike it cannot be
told apart from (on a still, level table a gyro step about x is an
accelerometer ramp on y) is counted apart.

Usage:
  scripts/no_datasheet_step_sweep.py [--preset mems] [--runs 16] [--jobs 2] [--unit-type none]
INSDIAG_CLI names the CLI (default build/clients/insdiag). The figures in
docs/FAULT_SCENARIOS.md come from `--runs 16`.
"""
import argparse
import json
import math
import os
import random
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

import fault_matrix
import unit_classes  # noqa: E402 (fault_matrix puts the simulator's directory on the path)
from fault_matrix import BENCHSIM, CLI, PYTHON

DURATION_S = 1800.0


def simulate_run(preset, unit_type, i, path):
    """Writes the sweep's run i to `path`; returns its step (the term it is,
    the fault's spec, the profile, rate and onset)."""
    rng = random.Random(5000 + i)
    sensor = ("gyro", "acc")[i % 2]
    axis = rng.choice("xyz")
    sign = rng.choice((-1, 1))
    profile = rng.choice(("static", "positions", "turns", "mixed"))
    rate_hz = rng.choice((10, 50, 100))
    onset_s = round(rng.uniform(0.3, 0.8) * DURATION_S, 2)
    sigma = unit_classes.PRESETS[preset]()[f"{sensor}_bias_gm.{axis}.sigma"]
    spec = f"{sensor}_bias_step.{axis}={sign * 5.0 * sigma}@{onset_s}"
    subprocess.run([PYTHON, BENCHSIM, "--out", path, "--preset", preset, "--profile", profile,
                    "--rate-hz", str(rate_hz), "--duration", str(DURATION_S), "--seed", str(5000 + i),
                    "--datasheet", "no", "--unit-type", unit_type, "--fault", spec], check=True, capture_output=True)
    return {"expected": f"{sensor}_bias_step.{axis}", "spec": spec, "profile": profile, "rate_hz": rate_hz,
            "onset_s": onset_s}


def run_one(preset, unit_type, i):
    with tempfile.TemporaryDirectory() as work:
        path = os.path.join(work, "run.csv")
        step = simulate_run(preset, unit_type, i, path)
        done = subprocess.run([CLI, "analyze", path, "--json"], capture_output=True, text=True, check=True)
    report = json.loads(done.stdout)
    significant = [c for c in report["effectCandidates"] if fault_matrix.significant(c)]
    first = significant[0] if significant else None
    expected = step["expected"]
    right = first is not None and first["name"] == expected
    return {"run": i, "fault": step["spec"], "profile": step["profile"], "rate_hz": step["rate_hz"],
            "verdict": report["verdict"], "first": first["name"] if first else None,
            "names_it_as_look_alike": first is not None and expected in first.get("correlatedWith", []),
            "significant": len(significant),
            "onset_error_s": abs(first["onsetS"] - step["onset_s"]) if right else None}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", default="mems", choices=sorted(unit_classes.PRESETS))
    parser.add_argument("--runs", type=int, default=16)
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    parser.add_argument("--unit-type", default="none", help="the unit type the file names (none: no type)")
    args = parser.parse_args()
    with ThreadPoolExecutor(args.jobs) as pool:
        results = list(pool.map(lambda i: run_one(args.preset, args.unit_type, i), range(args.runs)))
    for r in results:
        print(json.dumps(r))
    for sensor in ("gyro", "acc"):
        rs = [r for r in results if r["fault"].startswith(sensor)]
        right = [r for r in rs if r["onset_error_s"] is not None]
        print(f"{args.preset} {sensor} steps, {len(rs)} runs: right step first {len(right)}; onset within 60 s "
              f"{sum(1 for r in right if r['onset_error_s'] < 60.0)}; a look-alike of it first "
              f"{sum(1 for r in rs if r['names_it_as_look_alike'])}; FAULTY "
              f"{sum(1 for r in rs if r['verdict'] == 'FAULTY')}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
