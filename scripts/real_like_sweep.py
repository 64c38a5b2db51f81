#!/usr/bin/python3
"""What insdiag does with real-like raw logs of healthy units: the
independent simulator's raw logs (tests/benchsim/rawlog.py: quantised
output, an unknown tilt and heading, a swaying stand, turn-on biases)
imported as a user imports a real record (`insdiag import … --attitude
level`) and analysed with no datasheet and no unit type
(`insdiag analyze RUN --json`).

Per scenario and seed: the verdict, NIS and its band, the OUTLIER and
GRADUAL intervals that start in the first 60 s (channel, kind, start,
β²), every effect candidate significant at Holm p < 0.01 (each a false
finding: the units are healthy), the import's start attitude against the
truth, and the turn-on biases the analysis removed against the truth.

  /usr/bin/python3 scripts/real_like_sweep.py --seeds 5 --out sweep.jsonl
  /usr/bin/python3 scripts/real_like_sweep.py --scenarios nav-up,nav-up-sway --seeds 1-20
  /usr/bin/python3 scripts/real_like_sweep.py --table sweep.jsonl     # the table of a file

Each run is appended to the --out file (JSON lines) as soon as it is done; a
run already in the file is not run again. The CLI: --cli, else INSDIAG_CLI,
else build/clients/insdiag.
"""
import argparse
import hashlib
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(ROOT, "tests", "benchsim"))
import numpy as np  # noqa: E402

import benchsim  # noqa: E402

DEG = math.pi / 180.0
EARLY_S = 60.0
SITE = (48.137, 11.575, 519.0)

NAV = ["--preset", "nav", "--rate-hz", "64", "--duration", "300", "--raw-format", "f64", "--tilt-deg", "1"]
MEMS = ["--preset", "mems", "--rate-hz", "100", "--duration", "3600", "--raw-format", "f64", "--tilt-deg", "1"]
# Scenario: the simulator's arguments, and whether the stand rocks (drawn per
# seed): True both sway and settling, "sway" or "settle" one of them.
SCENARIOS = {
    "nav-up": (NAV + ["--orientation", "up"], False),
    "nav-side": (NAV + ["--orientation", "side"], False),
    "nav-up-sway": (NAV + ["--orientation", "up"], True),
    "nav-side-sway": (NAV + ["--orientation", "side"], True),
    "mems": (MEMS + ["--orientation", "up"], False),
    "mems-sway": (MEMS + ["--orientation", "up"], True),
    # Ablations: one property off at a time (the other draws unchanged).
    "nav-up-unquantised": (NAV + ["--orientation", "up", "--quantise", "no"], False),
    "nav-up-level": (NAV + ["--orientation", "up", "--tilt-deg", "0"], False),
    "nav-up-gyro-quantised-only": (NAV + ["--orientation", "up", "--acc-lsb", "1e-9"], False),
    "mems-unquantised": (MEMS + ["--orientation", "up", "--quantise", "no"], False),
    "mems-2.8h": ([a if a != "3600" else "10008" for a in MEMS] + ["--orientation", "up"], False),
    # The accelerometers' count: 125 µg·s (as the record in data/real) over 4 and 16.
    "nav-up-acc-31ugs": (NAV + ["--orientation", "up", "--acc-lsb", str(31.25e-6 * 9.80665)], False),
    "nav-up-acc-8ugs": (NAV + ["--orientation", "up", "--acc-lsb", str(7.8125e-6 * 9.80665)], False),
    "nav-up-sway-only": (NAV + ["--orientation", "up"], "sway"),
    "nav-up-settle-only": (NAV + ["--orientation", "up"], "settle"),
    "nav-up-sway-unquantised": (NAV + ["--orientation", "up", "--quantise", "no"], True),
    # What a real part adds beyond the preset's Gauss–Markov drift: a flicker
    # floor (bias instability at the class's datasheet values) and a warm-up.
    "mems-flicker": (MEMS + ["--orientation", "up", "--gyro-flicker-dph", "10", "--acc-flicker-ug", "100"], False),
    # Which sensor's floor a MEMS flicker result comes from.
    "mems-flicker-gyro-only": (MEMS + ["--orientation", "up", "--gyro-flicker-dph", "10"], False),
    "mems-flicker-acc-only": (MEMS + ["--orientation", "up", "--acc-flicker-ug", "100"], False),
    "mems-2.8h-flicker": ([a if a != "3600" else "10008" for a in MEMS] +
                          ["--orientation", "up", "--gyro-flicker-dph", "10", "--acc-flicker-ug", "100"], False),
    "mems-warmup": (MEMS + ["--orientation", "up", "--warmup-gyro-dps", "0.05", "--warmup-acc-mg", "5",
                            "--warmup-tau-s", "600"], False),
    "mems-warmup-60s": (MEMS + ["--orientation", "up", "--warmup-gyro-dps", "0.1", "--warmup-acc-mg", "10",
                                "--warmup-tau-s", "60"], False),
    "mems-warmup-3000s": (MEMS + ["--orientation", "side", "--warmup-gyro-dps", "0.02", "--warmup-acc-mg", "2",
                                  "--warmup-tau-s", "3000"], False),
    "nav-up-warmup": (NAV + ["--orientation", "up", "--warmup-gyro-dps", "0.00001", "--warmup-acc-mg", "0.1",
                             "--warmup-tau-s", "300"], False),
    "nav-up-flicker": (NAV + ["--orientation", "up", "--gyro-flicker-dph", "0.005", "--acc-flicker-ug", "10"], False),
}
MAIN = ["nav-up", "nav-side", "nav-up-sway", "nav-side-sway", "mems", "mems-sway"]


