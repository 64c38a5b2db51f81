#!/usr/bin/env python3
"""What the page's Add costs on a server, measured on this machine
(docs/PERFORMANCE.md, "An Add on the server").

Starts an insdiagd of its own (embedded PostgreSQL in a temporary
directory, loopback only, one worker), uploads RUN.csv, analyses it (model
A), then asks for the Adds the page would send (`baseAnalysis` and one
effect each), one at a time, --pause seconds after the last ended, each
from model A or (--chain) from the Add before it. Prints each job's time from claim to end (the
server's insdiag_analysis_duration_seconds) and what the client waited from
POST to SUCCEEDED.

Usage: scripts/add_latency.py RUN.csv [--effects E1,E2,...] [--chain] [--cache-mb N] [--pause S] [--build-dir DIR]
"""
import argparse
import http.client
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import uuid

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from scaling_benchmark import call  # noqa: E402


def job_seconds(server, token):
    """The sum of every succeeded job's claim-to-end time so far, and their count."""
    status, body = call(server(), token, "GET", "/metrics")
    assert status == 200, body
    total, count = 0.0, 0
    for line in body.decode().splitlines():
        m = re.match(r'insdiag_analysis_duration_seconds_(sum|count)\{outcome="succeeded"\} ([0-9.e+-]+)', line)
        if m and m.group(1) == "sum":
            total = float(m.group(2))
        elif m:
            count = int(float(m.group(2)))
    return total, count


def analyse(server, token, analysis):
    """Queues `analysis`, waits for it; (client wait s, job s, name)."""
    before = job_seconds(server, token)
    start = time.monotonic()
    status, body = call(server(), token, "POST", "/v1/analyses", json.dumps(analysis))
    assert status == 200, body
    name = json.loads(body)["name"]
    conn = server()
    while True:
        status, body = call(conn, token, "GET", f"/v1/{name}")
        state = json.loads(body)["state"]
        if state == "SUCCEEDED":
            break
        if state in ("FAILED", "CANCELLED"):
            sys.exit(f"{name} {state}: {body[:2000]}")
        time.sleep(0.01)
    waited = time.monotonic() - start
    # The job's duration is counted just after its state is written.
    after = job_seconds(server, token)
    while after[1] == before[1]:
        time.sleep(0.01)
        after = job_seconds(server, token)
    return waited, after[0] - before[0], name


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run")
    parser.add_argument("--effects", default="gyro_scale_factor.z,gyro_scale_factor.x,acc_scale_factor.z")
    parser.add_argument("--cache-mb", type=int, default=None, help="--analysis-cache-mb (default: the server's)")
    parser.add_argument("--chain", action="store_true",
                        help="each Add from the one before (its baseline then holds the effects added so far)")
    parser.add_argument("--pause", type=float, default=2.0,
                        help="seconds between an analysis ending and the next Add: the user reading the report")
    parser.add_argument("--build-dir", default=os.path.join(ROOT, "build"))
    args = parser.parse_args()
    work = tempfile.mkdtemp(prefix="insdiag-add-")
    os.chmod(work, 0o755)  # the embedded PostgreSQL runs as its own user when started as root
    log = open(os.path.join(work, "insdiagd.log"), "w")
    command = [f"{args.build_dir}/server/insdiagd", "--data-dir", os.path.join(work, "data"), "--grpc-port", "0",
               "--http-port", "0", "--bind", "127.0.0.1", "--workers", "1", "--fleet-refresh-seconds", "0"]
    if args.cache_mb is not None:
        command += ["--analysis-cache-mb", str(args.cache_mb)]
    server = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=log, text=True)
    try:
        line = server.stdout.readline()
        if "listening" not in line:
            sys.exit(f"insdiagd did not start: {open(log.name).read()[-2000:]}")
        port = int(line.split(" http=")[1].split()[0].rsplit(":", 1)[1])
        token = open(os.path.join(work, "data", "admin-token")).read().strip()
        # A connection a request: the server closes one left idle (keep-alive).
        def connection():
            return http.client.HTTPConnection("127.0.0.1", port, timeout=600)

        status, body = call(connection(), token, "POST", f"/v1/runs:upload?requestId={uuid.uuid4()}",
                            open(args.run, "rb").read(), "text/csv")
        assert status == 200, body
        run = json.loads(body)["name"]
        waited, job, base = analyse(connection, token, {"run": run})
        print(f"model A      job {job:6.2f} s  waited {waited:6.2f} s")
        for effect in args.effects.split(","):
            time.sleep(args.pause)
            waited, job, name = analyse(connection, token,
                                        {"run": run, "baseAnalysis": base, "model": {"effects": [effect]}})
            if args.chain:
                base = name
            print(f"add {effect:<22} job {job:6.2f} s  waited {waited:6.2f} s", flush=True)
    finally:
        server.terminate()
        server.wait(120)
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    main()
