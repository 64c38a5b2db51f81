#!/usr/bin/env python3
"""The diagnosis's first module over seeds, through a real server: `insdiag diagnose`.

Starts insdiagd on loopback ports with its own embedded PostgreSQL in a
temporary directory (the knowledge base holds the built-in unit types and
failure modes), simulates each run on both simulators as
scripts/fault_matrix.py does, diagnoses it, and prints per scenario and
simulator how often the first-ranked module is the right one.

  drift_sigma_x3_long  one gyro's drift σ × 3 (axis from the seed), no
                       datasheet, unit type INS-2000, 4 h of a multi-position
                       drift test with tilted positions (cpp: the `drift`
                       profile's first 4 h; py: `positions`), 10 or 50 Hz.
                       Right: the first module is that gyro's.
  drift_sigma_x3_8h    the same over 8 h (cpp: the whole `drift` profile;
                       py: `positions`), as the eight-hour runs of the
                       report that opened the faults issue.
  gyro_step, acc_step  a bias jump on one sensor axis (axis, sign and onset
                       in 30–80 % of the run from the seed) of 5 to 100 drift
                       σ (log-uniform: faults come in every size), 1 h,
                       datasheet, rates and profiles as `healthy`. Right: the
                       first module is that sensor axis's (gyro.x, acc.z, …).
  gyro_ramp, acc_ramp  a bias ramp from an onset in 20–60 % of the run,
                       reaching 5 to 100 drift σ in 1000 s; otherwise as the
                       jumps.
  healthy              1 h, datasheet, rates 10/50/100 Hz, three profiles a
                       simulator (the project's ramps its rate changes, the
                       independent one makes them instantaneous). Right: the
                       first module is `healthy`.

On healthy runs it also estimates, by maximum likelihood over the pooled
evidence terms, the share ε₀ of terms a healthy unit puts off nominal: the
mixture (1 − ε₀) N(0, s_h² + s_m²) + ε₀ Cauchy(0, √(b² + s_m²)) of
docs/DIAGNOSIS.md, with its 95 % profile-likelihood interval. The catalogue's
`incidentalContamination` is that estimate.

The binaries are the build's, or $INSDIAG_CLI and $INSDIAGD (copies, so that
a rebuild during a sweep does not pull them from under it).

Usage:
  scripts/diagnosis_sweep.py [--runs N] [--first-index I] [--scenarios a,b] [--simulators cpp,py] [--out results.json]
The figures in docs/FAULT_SCENARIOS.md come from
  scripts/diagnosis_sweep.py --runs 5 --scenarios drift_sigma_x3_long
  scripts/diagnosis_sweep.py --runs 6 --scenarios healthy
"""
import argparse
import importlib.util
import json
import math
import os
import random
import socket
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location("fault_matrix", os.path.join(HERE, "fault_matrix.py"))
matrix = importlib.util.module_from_spec(spec)
spec.loader.exec_module(matrix)

SERVER = os.environ.get("INSDIAGD", os.path.join(matrix.ROOT, "build", "server", "insdiagd"))
# The drift scenarios' durations.
LONG_S = {"drift_sigma_x3_long": 4 * 3600.0, "drift_sigma_x3_8h": 8 * 3600.0}


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(data_dir):
    grpc, http = free_port(), free_port()
    log = open(os.path.join(os.path.dirname(data_dir), "insdiag-diagnosis-sweep-server.log"), "w")
    proc = subprocess.Popen([SERVER, "--data-dir", os.path.join(data_dir, "pg"), "--grpc-port", str(grpc),
                             "--http-port", str(http), "--bind", "127.0.0.1", "--workers", "1",
                             "--fleet-refresh-seconds", "0"], stdout=log, stderr=subprocess.STDOUT)
    for _ in range(600):
        if proc.poll() is not None:
            sys.exit(f"insdiagd exited with {proc.returncode}; see {log.name}")
        try:
            with socket.create_connection(("127.0.0.1", grpc), timeout=1):
                # The server's first start on its new database wrote an admin token.
                with open(os.path.join(data_dir, "pg", "admin-token")) as f:
                    return proc, (f"127.0.0.1:{grpc}", f.read().strip())
        except OSError:
            time.sleep(0.5)
    proc.kill()
    sys.exit("insdiagd did not start")


