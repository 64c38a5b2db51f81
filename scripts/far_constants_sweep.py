#!/usr/bin/env python3
"""MEMS-class units far from any a-priori model: large turn-on biases.

Each run is a MEMS-class unit (drift 10 °/h, τ 100 s, ARW 0.3 °/√h; accelerometer
drift 500 µg, VRW 100 µg/√Hz) with turn-on biases of 0.1–1 °/s on every gyro
and 10–20 mg on every accelerometer (log-uniform magnitudes, random signs),
one hour, no datasheet, on both simulators: the project's (`insdiag simulate`)
and the independent one (tests/benchsim). The profile (static or multi-position)
and rate (50 or 100 Hz) come from the seed. The runs name no unit type: the
a-priori model is the run's Allan fit.

Per run: the verdict; the significant candidates at family-wise 1 %; each
turn-on bias either removed before identification (reported as identified,
method STATIC, and then checked against the truth within 3 SE) or named by
the scan as a significant missing effect; and whether any other candidate
is significant.

Usage:
  scripts/far_constants_sweep.py [--runs N] [--simulators cpp,py] [--out results.json]
The figures in docs/IDENTIFICATION.md come from
  scripts/far_constants_sweep.py --runs 10
"""
import argparse
import importlib.util
import json
import math
import os
import random
import subprocess
import sys
import tempfile
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location("fault_matrix", os.path.join(HERE, "fault_matrix.py"))
matrix = importlib.util.module_from_spec(spec)
spec.loader.exec_module(matrix)

DEG = matrix.unit_classes.DEG
DURATION_S = 3600.0
# The independent simulator's `mems` preset, given to the project's simulator as parameters.
MEMS = matrix.unit_classes.PRESETS["mems"]()
PROFILES = {"cpp": ["static", "positions"], "py": ["static", "positions"]}


def draw(rng):
    biases = {}
    for a in "xyz":
        biases[f"gyro_turn_on_bias.{a}"] = rng.choice([-1, 1]) * math.exp(rng.uniform(math.log(0.1), math.log(1.0))) * DEG
        biases[f"acc_turn_on_bias.{a}"] = rng.choice([-1, 1]) * rng.uniform(10e-3, 20e-3) * 9.80665
    return biases


def simulate(simulator, biases, profile, rate_hz, seed, path):
    if simulator == "cpp":
        cmd = [matrix.CLI, "simulate", path, "--profile", profile, "--rate", f"{rate_hz:g}", "--seed", str(seed),
               "--no-datasheet"]
        for name, value in MEMS.items():
            cmd += ["--param", f"{name}={value:.6g}"]
        for name, value in biases.items():
            cmd += ["--effect", f"{name}={value:.6g}"]
    else:
        cmd = [matrix.PYTHON, matrix.BENCHSIM, "--out", path, "--preset", "mems", "--profile", profile, "--rate-hz",
               f"{rate_hz:g}", "--duration", f"{DURATION_S:g}", "--seed", str(seed), "--datasheet", "no",
               "--unit-type", "INS-2000"]
        for name, value in biases.items():
            cmd += ["--fault", f"{name}={value:.6g}"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    if simulator == "cpp":
        matrix.truncate(path, DURATION_S)


def set_unit_type(path, unit_type):
    """The runs name INS-2000; `none` removes the line (unknown unit type)."""
    with open(path) as f:
        lines = f.readlines()
    lines = [l for l in lines if not l.startswith("# unit_type:")]
    if unit_type != "none":
        lines.insert(1, f"# unit_type: {unit_type}\n")
    with open(path, "w") as f:
        f.writelines(lines)


def run_one(args):
    simulator, index, seed = args
    rng = random.Random(seed)
    biases = draw(rng)
    profile = rng.choice(PROFILES[simulator])
    rate_hz = rng.choice([50.0, 100.0])
    unit_type = "none"
    with tempfile.TemporaryDirectory() as d:
        path = os.path.join(d, "run.csv")
        simulate(simulator, biases, profile, rate_hz, seed, path)
        set_unit_type(path, unit_type)
        done = subprocess.run([matrix.CLI, "analyze", path, "--json"], capture_output=True, text=True)
    if done.returncode != 0:
        return {"simulator": simulator, "seed": seed, "error": done.stderr[-500:]}
    report = json.loads(done.stdout)
    removed = {p["name"]: p for p in report.get("identified", []) if p.get("method") == "STATIC"}
    within = sum(1 for name, value in biases.items()
                 if name in removed and abs(removed[name]["value"] - value) <= 3.0 * removed[name].get("stdError", 0.0))
    significant = [c["name"] for c in report.get("effectCandidates", []) if matrix.significant(c)]
    named = [n for n in significant if n in biases and n not in removed]
    return {"simulator": simulator, "seed": seed, "profile": profile, "rate_hz": rate_hz, "unit_type": unit_type,
            "verdict": report.get("verdict"), "nis": report.get("nisMean"), "significant": significant,
            "removed": len(removed), "removed_within_3se": within, "named": len(named),
            "others_significant": [n for n in significant if "turn_on_bias" not in n]}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=10, help="runs per simulator")
    parser.add_argument("--simulators", default="cpp,py")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out")
    args = parser.parse_args()
    jobs = [(sim, i, 7000 + 100 * k + i) for k, sim in enumerate(args.simulators.split(",")) for i in range(args.runs)]
    with ThreadPoolExecutor(args.jobs) as pool:
        results = list(pool.map(run_one, jobs))
    if args.out:
        with open(args.out, "w") as f:
            json.dump(results, f, indent=1)
    print("| simulator | runs | biases removed | removed within 3 SE | named by the scan | runs with another significant candidate | FAULTY |")
    print("|---|---|---|---|---|---|---|")
    for sim in args.simulators.split(","):
        rows = [r for r in results if r["simulator"] == sim and "error" not in r]
        for e in (r for r in results if r["simulator"] == sim and "error" in r):
            print(f"  error (seed {e['seed']}): {e['error']}", file=sys.stderr)
        if rows:
            print(f"| {sim} | {len(rows)} | {sum(r['removed'] for r in rows)} of {6 * len(rows)} | "
                  f"{sum(r['removed_within_3se'] for r in rows)} | {sum(r['named'] for r in rows)} | "
                  f"{sum(bool(r['others_significant']) for r in rows)} | {sum(r['verdict'] == 'FAULTY' for r in rows)} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
