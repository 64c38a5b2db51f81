#!/usr/bin/env python3
"""Healthy units with neither datasheet nor unit type: the Allan fit's a-priori model.

Each run is a healthy unit of one of the independent simulator's classes
(tests/benchsim, `--preset`), with no datasheet and no unit type, so the
analysis starts from the Allan fit of the run's static segments. With
`--unit-type INS-2000` the file names that type instead: a unit of another
class labelled with it, whose nominal model the analysis then weighs
against the run's Allan deviation. The profile
and rate come from the seed (`static` or `positions`; 50 or 100 Hz). Per run,
from `insdiag analyze --json`: the verdict; the candidates significant at
family-wise 1 %; and the identified drift parameters whose family-wise 1 %
interval (Bonferroni over those compared) excludes the truth — an estimate
that is wrong with a standard error that says it is not.

Usage:
  scripts/allan_prior_probe.py [--preset mems] [--runs N] [--duration S] [--jobs J] [--unit-type none]
The figures in docs/FAULT_SCENARIOS.md come from
  scripts/allan_prior_probe.py --preset mems --runs 12
"""
import argparse
import importlib.util
import json
import math
import os
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location("fault_matrix", os.path.join(HERE, "fault_matrix.py"))
matrix = importlib.util.module_from_spec(spec)
spec.loader.exec_module(matrix)
BENCHSIM = os.path.join(matrix.ROOT, "tests", "benchsim", "benchsim.py")


def wrong_but_sure(report, truth):
    """(|z|, name) of identified drift parameters whose family-wise 1 % interval excludes the truth."""
    compared = []
    for p in report.get("identified", []):
        name, value, se = p["name"], p.get("value", 0.0), p.get("stdError", 0.0)
        if ".sigma" not in name and ".tau" not in name:
            continue
        if name not in truth or not (se and se > 0 and value > 0):
            continue
        compared.append((abs(math.log(value / truth[name])) / (se / value), name))
    if not compared:
        return []
    threshold = -matrix.normal_quantile(0.005 / len(compared))
    return sorted((c for c in compared if c[0] > threshold), reverse=True)


def run_one(args):
    preset, seed, duration_s, unit_type = args
    profile = ("static", "positions")[seed % 2]
    rate_hz = (50, 100)[(seed // 2) % 2]
    with tempfile.TemporaryDirectory() as work:
        path = os.path.join(work, "run.csv")
        subprocess.run([sys.executable, BENCHSIM, "--out", path, "--preset", preset, "--profile", profile,
                        "--rate-hz", str(rate_hz), "--duration", str(duration_s), "--seed", str(seed),
                        "--datasheet", "no", "--unit-type", unit_type, "--serial", f"PROBE-{seed}"],
                       check=True, capture_output=True)
        with open(path + ".truth.json") as f:
            truth = json.load(f)["parameters"]
        done = subprocess.run([matrix.CLI, "analyze", path, "--json"], capture_output=True, text=True)
        if done.returncode != 0:
            return {"seed": seed, "error": done.stderr.strip()[:300]}
        report = json.loads(done.stdout)
        report = report.get("report", report)
    return {"seed": seed, "profile": profile, "rate_hz": rate_hz, "verdict": report.get("verdict"),
            "significant": [c["name"] for c in report.get("effectCandidates", []) if matrix.significant(c)],
            "wrong_but_sure": [f"{name} ({z:.1f} SE)" for z, name in wrong_but_sure(report, truth)]}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--preset", default="mems")
    parser.add_argument("--runs", type=int, default=12)
    parser.add_argument("--duration", type=float, default=1800.0)
    parser.add_argument("--jobs", type=int, default=1)
    parser.add_argument("--first-seed", type=int, default=21)
    parser.add_argument("--unit-type", default="none", help="the unit type the file names (none: no type)")
    options = parser.parse_args()
    seeds = range(options.first_seed, options.first_seed + options.runs)
    with ThreadPoolExecutor(max_workers=options.jobs) as pool:
        results = list(pool.map(run_one, [(options.preset, s, options.duration, options.unit_type) for s in seeds]))
    for r in results:
        print(json.dumps(r))
    good = sum(1 for r in results if r.get("verdict") == "GOOD")
    quiet = sum(1 for r in results if not r.get("significant") and "error" not in r)
    honest = sum(1 for r in results if not r.get("wrong_but_sure") and "error" not in r)
    n = len(results)
    print(f"{options.preset}, {n} runs: GOOD {good}/{n}; nothing significant {quiet}/{n}; "
          f"no drift estimate excluding the truth at family-wise 1 % {honest}/{n}")


if __name__ == "__main__":
    main()