def make_run(simulator, scenario, index, path):
    """Simulates one run; returns what was hidden (axis or None) and how."""
    rng = random.Random(f"{simulator}/{scenario}/{index}")
    seed = 2000 + index
    if scenario == "healthy":
        rate = matrix.RATES_HZ[index % 3]
        profile = matrix.PROFILES[simulator][(index // 3) % 3]
        fault = dict(kind=None)
        matrix.simulate(simulator, fault, rate, profile, seed, 3600.0, path)
        if simulator == "cpp":
            matrix.truncate(path, 3600.0)
        return dict(axis=None, rate_hz=rate, profile=profile)
    if scenario in ("gyro_step", "acc_step", "gyro_ramp", "acc_ramp"):
        sensor, shape = scenario.split("_")
        rate = matrix.RATES_HZ[index % 3]
        profile = matrix.PROFILES[simulator][(index // 3) % 3]
        fault = (matrix.step if shape == "step" else matrix.ramp)(sensor)(rng, 3600.0)
        fault["value"] *= math.exp(rng.uniform(0.0, math.log(20.0)))  # 5 to 100 drift σ
        matrix.simulate(simulator, fault, rate, profile, seed, 3600.0, path)
        if simulator == "cpp":
            matrix.truncate(path, 3600.0)
        # A ramp's size: what it reaches in 1000 s.
        size = abs(fault["value"]) * (1.0 if shape == "step" else 1000.0) / matrix.drift_sigma(sensor, fault["axis"])
        return dict(axis=fault["axis"], sensor=sensor, rate_hz=rate, profile=profile,
                    fault=f"{fault['name']} of {size:.0f} drift σ at {fault['onset_s']:.0f} s")
    axis = rng.choice(matrix.AXES)
    rate = [10.0, 50.0][index % 2]
    name = f"gyro_bias_gm.{axis}.sigma"
    if simulator == "cpp":
        cmd = [matrix.CLI, "simulate", path, "--profile", "drift", "--rate", f"{rate:g}", "--seed", str(seed),
               "--no-datasheet", "--param", f"{name}={matrix.NOMINAL[name] * 3.0:.6g}"]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        matrix.truncate(path, LONG_S[scenario])
        profile = f"drift (first {LONG_S[scenario] / 3600:g} h)"
    else:
        cmd = [matrix.PYTHON, matrix.BENCHSIM, "--out", path, "--preset", "nav", "--profile", "positions",
               "--rate-hz", f"{rate:g}", "--duration", f"{LONG_S[scenario]:g}", "--seed", str(seed), "--datasheet", "no",
               "--unit-type", "INS-2000", "--fault", f"{name}*3"]
        subprocess.run(cmd, check=True, capture_output=True, text=True)
        profile = "positions"
    return dict(axis=axis, rate_hz=rate, profile=profile)


def diagnose(server, path):
    address, token = server
    done = subprocess.run([matrix.CLI, "diagnose", path, "--json", "--server", address, "--token", token],
                          capture_output=True, text=True)
    if done.returncode != 0:
        return None, done.stderr.strip()[-300:]
    return json.loads(done.stdout), None


def modules(diagnosis):
    """The diagnosis's candidates: (module, probability), most probable first
    (`healthy` and `unknown` are candidates too)."""
    ranked = [(c.get("module"), c.get("probability", 0.0)) for c in diagnosis.get("candidates", [])]
    return sorted(ranked, key=lambda x: -x[1])


def judge(scenario, hidden, diagnosis):
    ranked = modules(diagnosis)
    first, probability = ranked[0] if ranked else (None, 0.0)
    right_module = "healthy" if scenario == "healthy" else f"{hidden.get('sensor', 'gyro')}.{hidden['axis']}"
    return dict(first=first, probability=probability, right=first == right_module,
                right_probability=dict(ranked).get(right_module, 0.0), ranked=ranked[:4],
                evidence=diagnosis.get("evidence", []))


def incidental_share(results):
    """ML estimate and 95 % profile-likelihood interval of ε₀ over the healthy
    runs' pooled evidence terms (None when there are none)."""
    with open(os.path.join(matrix.ROOT, "data", "failure-modes", "INS-2000.json")) as f:
        settings = json.load(f)["settings"]
    broad = {"log_ratio": settings["broadLogRatio"], "tolerance": settings["broadTolerance"],
             "z": settings["broadZ"]}
    normal, cauchy = [], []
    for r in results:
        if r["scenario"] != "healthy" or "error" in r:
            continue
        for t in r["evidence"]:
            x, sm, sh = t.get("value", 0.0), t.get("measurementSd", 0.0), t.get("healthySd", 0.0)
            var = sh * sh + sm * sm
            normal.append(-0.5 * (math.log(2 * math.pi * var) + x * x / var))
            c = math.sqrt(broad[t.get("scale", "z")] ** 2 + sm * sm)
            cauchy.append(-math.log(math.pi * c * (1 + (x / c) ** 2)))
    if not normal:
        return None

    def loglik(eps):
        return sum(math.log((1 - eps) * math.exp(n) + eps * math.exp(c)) for n, c in zip(normal, cauchy))

    grid = [0.0] + [10 ** (k / 50) for k in range(-250, -25)]  # 1e-5 … 0.3
    values = [loglik(e) for e in grid]
    best = max(range(len(grid)), key=lambda i: values[i])
    inside = [grid[i] for i in range(len(grid)) if 2 * (values[best] - values[i]) <= 3.84]
    return dict(terms=len(normal), estimate=grid[best], low=min(inside), high=max(inside))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--first-index", type=int, default=0,
                        help="the first run's index (seeds and axes follow it): to extend an earlier sweep")
    parser.add_argument("--scenarios", default="drift_sigma_x3_long,healthy")
    parser.add_argument("--simulators", default="cpp,py")
    parser.add_argument("--out", default=None)
    args = parser.parse_args()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        os.chmod(tmp, 0o755)  # run as root, the embedded PostgreSQL runs as `postgres` and must enter it
        proc, server = start_server(tmp)
        try:
            for scenario in args.scenarios.split(","):
                for simulator in args.simulators.split(","):
                    for index in range(args.first_index, args.first_index + args.runs):
                        path = os.path.join(tmp, "run.csv")
                        hidden = make_run(simulator, scenario, index, path)
                        started = time.monotonic()
                        diagnosis, error = diagnose(server, path)
                        r = dict(scenario=scenario, simulator=simulator, index=index, **hidden,
                                 seconds=round(time.monotonic() - started, 1))
                        r.update(dict(error=error) if error else judge(scenario, hidden, diagnosis))
                        results.append(r)
                        print(json.dumps(r), file=sys.stderr, flush=True)
        finally:
            proc.terminate()
            proc.wait(timeout=60)
    if args.out:
        with open(args.out, "w") as f:
            json.dump(results, f, indent=1)
    print("| scenario | simulator | runs | first module right | its probability (median) | the right module's probability where it is not first |")
    print("|---|---|---|---|---|---|")
    groups = {}
    for r in results:
        groups.setdefault((r["scenario"], r["simulator"]), []).append(r)
    for (scenario, simulator), rs in groups.items():
        ok = [r for r in rs if "error" not in r]
        p = sorted(r["probability"] for r in ok)
        median = f"{p[len(p) // 2]:.3f}" if p else "—"
        failed = len(rs) - len(ok)
        missed = ", ".join(f"{r['right_probability']:.2f}" for r in ok if not r["right"]) or "—"
        print(f"| {scenario} | {simulator} | {len(ok)}{f' ({failed} failed)' if failed else ''} | "
              f"{sum(r['right'] for r in ok)} | {median} | {missed} |")
    share = incidental_share(results)
    if share:
        print(f"\nhealthy units' share of evidence terms off nominal, ε₀: {share['estimate']:.2g} "
              f"(95 % interval {share['low']:.2g} – {share['high']:.2g}, {share['terms']} terms)")


if __name__ == "__main__":
    main()
