#!/usr/bin/env python3
"""How often the onset's reported interval holds the true onset, on the independent simulator.

The report gives each bias step or ramp's onset with a central interval
that leaves 16 % of the onset's posterior on each side (`onsetLowS` …
`onsetHighS`): over many runs it should hold the truth in 68 % of them, and
the placed onset should fall as often before the truth as after it.

Run i is the independent simulator's (tests/benchsim) unit of a class drawn
from the run's own seeded generator (seed 6000 + i), with its datasheet, a
half hour long: a step (i even) or a ramp reaching its size in 1000 s (i
odd), of the gyro or the accelerometer, on a random axis and sign, of 5 to
50 drift σ (log-uniform), at 30–70 % of the run; profile (static,
positions, turns, mixed) and rate (10, 50, 100, 200 Hz) drawn too. From
`insdiag analyze --json`, the fault's own candidate where it is significant
at family-wise 1 %: its onset error in samples and whether its interval
holds the truth.

--kind, --sensor, --preset, --profile, --rate-hz and --drift-sigmas pin
that part of the draw (the rest is drawn as before); --update-interval is
passed to the analysis.

Usage:
  scripts/onset_coverage.py [--runs 60] [--first-index 0] [--jobs 2] [--out results.json]
                            [--kind step|ramp] [--sensor gyro|acc] [--preset mems] [--profile static]
                            [--rate-hz 10] [--drift-sigmas 49] [--update-interval 0.1]
INSDIAG_CLI names the CLI (default build/clients/insdiag).
"""
import argparse
import json
import math
import os
import random
import subprocess
import tempfile

import fault_matrix
import unit_classes  # noqa: E402 (fault_matrix puts the simulator's directory on the path)
from fault_matrix import BENCHSIM, CLI, PYTHON

DURATION_S = 1800.0
RAMP_SPAN_S = 1000.0  # a ramp reaches its size in drift σ this long after its onset
# Each tail of the onset posterior outside the reported interval: the report
# carries the interval, not its level, which is OnsetScanOptions::interval_tail
# (engine/include/insdiag/engine/finder/onset_scan.h).
TAIL = 0.16


def draw(i, pinned):
    """Run i's conditions; `pinned` holds those the command line fixed (None: drawn)."""
    rng = random.Random(6000 + i)
    pick = lambda key, drawn: drawn if pinned.get(key) is None else pinned[key]
    kind = pick("kind", ("step", "ramp")[i % 2])
    sensor = pick("sensor", rng.choice(("gyro", "acc")))
    axis = rng.choice("xyz")
    preset = pick("preset", rng.choice(sorted(unit_classes.PRESETS)))
    sigmas = pick("drift_sigmas", math.exp(rng.uniform(math.log(5.0), math.log(50.0))))
    drift_sigma = unit_classes.PRESETS[preset]()[f"{sensor}_bias_gm.{axis}.sigma"]
    value = rng.choice((-1, 1)) * sigmas * drift_sigma / (RAMP_SPAN_S if kind == "ramp" else 1.0)
    return {"index": i, "term": f"{sensor}_bias_{kind}.{axis}", "preset": preset, "value": value,
            "size_drift_sigma": round(sigmas, 2), "onset_s": round(rng.uniform(0.3, 0.7) * DURATION_S, 3),
            "profile": pick("profile", rng.choice(("static", "positions", "turns", "mixed"))),
            "rate_hz": pick("rate_hz", rng.choice((10, 50, 100, 200)))}


