#!/usr/bin/env python3
"""The fault-zoo scenario matrix: faulty and healthy units through `insdiag analyze`,
on two independent simulators, over seeds, axes, onsets, profiles and rates.

Each scenario hides one fault (or none) in a unit of one class (--unit-class):
`nav`, a navigation-grade unit of the INS-2000 type (its nominal model, per axis),
or one of the independent simulator's presets with no unit type, such as
`tactical-0.1`, a gyro drift of 0.1 °/h and τ 200 s (the drift of the unit in
issue 17's bias-step report). The datasheet in the file
states the class, not the fault. Each run draws its axis and onset from the seed, and takes its
rate (10, 50, 100 Hz) and table profile from the seed too, so that every
scenario covers every rate and three profiles per simulator:

  cpp   `insdiag simulate` (the project's own simulator): rotations, positions, full
  py    tests/benchsim/benchsim.py (written from the spec alone): turns, positions, mixed

For each run the report's verdict, its most significant candidate and the
identified drift parameters are read, and per scenario the script prints:

  detected      the analysis says the unit is not healthy: verdict FAULTY, or a
                candidate significant at family-wise 1 %, or an identified drift or
                noise parameter whose family-wise 1 % interval (Bonferroni over the
                parameters compared) excludes the nominal value
  right effect  the analysis's best explanation: the significant term or family with
                the lowest predicted ΔBIC (of look-alike faults within 2 of it, the
                smaller), which `--discover` adds first (or, for drift and noise
                changes, the parameter that departs most) is the injected one,
                on the injected axis
  right module  the failure-mode catalogue (data/failure-modes) maps that
                effect to the injected sensor's module (gyro.x, acc.z, ...)
  onset error   |onset − truth| of the top candidate for steps and ramps
  false alarm   for healthy units: the "detected" column

Usage:
  scripts/fault_matrix.py [--runs N] [--duration S] [--simulators cpp,py]
                          [--scenarios a,b] [--unit-class nav|tactical-0.1|…]
                          [--jobs J] [--out results.json]
The figures in docs/FAULT_SCENARIOS.md come from
  scripts/fault_matrix.py --runs 9 --duration 3600 --jobs 2
"""
import argparse
import concurrent.futures
import json
import math
import os
import random
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CLI = os.environ.get("INSDIAG_CLI", os.path.join(ROOT, "build", "clients", "insdiag"))
BENCHSIM = os.path.join(ROOT, "tests", "benchsim", "benchsim.py")
sys.path.insert(0, os.path.dirname(BENCHSIM))
import unit_classes  # noqa: E402
# The Debian interpreter, which has numpy and scipy (scripts/install-deps.sh).
PYTHON = "/usr/bin/python3" if os.path.exists("/usr/bin/python3") else sys.executable
UNIT_TYPE = os.path.join(ROOT, "data", "unit-types", "INS-2000.json")

RATES_HZ = [10.0, 50.0, 100.0]
PROFILES = {"cpp": ["rotations", "positions", "full"], "py": ["turns", "positions", "mixed"]}
AXES = "xyz"


def nav_class():
    """INS-2000's nominal values by parameter name (SI)."""
    with open(UNIT_TYPE) as f:
        return {p["name"]: p["value"] for p in json.load(f)["nominal"]}


# The unit's class: `nav` is INS-2000 (its whole nominal model, and the file
# names the type); any other is one of the independent simulator's presets
# (tests/benchsim/unit_classes.py), with no unit type.
UNIT_CLASSES = ["nav"] + [name for name in unit_classes.PRESETS if name != "nav"]
UNIT_CLASS = "nav"
NOMINAL = nav_class()
UNIT_TYPE_NAME = "INS-2000"


def use_unit_class(name):
    global UNIT_CLASS, NOMINAL, UNIT_TYPE_NAME
    UNIT_CLASS = name
    if name == "nav":
        NOMINAL, UNIT_TYPE_NAME = nav_class(), "INS-2000"
    else:
        NOMINAL, UNIT_TYPE_NAME = unit_classes.PRESETS[name](), None


def drift_sigma(sensor, axis):
    return NOMINAL[f"{sensor}_bias_gm.{axis}.sigma"]


