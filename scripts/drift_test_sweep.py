#!/usr/bin/env python3
"""Long drift tests over seeds: which drift changes the diagnosis names, on both simulators.

Each run is a drift test of several hours of an INS-2000 unit without a
datasheet, with one drift parameter of one sensor axis changed (or none),
simulated on the project's simulator (`cpp`: its `drift` profile) or on the
independent one (`py`: tests/benchsim, its `tilted`, `tilted-turns` and
`positions` profiles, written for long tests at oblique positions and
continuous turns). The run is analysed as the server does for a diagnosis
(`insdiag analyze --discover --json`), the report kept, and the report
diagnosed offline against the built-in failure modes
(`insdiag-diagnose-report`), so that a change to the diagnosis can be
measured again on the same reports (`--rediagnose`).

Scenarios (sensor, axis, rate and profile drawn from the seed):
  healthy      nothing changed. Right: the first module is `healthy`.
  sigma_x3     one of the six sensors' drift σ × 3. Right: that sensor axis's module first.
  sigma_x10    drift σ × 10.
  tau_x0.1     one gyro's drift τ × 0.1.
  tau_x10      one gyro's drift τ × 10, over eight hours.
  noise_x2     one sensor's white noise × 2 (gyro ARW or accelerometer VRW).

Usage:
  scripts/drift_test_sweep.py --scenarios healthy,sigma_x3 --runs 20 --out results.jsonl [--keep DIR]
  scripts/drift_test_sweep.py --rediagnose results.jsonl --out again.jsonl
  scripts/drift_test_sweep.py --table results.jsonl
The binaries are the build's, or $INSDIAG_CLI and $INSDIAG_DIAGNOSE_REPORT.
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

HERE = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location("fault_matrix", os.path.join(HERE, "fault_matrix.py"))
matrix = importlib.util.module_from_spec(spec)
spec.loader.exec_module(matrix)

DIAGNOSE_REPORT = os.environ.get("INSDIAG_DIAGNOSE_REPORT",
                                 os.path.join(matrix.ROOT, "build", "tools", "insdiag-diagnose-report"))
PROFILES = {"cpp": ["drift"], "py": ["tilted", "tilted-turns", "positions"]}
RATES_HZ = [10.0, 50.0]
SCENARIOS = {
    # name: (sensors, parameter field, factor, hours)
    "healthy": (None, None, 1.0, 4.0),
    "sigma_x3": (("gyro", "acc"), "sigma", 3.0, 4.0),
    "sigma_x10": (("gyro", "acc"), "sigma", 10.0, 4.0),
    "tau_x0.1": (("gyro",), "tau", 0.1, 4.0),
    "tau_x10": (("gyro",), "tau", 10.0, 8.0),
    "noise_x2": (("gyro", "acc"), "noise", 2.0, 4.0),
}


def parameter_name(sensor, field, axis):
    if field == "noise":
        return f"gyro_arw.{axis}" if sensor == "gyro" else f"acc_vrw.{axis}"
    return f"{sensor}_bias_gm.{axis}.{field}"


def make_run(simulator, scenario, index, path):
    """Simulates one run; returns what was hidden and how."""
    rng = random.Random(f"drift-test/{simulator}/{scenario}/{index}")
    sensors, field, factor, hours = SCENARIOS[scenario]
    seed = 7000 + index
    rate = RATES_HZ[index % len(RATES_HZ)]
    profile = PROFILES[simulator][index % len(PROFILES[simulator])]
    duration_s = hours * 3600.0
    hidden = dict(scenario=scenario, simulator=simulator, index=index, seed=seed, rate_hz=rate,
                  profile=profile, hours=hours, module="healthy")
    name = None
    if sensors:
        sensor, axis = rng.choice(sensors), rng.choice(matrix.AXES)
        name = parameter_name(sensor, field, axis)
        hidden.update(module=f"{sensor}.{axis}", parameter=name, factor=factor)
    if simulator == "cpp":
        cmd = [matrix.CLI, "simulate", path, "--profile", profile, "--rate", f"{rate:g}", "--seed", str(seed),
               "--no-datasheet"]
        if name:
            cmd += ["--param", f"{name}={matrix.NOMINAL[name] * factor:.6g}"]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        matrix.truncate(path, duration_s)
    else:
        cmd = [matrix.PYTHON, matrix.BENCHSIM, "--out", path, "--preset", "nav", "--profile", profile,
               "--rate-hz", f"{rate:g}", "--duration", f"{duration_s:g}", "--seed", str(seed), "--datasheet", "no",
               "--unit-type", "INS-2000"]
        if name:
            cmd += ["--fault", f"{name}*{factor:g}"]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
    return hidden


def diagnose(report_path):
    done = subprocess.run([DIAGNOSE_REPORT, report_path], capture_output=True, text=True)
    if done.returncode != 0:
        return dict(error=done.stderr.strip()[-300:])
    d = json.loads(done.stdout)
    ranked = [(c.get("module"), c.get("probability", 0.0), c.get("failureMode", "")) for c in d.get("candidates", [])]
    ranked.sort(key=lambda c: -c[1])
    return dict(ranked=ranked[:4], first=ranked[0][0] if ranked else None,
                evidence=[e for e in d.get("evidence", []) if "_gm." in e.get("name", "") or "rw" in e.get("name", "")])


def judge(hidden, diagnosis):
    out = dict(hidden)
    out.update(diagnosis)
    out["right"] = diagnosis.get("first") == hidden["module"]
    out["right_probability"] = next((p for m, p, _ in diagnosis.get("ranked", []) if m == hidden["module"]), 0.0)
    return out


def analyse(run_path, report_path):
    with open(report_path, "w") as out:
        done = subprocess.run([matrix.CLI, "analyze", run_path, "--discover", "--json", "--unit-type", "INS-2000"],
                              stdout=out, stderr=subprocess.PIPE, text=True)
    return None if done.returncode == 0 else done.stderr.strip()[-300:]


def sweep(args):
    keep = args.keep or tempfile.mkdtemp(prefix="drift-test-")
    os.makedirs(keep, exist_ok=True)
    with open(args.out, "a") as out:
        for index in range(args.first_index, args.first_index + args.runs):
            for scenario in args.scenarios.split(","):
                for simulator in args.simulators.split(","):
                    stem = os.path.join(keep, f"{scenario}-{simulator}-{index}")
                    hidden = make_run(simulator, scenario, index, stem + ".csv")
                    error = analyse(stem + ".csv", stem + ".json")
                    os.remove(stem + ".csv")
                    hidden["report"] = stem + ".json"
                    result = judge(hidden, dict(error=error) if error else diagnose(stem + ".json"))
                    out.write(json.dumps(result) + "\n")
                    out.flush()
                    print(f"{scenario:10s} {simulator} {index:3d} {hidden['module']:8s} -> {result.get('first')} "
                          f"{result['right_probability']:.2f}", flush=True)


def rediagnose(args):
    with open(args.rediagnose) as f, open(args.out, "w") as out:
        for line in f:
            r = json.loads(line)
            hidden = {k: v for k, v in r.items() if k not in ("ranked", "first", "evidence", "right",
                                                               "right_probability", "error")}
            out.write(json.dumps(judge(hidden, diagnose(r["report"]))) + "\n")


def wilson(k, n, z=1.96):
    if n == 0:
        return (0.0, 1.0)
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / (1 + z * z / n)
    return (max(0.0, centre - half), min(1.0, centre + half))


def table(path):
    rows = [json.loads(line) for line in open(path)]
    groups = {}
    for r in rows:
        groups.setdefault((r["scenario"], r["simulator"]), []).append(r)
    print("| scenario | simulator | right module first | 95 % interval | firsts when wrong |")
    print("|---|---|---|---|---|")
    for (scenario, simulator), rs in sorted(groups.items()):
        k = sum(1 for r in rs if r.get("right"))
        low, high = wilson(k, len(rs))
        wrong = {}
        for r in rs:
            if not r.get("right"):
                wrong[r.get("first") or "error"] = wrong.get(r.get("first") or "error", 0) + 1
        print(f"| {scenario} | {simulator} | {k} of {len(rs)} | {low:.2f}–{high:.2f} | "
              f"{', '.join(f'{m} {n}' for m, n in sorted(wrong.items())) or '—'} |")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenarios", default="healthy,sigma_x3")
    parser.add_argument("--simulators", default="cpp,py")
    parser.add_argument("--runs", type=int, default=20)
    parser.add_argument("--first-index", type=int, default=0)
    parser.add_argument("--keep", help="directory for the reports (default: a temporary one)")
    parser.add_argument("--out", help="JSON lines, one a run (appended)")
    parser.add_argument("--rediagnose", help="diagnose a sweep's kept reports again")
    parser.add_argument("--table", help="summarise a sweep's results")
    args = parser.parse_args()
    if args.table:
        table(args.table)
    elif args.rediagnose:
        rediagnose(args)
    else:
        if not args.out:
            sys.exit("--out is required")
        for s in args.scenarios.split(","):
            if s not in SCENARIOS:
                sys.exit(f"unknown scenario '{s}'; scenarios: {', '.join(SCENARIOS)}")
        sweep(args)


if __name__ == "__main__":
    main()
