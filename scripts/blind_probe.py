#!/usr/bin/env python3
"""A blind probe: every condition of a bench run drawn at random, on the independent simulator.

The fault matrix (scripts/fault_matrix.py) holds the rate, profile, duration
and fault size to a grid. This probe draws each run's conditions from its own
seeded generator instead, the way an outside check would pick cases nobody
tuned for:

  unit      by default navigation grade (INS-2000) with its datasheet, or
            labelled INS-2000 without one; a 0.1 °/h or a 1 °/h tactical
            unit with its class's datasheet. --units widens the choice to
            tactical and 10 °/h MEMS units without a datasheet, labelled
            INS-2000 or with no unit type
  table     profile (turns, positions, mixed, static), rate changes
            instantaneous or ramped, holds jittered
  sampling  10, 20, 25, 50, 100 or 200 Hz
  run       30 to 90 minutes, latitude −70° to 70°
  fault     none (about a third of the runs), or a gyro or accelerometer
            bias step of 5 to 50 drift σ (log-uniform) at 10–90 % of the
            run, or a bias ramp reaching 5 to 50 drift σ in 1000 s from
            10–70 % of the run; axis and sign at random

Each run goes through `insdiag analyze --json` and is judged as the fault
matrix judges it (its `judge`): detected, right effect (the significant term
with the lowest predicted ΔBIC, of look-alike faults the smaller, which
`--discover` adds first), right
module, onset error. A step's onset counts as found when it is within 60 s,
its size when the right effect's estimate is within 3 standard errors of it.
Runs where the fault cannot be seen are counted apart: a gyro fault whose
axis the table holds vertical from the onset to the end (a z gyro on a
table that never tilts z; any gyro turned vertical before its fault), whose
only trace is the heading.

Usage:
  scripts/blind_probe.py [--runs N] [--first-index I] [--kinds healthy,step,ramp] [--jobs J]
                         [--units nav,mems-unlabelled,...] [--out results.json]
(--kinds keeps the drawn runs of those kinds: the draws stay those of their index.)
INSDIAG_CLI names the CLI (default build/clients/insdiag).
"""
import argparse
import json
import math
import os
import random
import re
import subprocess
import sys
import tempfile
import threading

import numpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
import fault_matrix  # noqa: E402
from fault_matrix import BENCHSIM, CLI, PYTHON  # noqa: E402

UNITS = {  # name: (preset, datasheet, unit type)
    "nav": ("nav", "yes", "INS-2000"),
    "nav-labelled": ("nav", "no", "INS-2000"),
    "tactical-0.1": ("tactical-0.1", "yes", "none"),
    "tactical": ("tactical", "yes", "none"),
    "tactical-0.1-labelled": ("tactical-0.1", "no", "INS-2000"),
    "tactical-unlabelled": ("tactical", "no", "none"),
    "mems-labelled": ("mems", "no", "INS-2000"),
    "mems-unlabelled": ("mems", "no", "none"),
}
# The units of the first draws; a draw's conditions depend on the list it drew from.
DEFAULT_UNITS = "nav,nav-labelled,tactical-0.1,tactical"
PROFILES = ["turns", "positions", "mixed", "static"]
RATES_HZ = [10, 20, 25, 50, 100, 200]
SENSORS = ["gyro", "acc"]
# The fault matrix's judge reads its module-level unit class.
JUDGE_LOCK = threading.Lock()


def draw(index, units, rates_hz=RATES_HZ):
    """The run's conditions, from its own generator, its unit one of `units`
    (names in UNITS) and its rate one of `rates_hz`."""
    rng = random.Random(f"blind/{index}")
    preset, datasheet, unit_type = UNITS[rng.choice(units)]
    conditions = dict(index=index, seed=7000 + index, preset=preset, datasheet=datasheet, unit_type=unit_type,
                      profile=rng.choice(PROFILES), rate_hz=rng.choice(rates_hz),
                      duration_s=round(rng.uniform(1800.0, 5400.0)), latitude_deg=round(rng.uniform(-70, 70), 2),
                      ramp_accel_deg_s2=rng.choice([None, None, 5.0, 20.0]))
    kind = rng.choice(["healthy", "step", "ramp"])
    if kind == "healthy":
        conditions["fault"] = dict(kind=None, name=None, expected=None)
        return conditions
    sensor, axis, sign = rng.choice(SENSORS), rng.choice("xyz"), rng.choice([-1, 1])
    sigma = fault_matrix.unit_classes.PRESETS[preset]()[f"{sensor}_bias_gm.{axis}.sigma"]
    size_sigma = math.exp(rng.uniform(math.log(5.0), math.log(50.0)))
    duration = conditions["duration_s"]
    if kind == "step":
        onset, value = rng.uniform(0.1, 0.9) * duration, sign * size_sigma * sigma
    else:
        onset, value = rng.uniform(0.1, 0.7) * duration, sign * size_sigma * sigma / 1000.0
    name = f"{sensor}_bias_{kind}.{axis}"
    conditions["fault"] = dict(kind="effect", name=name, value=value, onset_s=round(onset, 3), sensor=sensor, axis=axis,
                               expected=name, size_drift_sigma=round(size_sigma, 2))
    return conditions