# Scenario: name -> function(rng, duration_s) returning the injected fault:
#   kind      "effect" (a catalogue effect NAME=VALUE[@ONSET]) or "param" (a base-model
#             parameter changed) or None (healthy)
#   name, value, onset_s, sensor, axis, expected (effect or parameter that should be named)
def step(sensor):
    def make(rng, duration_s):
        axis = rng.choice(AXES)
        size = rng.choice([-1, 1]) * 5.0 * drift_sigma(sensor, axis)
        onset = rng.uniform(0.3, 0.8) * duration_s
        return dict(kind="effect", name=f"{sensor}_bias_step.{axis}", value=size, onset_s=onset, sensor=sensor,
                    axis=axis, expected=f"{sensor}_bias_step.{axis}")
    return make


def ramp(sensor):
    def make(rng, duration_s):
        axis = rng.choice(AXES)
        # Reaches five drift σ within 1000 s of its onset.
        rate = rng.choice([-1, 1]) * 5.0 * drift_sigma(sensor, axis) / 1000.0
        onset = rng.uniform(0.2, 0.6) * duration_s
        return dict(kind="effect", name=f"{sensor}_bias_ramp.{axis}", value=rate, onset_s=onset, sensor=sensor,
                    axis=axis, expected=f"{sensor}_bias_ramp.{axis}")
    return make


def drift_change(parameter, factor):
    def make(rng, duration_s):
        axis = rng.choice(AXES)
        name = f"gyro_bias_gm.{axis}.{parameter}"
        return dict(kind="param", name=name, value=NOMINAL[name] * factor, factor=factor, sensor="gyro", axis=axis,
                    expected=name)
    return make


def arw_double(rng, duration_s):
    axis = rng.choice(AXES)
    name = f"gyro_arw.{axis}"
    return dict(kind="param", name=name, value=NOMINAL[name] * 2.0, factor=2.0, sensor="gyro", axis=axis,
                expected=name)


def scale_factor(all_axes):
    def make(rng, duration_s):
        axis = rng.choice(AXES)
        value = rng.choice([-1, 1]) * 50e-6
        name = "gyro_scale_factor" if all_axes else f"gyro_scale_factor.{axis}"
        return dict(kind="effect", name=name, value=value, sensor="gyro", axis=None if all_axes else axis,
                    expected=name)
    return make


def healthy(rng, duration_s):
    return dict(kind=None, name=None, expected=None)


SCENARIOS = {
    "healthy": healthy,
    "gyro_step": step("gyro"),
    "acc_step": step("acc"),
    "gyro_ramp": ramp("gyro"),
    "acc_ramp": ramp("acc"),
    "drift_sigma_x3": drift_change("sigma", 3.0),
    "drift_sigma_x10": drift_change("sigma", 10.0),
    "drift_tau_x0.1": drift_change("tau", 0.1),
    "drift_tau_x10": drift_change("tau", 10.0),
    "arw_x2": arw_double,
    "scale_factor_one_axis": scale_factor(False),
    "scale_factor_all_axes": scale_factor(True),
}


def module_of(effect_or_parameter):
    """The module a failure-mode signature ties this effect or parameter to."""
    if effect_or_parameter is None:
        return None
    with open(os.path.join(ROOT, "data", "failure-modes", "INS-2000.json")) as f:
        modes = json.load(f)["modes"]
    family = effect_or_parameter.split(".")[0]
    parts = effect_or_parameter.split(".")
    axis = parts[1] if len(parts) > 1 and parts[1] in AXES else None
    for m in modes:
        for term in m["signature"]:
            p = term["parameter"]
            if p.split(".")[0] != family:
                continue
            if p.endswith(".*") or "{i}" not in p:
                return m["moduleRole"]
            if axis is not None and (len(parts) < 3 or p.split(".")[-1] == parts[-1]):
                return m["moduleRole"].replace("{i}", axis)
    return None