def run_one(i, pinned, update_interval_s):
    d = draw(i, pinned)
    with tempfile.TemporaryDirectory() as work:
        path = os.path.join(work, "run.csv")
        subprocess.run([PYTHON, BENCHSIM, "--out", path, "--preset", d["preset"], "--profile", d["profile"],
                        "--rate-hz", str(d["rate_hz"]), "--duration", str(DURATION_S), "--seed", str(6000 + i),
                        "--datasheet", "yes", "--fault", f"{d['term']}={d['value']}@{d['onset_s']}"],
                       check=True, capture_output=True)
        interval = ["--update-interval", str(update_interval_s)] if update_interval_s else []
        done = subprocess.run([CLI, "analyze", path, "--json", *interval], capture_output=True, text=True)
    if done.returncode != 0:
        return {**d, "error": done.stderr.strip()[-300:]}
    report = json.loads(done.stdout)
    own = [c for c in report["effectCandidates"] if c["name"] == d["term"] and fault_matrix.significant(c)]
    if not own or own[0].get("onsetS") is None:
        return {**d, "found": False}
    c = own[0]
    sample_s = 1.0 / d["rate_hz"]
    return {**d, "found": True, "size_error_se": (c["estimate"] - d["value"]) / c["stdError"],
            "onset_error_s": c["onsetS"] - d["onset_s"],
            "onset_error_samples": (c["onsetS"] - d["onset_s"]) / sample_s,
            "interval_samples": [(c["onsetLowS"] - d["onset_s"]) / sample_s,
                                 (c["onsetHighS"] - d["onset_s"]) / sample_s],
            "onset_covered": c["onsetLowS"] <= d["onset_s"] <= c["onsetHighS"]}


def summarise(results):
    nominal = 1.0 - 2.0 * TAIL
    lines = ["| faults | runs | found | interval holds the truth | 3σ band about 68 % | placed late / early "
             "| size within 3 SE |",
             "|---|---|---|---|---|---|---|"]
    for label, keep in (("every", lambda r: True),
                        ("steps", lambda r: "_step." in r["term"]), ("ramps", lambda r: "_ramp." in r["term"]),
                        ("gyro", lambda r: r["term"].startswith("gyro")),
                        ("accelerometer", lambda r: r["term"].startswith("acc"))):
        rs = [r for r in results if keep(r) and "error" not in r]
        found = [r for r in rs if r["found"]]
        held = sum(1 for r in found if r["onset_covered"])
        band = 3.0 * math.sqrt(nominal * (1.0 - nominal) / max(1, len(found)))
        late = sum(1 for r in found if r["onset_error_samples"] > 0)
        early = sum(1 for r in found if r["onset_error_samples"] < 0)
        measured = [r for r in found if "size_error_se" in r]
        sized = sum(1 for r in measured if abs(r["size_error_se"]) <= 3.0)
        share = f"{held / len(found):.2f}" if found else "—"
        lines.append(f"| {label} | {len(rs)} | {len(found)} | {held} ({share}) "
                     f"| {max(0.0, nominal - band):.2f}–{min(1.0, nominal + band):.2f} | {late} / {early} "
                     f"| {sized} of {len(measured)} |")
    failed = [r for r in results if "error" in r]
    if failed:
        lines.append(f"\nfailed to analyse: {', '.join(str(r['index']) for r in failed)}")
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=60)
    parser.add_argument("--first-index", type=int, default=0)
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", default=None)
    parser.add_argument("--kind", choices=("step", "ramp"))
    parser.add_argument("--sensor", choices=("gyro", "acc"))
    parser.add_argument("--preset", choices=sorted(unit_classes.PRESETS))
    parser.add_argument("--profile", choices=("static", "positions", "turns", "mixed"))
    parser.add_argument("--rate-hz", type=float)
    parser.add_argument("--drift-sigmas", type=float, help="the fault's size in drift σ")
    parser.add_argument("--update-interval", type=float, help="seconds between filter updates (the analysis's default: 1)")
    args = parser.parse_args()
    pinned = {"kind": args.kind, "sensor": args.sensor, "preset": args.preset, "profile": args.profile,
              "rate_hz": args.rate_hz, "drift_sigmas": args.drift_sigmas}
    indices = range(args.first_index, args.first_index + args.runs)
    results = fault_matrix.run_all(lambda i: run_one(i, pinned, args.update_interval), indices, args.jobs, args.out)
    print(summarise(results))


if __name__ == "__main__":
    main()