def kind_of(conditions):
    name = conditions["fault"]["name"]
    return "healthy" if name is None else "step" if "_step." in name else "ramp"


# An axis within this angle of the vertical senses no component of a tilt.
VERTICAL_WITHIN_DEG = 1.0


def heading_only(conditions, path):
    """A gyro fault whose axis the table holds vertical from the onset to the
    end shows only through the heading (a z gyro on a table that never tilts,
    or any gyro turned vertical before its fault and kept so)."""
    fault = conditions["fault"]
    if fault.get("sensor") != "gyro":
        return False
    with open(path) as f:
        lines = f.read().splitlines()
    header = next(i for i, line in enumerate(lines) if line.startswith("t,"))
    columns = lines[header].split(",")
    rows = numpy.loadtxt(lines[header + 1:], delimiter=",", usecols=[columns.index(c) for c in
                                                                      ("t", "ref_roll", "ref_pitch")])
    after = rows[rows[:, 0] >= fault["onset_s"]]
    roll, pitch = after[:, 1], after[:, 2]
    # The down component of the body axis in NED: the third row of
    # C_b^n = Rz(yaw)·Ry(pitch)·Rx(roll) (shared/spec/bench-run-format.md).
    down = {"x": -numpy.sin(pitch), "y": numpy.cos(pitch) * numpy.sin(roll),
            "z": numpy.cos(pitch) * numpy.cos(roll)}[fault["axis"]]
    return bool(numpy.all(numpy.abs(down) >= math.cos(math.radians(VERTICAL_WITHIN_DEG))))


def run_one(index, units, rates_hz=RATES_HZ):
    c = draw(index, units, rates_hz)
    fault = c["fault"]
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "run.csv")
        cmd = [PYTHON, BENCHSIM, "--out", path, "--preset", c["preset"], "--profile", c["profile"], "--rate-hz",
               str(c["rate_hz"]), "--duration", str(c["duration_s"]), "--seed", str(c["seed"]), "--datasheet",
               c["datasheet"], "--unit-type", c["unit_type"], "--latitude-deg", str(c["latitude_deg"])]
        if c["ramp_accel_deg_s2"]:
            cmd += ["--ramp-accel", str(c["ramp_accel_deg_s2"])]
        if fault["kind"]:
            cmd += ["--fault", f"{fault['name']}={fault['value']:.9g}@{fault['onset_s']}"]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        only_heading = fault["kind"] is not None and heading_only(c, path)
        done = subprocess.run([CLI, "analyze", path, "--json"], capture_output=True, text=True)
    if done.returncode != 0:
        return dict(c, error=done.stderr.strip()[-300:])
    report = json.loads(done.stdout)
    with JUDGE_LOCK:
        fault_matrix.use_unit_class(c["preset"])
        verdict = fault_matrix.judge(fault, report)
    return dict(c, heading_only=only_heading, allan_ramps=allan_ramps(report), allan_jumps=allan_jumps(report),
                drifts_held=drifts_held(report), constants_refuted=constants_refuted(report),
                raw_sample_faults=[c["name"] for c in report.get("effectCandidates", []) if c.get("source") == "RAW"],
                **verdict)


def drifts_held(report):
    """The drifts whose likelihood estimate the raw samples refused (the analysis's notes)."""
    found = (re.match(r"(\w+\.[xyz]): the innovations' likelihood peaks at .* the model holds it", note)
             for note in report.get("notes", []))
    return sorted({m.group(1) for m in found if m})


def constants_refuted(report):
    """The constant-bias candidates the still segments' raw samples refuted (their notes)."""
    return [c["name"] for c in report.get("effectCandidates", []) if "refuted by the raw samples" in c.get("note", "")]


def allan_ramps(report):
    """The channels whose Allan curve had a ramp taken out (the analysis's notes)."""
    found = (re.search(r"took a ramp out of (\w+)'s", note) for note in report.get("notes", []))
    return [m.group(1) for m in found if m]


def allan_jumps(report):
    """The channels whose still segments were cut at a jump of their mean (the analysis's notes)."""
    found = (re.search(r"the Allan analysis cut (\w+)'s", note) for note in report.get("notes", []))
    return [m.group(1) for m in found if m]