def simulate(simulator, fault, rate_hz, profile, seed, duration_s, path):
    if simulator == "cpp":
        cmd = [CLI, "simulate", path, "--profile", profile, "--rate", f"{rate_hz:g}", "--seed", str(seed)]
        if UNIT_CLASS != "nav":
            cmd += ["--no-datasheet"] + [f"--param={n}={v:.9g}" for n, v in sorted(NOMINAL.items())]
        if fault["kind"] == "effect":
            onset = f"@{fault['onset_s']:.3f}" if "onset_s" in fault else ""
            cmd += ["--effect", f"{fault['name']}={fault['value']:.6g}{onset}"]
        elif fault["kind"] == "param":
            cmd += ["--param", f"{fault['name']}={fault['value']:.6g}"]
    else:
        cmd = [PYTHON, BENCHSIM, "--out", path, "--preset", UNIT_CLASS, "--profile", profile, "--rate-hz",
               f"{rate_hz:g}", "--duration", f"{duration_s:g}", "--seed", str(seed), "--datasheet", "yes",
               "--unit-type", UNIT_TYPE_NAME or "none"]
        if fault["kind"] == "effect":
            onset = f"@{fault['onset_s']:.3f}" if "onset_s" in fault else ""
            cmd += ["--fault", f"{fault['name']}={fault['value']:.6g}{onset}"]
        elif fault["kind"] == "param":
            cmd += ["--fault", f"{fault['name']}*{fault['factor']:g}"]
    subprocess.run(cmd, check=True, capture_output=True, text=True)
    if simulator == "cpp" and UNIT_CLASS != "nav":
        state_unit_class(path)


def state_unit_class(path):
    """The project's simulator states INS-2000: name no unit type, and write the
    class's datasheet instead."""
    with open(path) as f:
        lines = f.readlines()
    metadata = [line for line in lines if line.startswith("#")]
    rows = lines[len(metadata):]
    metadata = [line for line in metadata if not line.startswith("# unit_type:")]
    with open(path, "w") as f:
        f.writelines(metadata + [line + "\n" for line in unit_classes.datasheet_lines(NOMINAL)] + rows)


def truncate(path, duration_s):
    """The C++ profiles have their own lengths: keep the first `duration_s`."""
    with open(path) as f:
        lines = f.readlines()
    out, header_seen = [], False
    for line in lines:
        if line.startswith("#") or not header_seen:
            out.append(line)
            header_seen = header_seen or not line.startswith("#")
            continue
        if float(line.split(",", 1)[0]) > duration_s:
            break
        out.append(line)
    with open(path, "w") as f:
        f.writelines(out)


def significant(candidate):
    return candidate.get("identifiable") and not candidate.get("notTested") and candidate.get("pValueHolm", 1) < 0.01


def normal_quantile(p):
    """Φ⁻¹(p) by bisection on math.erf (no scipy needed)."""
    low, high = -40.0, 40.0
    for _ in range(200):
        mid = 0.5 * (low + high)
        if 0.5 * (1.0 + math.erf(mid / math.sqrt(2.0))) < p:
            low = mid
        else:
            high = mid
    return 0.5 * (low + high)


def departures(report):
    """Identified drift and noise parameters against the nominal, (|z|, name), where the
    family-wise 1 % interval (Bonferroni over the parameters compared) excludes it."""
    compared = []
    for p in report.get("identified", []):
        name, value, se = p["name"], p.get("value", 0.0), p.get("stdError", 0.0)
        if name not in NOMINAL or not (se and se > 0 and value > 0):
            continue
        compared.append((abs(math.log(value / NOMINAL[name])) / (se / value), name))
    if not compared:
        return []
    threshold = -normal_quantile(0.005 / len(compared))
    return sorted((c for c in compared if c[0] > threshold), reverse=True)


def judge(fault, report):
    candidates = report.get("effectCandidates", [])
    # The analysis's best explanation, the effect `--discover` adds first: the
    # significant term or whole family with the lowest predicted ΔBIC. Of the
    # terms, the analysis's first significant one: its order is by ΔBIC, but
    # puts the smaller of look-alike faults the run cannot tell apart first
    # (min keeps the first of equal keys, as the analysis does).
    terms = [c for c in candidates if significant(c)][:1]
    explanations = terms + [c for c in report.get("familyCandidates", []) if significant(c)]
    top = min(explanations, key=lambda c: c.get("predictedDeltaBic", 0.0), default=None)
    moved = departures(report)
    named = top["name"] if top else (moved[0][1] if moved else None)
    result = dict(verdict=report.get("verdict"), top=named, detected=False, right_effect=False, right_module=False,
                  onset_error_s=None, significant=[c["name"] for c in candidates if significant(c)][:5],
                  departures=[[round(z, 1), n] for z, n in moved[:5]])
    result["detected"] = report.get("verdict") == "FAULTY" or top is not None or bool(moved)
    if fault["kind"] is None:
        return result
    expected = fault["expected"]
    if fault["kind"] == "param":
        # The parameter that departs most, among the identified ones.
        named = moved[0][1] if moved else (top["name"] if top else None)
        result["top"] = named
    result["right_effect"] = named is not None and (named == expected or named.startswith(expected + "."))
    want_module = module_of(expected)
    result["right_module"] = named is not None and want_module is not None and module_of(named) == want_module
    if top is not None and named == top["name"]:
        result["estimate"], result["std_error"] = top.get("estimate"), top.get("stdError")
    if top is not None and "onset_s" in fault and "onsetS" in top:
        result["onset_error_s"] = abs(top["onsetS"] - fault["onset_s"])
        result["onset_interval_s"] = [top.get("onsetLowS"), top.get("onsetHighS")]
        result["onset_covered"] = top.get("onsetLowS", 0) <= fault["onset_s"] <= top.get("onsetHighS", 0)
    return result


