#!/usr/bin/env python3
"""How much evidence a simulated run holds for its own fault: a missed fault
the run could not show, told apart from one the analysis failed to find.

For a run of the independent simulator (tests/benchsim) with one bias step
or ramp, this sets the likelihood ratio the analysis reached against the one
the truth reaches. From the run's own analysis (`insdiag analyze --json`),
`insdiag analyze --base` evaluates models the identification did not choose:

- the null: the best of the analysis's own model A, that model with every
  drift except the fault's sensor axis at its true values, and the true
  drifts (each without the fault);
- the fault's side: the true drifts, and the true drifts but the fault's
  axis as identified, each with the fault added at its scanned onset and
  magnitude (`--add`).

2Δℓ between the best of each is the evidence the run holds for the fault
when the drifts are learned from the run: each side's maximum over the
drifts is at least its best point here, so it is an estimate, not a bound.
Where it falls below the level of the onset scan's test (about 18 for p
0.01 over the onsets and the fault terms of a half hour at 1 s updates), no
test at that level finds the fault on that run; where it is above and the
analysis missed the fault, the miss is the analysis's.

Usage:
  scripts/fault_evidence.py RUN.csv [RUN.csv ...]
Each RUN.csv needs the simulator's RUN.csv.truth.json beside it. INSDIAG_CLI
names the CLI (default build/clients/insdiag).
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

from fault_matrix import CLI, significant


def analyze(*args):
    return subprocess.run([CLI, "analyze", *args], capture_output=True, text=True, check=True).stdout


def log_likelihoods_with_the_fault_added(run_csv, base_report, term):
    """ℓ of model A (the base) and of model B (the base with `term`) from the text report."""
    with tempfile.NamedTemporaryFile("w", suffix=".json", delete=False) as f:
        json.dump(base_report, f)
        base_path = f.name
    try:
        text = analyze(run_csv, "--base", base_path, "--add", term)
    finally:
        os.unlink(base_path)
    with_fault = float(re.search(r"log-likelihood ([-0-9.eE+]+)", text).group(1))
    realised = float(re.search(r"2ΔlogL realised ([-0-9.eE+]+)", text).group(1))
    return with_fault - realised / 2.0, with_fault


def with_true_drifts(report, truth_parameters, keep):
    """The report's model with every drift parameter the truth states set to it, except those `keep` names."""
    changed = json.loads(json.dumps(report))
    for p in changed["model"]["parameters"]:
        name = p["name"]
        if "_bias_gm." in name and name in truth_parameters and not keep(name):
            p["value"] = truth_parameters[name]
    return changed


def evidence(run_csv):
    with open(run_csv + ".truth.json") as f:
        truth = json.load(f)
    faults = [e for e in truth["effects"] if e["family"].endswith(("_bias_step", "_bias_ramp"))]
    if len(faults) != 1:
        raise SystemExit(f"{run_csv}: needs exactly one bias step or ramp in its truth, has {len(faults)}")
    fault = faults[0]
    term = f"{fault['family']}.{fault['axis']}"
    sensor = fault["family"].split("_bias_")[0]
    faulty_drift = f"{sensor}_bias_gm.{fault['axis']}."
    report = json.loads(analyze(run_csv, "--json"))
    params = truth["parameters"]
    others_null, others_fault = log_likelihoods_with_the_fault_added(
        run_csv, with_true_drifts(report, params, keep=lambda n: n.startswith(faulty_drift)), term)
    true_null, true_fault = log_likelihoods_with_the_fault_added(
        run_csv, with_true_drifts(report, params, keep=lambda n: False), term)
    null = max(report["logLikelihood"], others_null, true_null)
    named = [c for c in report["effectCandidates"] if significant(c)]
    return {"run": run_csv, "fault": term, "onset_s": fault["onset_s"], "verdict": report["verdict"],
            "first_significant": named[0]["name"] if named else None,
            "null_log_likelihood": {"model_a": report["logLikelihood"], "true_drifts_but_its_axis": others_null,
                                    "true_drifts": true_null},
            "fault_log_likelihood": {"true_drifts_but_its_axis": others_fault, "true_drifts": true_fault},
            "evidence_2dl": 2.0 * (max(others_fault, true_fault) - null)}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="+")
    args = parser.parse_args()
    for run_csv in args.runs:
        print(json.dumps(evidence(run_csv)), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