def summarise(results):
    done = [r for r in results if "error" not in r]
    lines = [f"runs: {len(results)}, failed to analyse: {len(results) - len(done)}", "",
             "| runs | count | detected | right effect | right module | step onset within 60 s | size within 3 SE "
             "| onset's ±1σ interval holds it | FAULTY |",
             "|---|---|---|---|---|---|---|---|---|"]

    def row(label, rs):
        steps = [r for r in rs if r["fault"].get("name", "") and "_step." in r["fault"]["name"]]
        onset_ok = sum(1 for r in steps if r["right_effect"] and (r.get("onset_error_s") or 1e9) <= 60.0)
        count = lambda key: sum(1 for r in rs if r.get(key))
        faulty = sum(1 for r in rs if r.get("verdict") == "FAULTY")
        sized = [r for r in rs if r["right_effect"] and r.get("estimate") is not None and r.get("std_error")]
        size_ok = sum(1 for r in sized if abs(r["estimate"] - r["fault"]["value"]) <= 3.0 * r["std_error"])
        # The onset's central interval leaves 16 % of its posterior on each side: it should hold 68 %.
        placed = [r for r in rs if r["right_effect"] and "onset_covered" in r]
        held = sum(1 for r in placed if r["onset_covered"])
        lines.append(f"| {label} | {len(rs)} | {count('detected')} | {count('right_effect')} | {count('right_module')} "
                     f"| {onset_ok} of {len(steps)} | {size_ok} of {len(sized)} | {held} of {len(placed)} | {faulty} |")

    healthy = [r for r in done if r["fault"]["kind"] is None]
    faulty = [r for r in done if r["fault"]["kind"]]
    row("healthy", healthy)
    row("faulty, every run", faulty)
    row("faulty, the fault visible beyond the heading", [r for r in faulty if not r["heading_only"]])
    for kind in ("gyro_bias_step", "acc_bias_step", "gyro_bias_ramp", "acc_bias_ramp"):
        row(kind, [r for r in faulty if r["fault"]["name"].startswith(kind)])
    for label, rs in (("healthy", healthy), ("faulty", faulty)):
        ramped = [r for r in rs if r.get("allan_ramps")]
        lines.append(f"\n{label}: a ramp taken out of the Allan curve in {len(ramped)} of {len(rs)} runs"
                     + "".join(f"; {r['index']}: {', '.join(r['allan_ramps'])}" for r in ramped))
    for label, rs in (("healthy", healthy), ("faulty", faulty)):
        cut = [r for r in rs if r.get("allan_jumps")]
        lines.append(f"\n{label}: a still segment cut at a jump in {len(cut)} of {len(rs)} runs"
                     + "".join(f"; {r['index']}: {', '.join(r['allan_jumps'])}" for r in cut))
    for label, rs in (("healthy", healthy), ("faulty", faulty)):
        held = [r for r in rs if r.get("drifts_held")]
        lines.append(f"\n{label}: a drift held within what the raw samples allow in {len(held)} of {len(rs)} runs"
                     + "".join(f"; {r['index']}: {', '.join(r['drifts_held'])}" for r in held))
    misses = [r for r in faulty if not r["right_module"]] + [r for r in healthy if r["detected"]]
    if misses:
        lines += ["", "Misses and false alarms:"]
        for r in misses:
            f = r["fault"]
            what = f"{f['name']} {f['size_drift_sigma']} σ @ {f['onset_s']:.0f} s" if f["kind"] else "healthy"
            lines.append(f"- {r['index']}: {r['preset']} datasheet {r['datasheet']}, {r['profile']} {r['rate_hz']} Hz, "
                         f"{r['duration_s']} s, lat {r['latitude_deg']}: {what} → {r['verdict']}, {r['top']}"
                         f"{' (heading only)' if r['heading_only'] else ''}")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=40)
    parser.add_argument("--first-index", type=int, default=0)
    parser.add_argument("--indices", default=None,
                        help="comma-separated draw indices to run instead of --first-index/--runs (a rerun)")
    parser.add_argument("--kinds", default="healthy,step,ramp")
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default=None)
    parser.add_argument("--units", default=DEFAULT_UNITS, help=f"units to draw from, of: {', '.join(UNITS)}")
    parser.add_argument("--rates", default=",".join(map(str, RATES_HZ)),
                        help="sample rates to draw from, Hz (a draw's conditions depend on the list)")
    args = parser.parse_args()
    kinds = set(args.kinds.split(","))
    units = args.units.split(",")
    rates_hz = [float(r) if "." in r else int(r) for r in args.rates.split(",")]
    unknown = [u for u in units if u not in UNITS]
    if unknown:
        parser.error(f"--units: unknown unit {', '.join(unknown)}; known: {', '.join(UNITS)}")
    drawn = ([int(i) for i in args.indices.split(",")] if args.indices
             else range(args.first_index, args.first_index + args.runs))
    indices = [i for i in drawn if kind_of(draw(i, units, rates_hz)) in kinds]
    print(summarise(fault_matrix.run_all(lambda i: run_one(i, units, rates_hz), indices, args.jobs, args.out)))


if __name__ == "__main__":
    main()