def run_one(args):
    simulator, scenario, index, duration_s = args
    rng = random.Random(f"{simulator}/{scenario}/{index}")
    seed = 1000 + index
    rate_hz = RATES_HZ[index % 3]
    profile = PROFILES[simulator][(index // 3) % 3]
    fault = SCENARIOS[scenario](rng, duration_s)
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "run.csv")
        simulate(simulator, fault, rate_hz, profile, seed, duration_s, path)
        if simulator == "cpp":
            truncate(path, duration_s)
        done = subprocess.run([CLI, "analyze", path, "--json"], capture_output=True, text=True)
        if done.returncode != 0:
            return dict(simulator=simulator, scenario=scenario, index=index, error=done.stderr.strip()[-300:])
        report = json.loads(done.stdout)
    return dict(simulator=simulator, scenario=scenario, index=index, rate_hz=rate_hz, profile=profile,
                fault={k: v for k, v in fault.items() if k != "kind"}, **judge(fault, report))


def summarise(results):
    rows = {}
    for r in results:
        rows.setdefault((r["scenario"], r["simulator"]), []).append(r)
    lines = ["| scenario | simulator | runs | detected | right effect | right module | onset error (median, max) | "
             "FAULTY verdicts |", "|---|---|---|---|---|---|---|---|"]
    for (scenario, simulator), rs in sorted(rows.items()):
        ok = [r for r in rs if "error" not in r]
        n = len(ok)
        onset = sorted(r["onset_error_s"] for r in ok if r.get("onset_error_s") is not None)
        onset_text = f"{onset[len(onset) // 2]:.0f} s, {onset[-1]:.0f} s" if onset else "—"
        count = lambda key: sum(1 for r in ok if r.get(key))
        faulty = sum(1 for r in ok if r.get("verdict") == "FAULTY")
        errors = len(rs) - n
        lines.append(f"| {scenario} | {simulator} | {n}{f' ({errors} failed)' if errors else ''} | {count('detected')} "
                     f"| {count('right_effect') if scenario != 'healthy' else '—'} "
                     f"| {count('right_module') if scenario != 'healthy' else '—'} | {onset_text} | {faulty} |")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=9)
    parser.add_argument("--duration", type=float, default=3600.0)
    parser.add_argument("--simulators", default="cpp,py")
    parser.add_argument("--scenarios", default=",".join(SCENARIOS))
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    parser.add_argument("--unit-class", default="nav", choices=UNIT_CLASSES)
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    use_unit_class(args.unit_class)
    simulators = [s for s in args.simulators.split(",") if s]
    if "py" in simulators and not os.path.exists(BENCHSIM):
        sys.exit(f"{BENCHSIM} is missing")
    work = [(sim, sc, i, args.duration) for sim in simulators for sc in args.scenarios.split(",")
            for i in range(args.runs)]
    print(summarise(run_all(run_one, work, args.jobs, args.out)))


def run_all(run, work, jobs, out_path):
    """Runs `run` over `work` on `jobs` threads, each result to stderr as it comes (a JSON line),
    all of them to `out_path` if given; returns them in order."""
    results = []
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        for r in pool.map(run, work):
            results.append(r)
            print(json.dumps(r), file=sys.stderr, flush=True)
    if out_path:
        with open(out_path, "w") as f:
            json.dump(results, f, indent=1)
    return results


if __name__ == "__main__":
    main()