def sway_draw(seed):
    """The stand's sway and settling for a seed: amplitudes log-uniform
    (sway 10 µrad–1 mrad, settling 0.1–3 mrad), frequencies uniform (sway
    0.1–5 Hz, settling 1–5 Hz), ring-down τ 0.5–3 s."""
    rng = np.random.default_rng([seed, 77])
    return dict(sway_urad=math.exp(rng.uniform(math.log(10.0), math.log(1000.0))), sway_hz=rng.uniform(0.1, 5.0),
                settle_urad=math.exp(rng.uniform(math.log(100.0), math.log(3000.0))),
                settle_hz=rng.uniform(1.0, 5.0), settle_tau_s=rng.uniform(0.5, 3.0))


def significant(candidate):
    return candidate.get("identifiable") and not candidate.get("notTested") and candidate.get("pValueHolm", 1) < 0.01


def first_row(run_csv):
    with open(run_csv) as f:
        for line in f:
            if line.startswith("#") or line.startswith("t,"):
                continue
            return [float(v) for v in line.split(",")]


def angle_diff(a, b):
    return math.remainder(a - b, 2 * math.pi)


def sha256_of(path):
    with open(path, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def one_run(cli, scenario, seed, work):
    args, sways = SCENARIOS[scenario]
    log = os.path.join(work, "raw.bin")
    run = os.path.join(work, "run.csv")
    extra = []
    sway = sway_draw(seed) if sways else None
    if sways == "sway":  # the stand sways; no settling transient
        sway["settle_urad"] = 0.0
    elif sways == "settle":  # it settles; no sway
        sway["sway_urad"] = 0.0
    if sway:
        extra = [f"--{k.replace('_', '-')}={v}" for k, v in sway.items()]
    sim = ["--raw-log", "--out", log, "--seed", str(seed), "--latitude-deg", str(SITE[0]),
           "--longitude-deg", str(SITE[1]), "--height-m", str(SITE[2])] + args + extra
    t0 = time.time()
    if benchsim.main(sim) != 0:
        raise RuntimeError(f"the simulator refused {sim}")
    with open(log + ".truth.json") as f:
        truth = json.load(f)
    imp = [cli, "import", log, "--binary", "f64", "--columns", truth["import_columns"], "--units",
           truth["import_units"], "--attitude", "level", "--site", ",".join(str(v) for v in SITE),
           "--serial", f"RL-{scenario}-{seed}", "-o", run]
    done = subprocess.run(imp, capture_output=True, text=True)
    record = dict(scenario=scenario, seed=seed, cli_sha256=sha256_of(cli), simulate=[a for a in sim if a not in (log,)],
                  sway=sway, import_cmd=imp[1:], truth_start_rpy_rad=truth["start_rpy_rad"],
                  truth_turn_on=truth["turn_on_biases"], truth_roll_pitch_rad=[truth["roll0_rad"], truth["pitch0_rad"]],
                  truth_heading_rad=truth["heading_rad"], truth_counter_residues=truth.get("counter_residues"),
                  truth_warmup=truth.get("warmup"))
    if done.returncode != 0:
        record.update(verdict="IMPORT-REFUSED", error=done.stderr.strip()[-400:])
        return record
    row = first_row(run)
    rpy = row[7:10]
    record["import_rpy_error_deg"] = [angle_diff(rpy[i], truth["start_rpy_rad"][i]) / DEG for i in range(3)]
    done = subprocess.run([cli, "analyze", run, "--json"], capture_output=True, text=True)
    record["seconds"] = round(time.time() - t0, 1)
    if done.returncode != 0:
        record.update(verdict="ANALYSIS-FAILED", error=done.stderr.strip()[-400:])
        return record
    report = json.loads(done.stdout)
    record.update(
        verdict=report["verdict"], nis=report.get("nisMean"), band=[report.get("nisBandLow"), report.get("nisBandHigh")],
        channel_nis={c["name"]: c.get("nisMean") for c in report.get("channels", []) if c.get("nisMean")},
        early=[dict(channel=f["channel"], kind=f["kind"], start_s=f["startS"], end_s=f["endS"],
                    beta2=f.get("peakStatistic")) for f in report.get("faultIntervals", [])
               if f["kind"] in ("OUTLIER", "GRADUAL") and f["startS"] < EARLY_S],
        intervals=[dict(channel=f["channel"], kind=f["kind"], start_s=f["startS"], end_s=f["endS"],
                        beta2=f.get("peakStatistic")) for f in report.get("faultIntervals", [])],
        significant=[dict(name=c["name"], estimate=c.get("estimate"), std_error=c.get("stdError"),
                          p_holm=c.get("pValueHolm"), onset_s=c.get("onsetS")) for c in report.get("effectCandidates", [])
                     if significant(c)],
        localisation=[dict(state=l.get("state"), time_s=l.get("timeS"), p=l.get("pValue"))
                      for l in report.get("localisation", [])][:5],
        removed={p["name"]: p["value"] for p in report.get("identified", []) if p.get("method") == "STATIC"},
        warm_ups={p["name"]: dict(value=p["value"], std_error=p.get("stdError")) for p in report.get("identified", [])
                  if "_warm_up." in p["name"]},
        plain_words=report.get("plainWords", []))
    return record


def load(path):
    records = []
    if os.path.exists(path):
        with open(path) as f:
            records = [json.loads(line) for line in f if line.strip()]
    return records


def fmt_rate(k, n):
    return f"{k}/{n}" if n else "—"


def table(records):
    """One line per scenario: the rates over its seeds."""
    lines = ["| scenario | runs | GOOD | OPERABLE | FAULTY | NIS median (min–max) | band (median) | NIS above band | "
             "OUTLIER < 60 s (channels) | GRADUAL < 60 s (channels) | significant at Holm p < 0.01 | "
             "gyro turn-on bias removed: worst error | heading error of the import (median abs) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    order = [s for s in SCENARIOS if any(r["scenario"] == s for r in records)]
    for s in order:
        rs = [r for r in records if r["scenario"] == s]
        ok = [r for r in rs if r["verdict"] in ("GOOD", "OPERABLE", "FAULTY")]
        n = len(rs)
        count = lambda v: sum(1 for r in rs if r["verdict"] == v)
        nis = sorted(r["nis"] for r in ok)
        bands = sorted(r["band"][1] for r in ok)
        lows = sorted(r["band"][0] for r in ok)
        above = sum(1 for r in ok if r["nis"] > r["band"][1])
        below = sum(1 for r in ok if r["nis"] < r["band"][0])

        def early(kind):
            runs = [r for r in ok if any(e["kind"] == kind for e in r["early"])]
            chans = {}
            for r in runs:
                for c in sorted({e["channel"] for e in r["early"] if e["kind"] == kind}):
                    chans[c] = chans.get(c, 0) + 1
            return f"{len(runs)}/{len(ok)}" + (" (" + ", ".join(f"{c} {k}" for c, k in sorted(chans.items(),
                                                                                           key=lambda x: -x[1])) + ")"
                                                if chans else "")

        sig_runs = [r for r in ok if r["significant"]]
        names = {}
        for r in sig_runs:
            for c in r["significant"]:
                names[c["name"]] = names.get(c["name"], 0) + 1
        sig = f"{len(sig_runs)}/{len(ok)}" + (" (" + ", ".join(f"{k} {v}" for k, v in sorted(names.items(),
                                                                                        key=lambda x: -x[1])[:4]) + ")"
                                               if names else "")
        worst = []
        for r in ok:
            for a in "xyz":
                key = f"gyro_turn_on_bias.{a}"
                truth = r["truth_turn_on"][key]
                if key in r["removed"]:
                    worst.append(abs(r["removed"][key] - truth))
        if worst:
            removed_count = sum(1 for r in ok for a in "xyz" if f"gyro_turn_on_bias.{a}" in r["removed"])
            bias = f"{removed_count}/{3 * len(ok)} axes removed, worst {max(worst) / DEG:.2g} °/s"
        else:
            bias = f"0/{3 * len(ok)} axes removed"
        headings = sorted(abs(r["import_rpy_error_deg"][2]) for r in ok if "import_rpy_error_deg" in r)
        heading = f"{headings[len(headings) // 2]:.3g}°" if headings else "—"
        nis_s = f"{nis[len(nis) // 2]:.3f} ({nis[0]:.3f}–{nis[-1]:.3f})" if nis else "—"
        band_s = f"{lows[len(lows) // 2]:.3f}–{bands[len(bands) // 2]:.3f}" if bands else "—"
        lines.append(f"| {s} | {n} | {fmt_rate(count('GOOD'), n)} | {fmt_rate(count('OPERABLE'), n)} | "
                     f"{fmt_rate(count('FAULTY'), n)} | {nis_s} | {band_s} | {above}/{len(ok)} above, {below} below | "
                     f"{early('OUTLIER')} | {early('GRADUAL')} | {sig} | {bias} | {heading} |")
        failed = [r for r in rs if r not in ok]
        if failed:
            lines.append(f"| {s}: not analysed | {len(failed)} | " + "; ".join(
                f"seed {r['seed']}: {r['verdict']}" for r in failed) + " |||||||||||")
    return "\n".join(lines)


def warm_up_table(records):
    """Per scenario with a warm-up and per sensor axis: how often the analysis
    carried one, and its start value against the truth (median ratio)."""
    lines = ["| scenario | axis | warm-up carried | start value / truth, median (min–max) | τ / truth, median |",
             "|---|---|---|---|---|"]
    for s in [s for s in SCENARIOS if any(r["scenario"] == s and r.get("truth_warmup") for r in records)]:
        rs = [r for r in records if r["scenario"] == s and r.get("warm_ups") is not None and r.get("truth_warmup")]
        for sensor, key in (("gyro", "gyro_rad_s"), ("acc", "acc_mps2")):
            for i, a in enumerate("xyz"):
                name = f"{sensor}_warm_up.{a}"
                ratios, taus = [], []
                for r in rs:
                    truth = r["truth_warmup"][key][i]
                    if name in r["warm_ups"] and truth:
                        ratios.append(r["warm_ups"][name]["value"] / truth)
                        tau = r["warm_ups"].get(name + ".tau")
                        if tau:
                            taus.append(tau["value"] / r["truth_warmup"]["tau_s"])
                ratios.sort()
                taus.sort()
                ratio = f"{ratios[len(ratios) // 2]:.2f} ({ratios[0]:.2f}–{ratios[-1]:.2f})" if ratios else "—"
                tau = f"{taus[len(taus) // 2]:.2f}" if taus else "—"
                lines.append(f"| {s} | {name} | {len(ratios)}/{len(rs)} | {ratio} | {tau} |")
    return "\n".join(lines) if len(lines) > 2 else ""


def runs(records):
    """One line per run: what the table counts, with the draws beside it."""
    lines = []
    for r in records:
        early = "; ".join(f"{e['kind']} {e['channel']} {e['start_s']:.0f}–{e['end_s']:.0f} s β² {e['beta2']:.3g}"
                          for e in r.get("early", []))
        sway = r.get("sway") or {}
        draws = f"tilt {max(abs(v) for v in r['truth_roll_pitch_rad']) / DEG:.2f}°" if "truth_roll_pitch_rad" in r else ""
        if sway:
            draws += (f", sway {sway['sway_urad']:.0f} µrad {sway['sway_hz']:.2f} Hz, settle {sway['settle_urad']:.0f} µrad "
                      f"{sway['settle_hz']:.1f} Hz τ {sway['settle_tau_s']:.1f} s")
        err = r.get("import_rpy_error_deg")
        att = f"import err r/p/y {err[0]:.4f}/{err[1]:.4f}/{err[2]:.2f}°" if err else ""
        sig = ", ".join(c["name"] for c in r.get("significant", []))
        nis = r.get("nis")
        lines.append(f"{r['scenario']} {r['seed']}: {r['verdict']} NIS {nis if nis is None else round(nis, 3)} | "
                     f"{early or '-'} | {sig or '-'} | {draws} | {att}")
    return "\n".join(lines)


def parse_seeds(text):
    if "-" in text:
        lo, hi = text.split("-")
        return list(range(int(lo), int(hi) + 1))
    if "," in text:
        return [int(v) for v in text.split(",")]
    return list(range(1, int(text) + 1))


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--seeds", default="5", help="N (seeds 1..N), LO-HI or a,b,c")
    p.add_argument("--scenarios", default=",".join(MAIN), help=f"comma-separated, of: {', '.join(SCENARIOS)}")
    p.add_argument("--out", default="real_like_sweep.jsonl")
    p.add_argument("--cli", default=os.environ.get("INSDIAG_CLI", os.path.join(ROOT, "build", "clients", "insdiag")))
    p.add_argument("--table", default=None, help="print the table of this file and stop")
    p.add_argument("--runs", default=None, help="print one line per run of this file and stop")
    p.add_argument("--keep", default=None, help="keep each run's log, truth and bench run under this directory")
    a = p.parse_args(argv)
    if a.table:
        print(table(load(a.table)))
        print(warm_up_table(load(a.table)))
        return 0
    if a.runs:
        print(runs(load(a.runs)))
        return 0
    scenarios = a.scenarios.split(",")
    for s in scenarios:
        if s not in SCENARIOS:
            p.error(f"unknown scenario {s}")
    done = {(r["scenario"], r["seed"]) for r in load(a.out)}
    for s in scenarios:
        for seed in parse_seeds(a.seeds):
            if (s, seed) in done:
                continue
            work = tempfile.mkdtemp(prefix="real-like-")
            try:
                record = one_run(a.cli, s, seed, work)
                if a.keep:
                    dest = os.path.join(a.keep, f"{s}-{seed}")
                    shutil.copytree(work, dest, dirs_exist_ok=True)
            finally:
                shutil.rmtree(work, ignore_errors=True)
            with open(a.out, "a") as f:
                f.write(json.dumps(record) + "\n")
            early = ", ".join(f"{e['kind']} {e['channel']}@{e['start_s']:.0f}s β² {e['beta2']:.3g}"
                              for e in record.get("early", []))
            print(f"{s} seed {seed}: {record['verdict']} NIS {record.get('nis', float('nan')):.3f} "
                  f"band {record.get('band')} early [{early}] significant "
                  f"{[c['name'] for c in record.get('significant', [])]} ({record.get('seconds')} s)", flush=True)
    print(table([r for r in load(a.out) if r["scenario"] in scenarios]))
    print(warm_up_table([r for r in load(a.out) if r["scenario"] in scenarios]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
