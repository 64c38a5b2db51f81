#!/usr/bin/env python3
"""A bounded load on insdiagd over loopback: concurrent uploads, analyses and
reads for a fixed time, then a check that nothing acknowledged was lost.

Starts its own insdiagd (embedded PostgreSQL in a temporary directory,
loopback ports, the first admin token) unless --server-http and --token name
one. For --seconds, --clients threads each loop over:
  - upload (40 %): a new 2-minute, 10 Hz static run as text/csv over REST,
    with a request id; one upload in ten is sent again with the same id and
    must come back as the same run;
  - analysis (10 %): an analysis of one of its own runs, with a request id;
  - read (50 %): list runs, get a run, or get an analysis.
Per operation: count, throughput, p50 / p99 latency, errors by HTTP status.

Afterwards:
  - every acknowledged upload is stored byte-exact: the server's sha256 of
    its samples (runs.proto, UploadRunRequest.sha256), in the upload's answer
    and in GET /v1/runs/{run}, is the digest of the samples sent, and the
    run downloaded as CSV holds those samples exactly (floats compared);
  - every acknowledged analysis is waited for: it must succeed, taken up by
    exactly one worker (attempts == 1).

It fails (exit 1) when an acknowledged write was lost or changed, an
analysis did not succeed exactly once, a repeated request id got another
run, or nothing at all was acknowledged. ctest runs a short load
(LoadTest.NothingAcknowledgedIsLost, label e2e: 2 clients for 5 s).

Usage:
  scripts/load_test.py [--seconds 60] [--clients 8] [--workers 1] [--insdiagd PATH] [--out results.json]
The figures in docs/RELIABILITY.md come from
  scripts/load_test.py --seconds 60 --clients 8
"""
import argparse
import hashlib
import http.client
import json
import os
import random
import socket
import statistics
import struct
import subprocess
import sys
import tempfile
import threading
import time
import uuid

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SERVER = os.path.join(ROOT, "build", "server", "insdiagd")
RATE_HZ = 10.0
DURATION_S = 120.0
G = 9.80665


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_server(server, tmp, workers):
    grpc, port = free_port(), free_port()
    data = os.path.join(tmp, "data")
    log = open(os.path.join(tmp, "insdiagd.log"), "w")
    os.chmod(tmp, 0o755)  # as root, the embedded PostgreSQL runs as `postgres`, which must reach its directory
    proc = subprocess.Popen([server, "--data-dir", data, "--grpc-port", str(grpc), "--http-port", str(port),
                             "--bind", "127.0.0.1", "--workers", str(workers), "--fleet-refresh-seconds", "0"],
                            stdout=log, stderr=subprocess.STDOUT)
    for _ in range(600):
        if proc.poll() is not None:
            log.flush()
            sys.exit(f"insdiagd exited with {proc.returncode}:\n" + open(log.name).read()[-2000:])
        try:
            with socket.create_connection(("127.0.0.1", port), timeout=1):
                with open(os.path.join(data, "admin-token")) as f:
                    return proc, port, f.read().strip()
        except OSError:
            time.sleep(0.5)
    proc.kill()
    sys.exit("insdiagd did not start")


def synthetic_run(rng, serial):
    """A level, static unit: Earth rate and gravity plus white noise. Returns (csv text, samples)."""
    lines = ["# format: insdiag-bench-run/1", f"# unit_serial: {serial}", "# site_latitude_deg: 55.5672",
             "# site_longitude_deg: 38.15", "# site_height_m: 125.0",
             "t,gyro_x,gyro_y,gyro_z,acc_x,acc_y,acc_z,ref_roll,ref_pitch,ref_yaw"]
    earth_n, earth_d = 7.292115e-5 * 0.5659, -7.292115e-5 * 0.8244
    samples = []
    for k in range(int(DURATION_S * RATE_HZ)):
        row = [k / RATE_HZ, earth_n + rng.gauss(0, 1e-6), rng.gauss(0, 1e-6), earth_d + rng.gauss(0, 1e-6),
               rng.gauss(0, 1e-4), rng.gauss(0, 1e-4), -G + rng.gauss(0, 1e-4), 0.0, 0.0, 0.0]
        samples.append(row)
        lines.append(",".join(repr(v) for v in row))
    return "\n".join(lines) + "\n", samples


class Client:
    def __init__(self, port, token):
        self.port, self.token = port, token
        self.conn = http.client.HTTPConnection("127.0.0.1", port, timeout=120)

    def call(self, method, path, body=None, content_type="application/json"):
        headers = {"Authorization": f"Bearer {self.token}"}
        if body is not None:
            headers["Content-Type"] = content_type
        for attempt in range(2):
            try:
                self.conn.request(method, path, body=body, headers=headers)
                response = self.conn.getresponse()
                return response.status, response.read()
            except (http.client.HTTPException, OSError):
                self.conn.close()
                self.conn = http.client.HTTPConnection("127.0.0.1", self.port, timeout=120)
                if attempt == 1:
                    return 0, b""


class Load:
    def __init__(self, port, token, seconds, seed):
        self.port, self.token, self.seconds, self.seed = port, token, seconds, seed
        self.lock = threading.Lock()
        self.latency = {}   # operation -> [seconds]
        self.errors = {}    # (operation, status) -> count
        self.uploads = []   # (run name, samples)
        self.analyses = set()
        self.idempotency_failures = 0

    def record(self, op, seconds, status):
        with self.lock:
            self.latency.setdefault(op, []).append(seconds)
            if status != 200:
                self.errors[(op, status)] = self.errors.get((op, status), 0) + 1

    def worker(self, index):
        rng = random.Random(self.seed * 1000 + index)
        client = Client(self.port, self.token)
        mine = []
        end = time.monotonic() + self.seconds
        while time.monotonic() < end:
            roll = rng.random()
            if roll < 0.4 or not mine:
                text, samples = synthetic_run(rng, f"LOAD-{index}-{len(mine)}")
                request_id = str(uuid.uuid4())
                path = f"/v1/runs:upload?requestId={request_id}"
                t0 = time.monotonic()
                status, body = client.call("POST", path, text.encode(), "text/csv")
                self.record("upload", time.monotonic() - t0, status)
                if status != 200:
                    continue
                run = json.loads(body)
                name = run["name"]
                mine.append(name)
                with self.lock:
                    self.uploads.append((name, samples, run.get("sha256")))
                if rng.random() < 0.1:  # the same upload again: the same run
                    t0 = time.monotonic()
                    status, again = client.call("POST", path, text.encode(), "text/csv")
                    self.record("upload (repeated id)", time.monotonic() - t0, status)
                    if status != 200 or json.loads(again)["name"] != name:
                        with self.lock:
                            self.idempotency_failures += 1
            elif roll < 0.5:
                body = json.dumps({"run": rng.choice(mine)})
                t0 = time.monotonic()
                status, answer = client.call("POST", f"/v1/analyses?requestId={uuid.uuid4()}", body)
                self.record("analysis", time.monotonic() - t0, status)
                if status == 200:
                    with self.lock:
                        self.analyses.add(json.loads(answer)["name"])
            else:
                choice = rng.random()
                if choice < 0.4:
                    op, path = "list runs", "/v1/runs?pageSize=20"
                elif choice < 0.8 or not self.analyses:
                    op, path = "get run", f"/v1/{rng.choice(mine)}"
                else:
                    with self.lock:
                        analysis = rng.choice(sorted(self.analyses))
                    op, path = "get analysis", f"/v1/{analysis}"
                t0 = time.monotonic()
                status, _ = client.call("GET", path)
                self.record(op, time.monotonic() - t0, status)


def sample_sha256(samples):
    """The digest of runs.proto's UploadRunRequest.sha256: each sample's ten
    fields (no temperature column here) as little-endian binary64, in order."""
    digest = hashlib.sha256()
    for row in samples:
        digest.update(struct.pack("<10d", *row))
    return digest.hexdigest()


def check_uploads(port, token, uploads):
    client = Client(port, token)
    lost = 0
    for name, sent, acknowledged_sha256 in uploads:
        expected = sample_sha256(sent)
        status, body = client.call("GET", f"/v1/{name}")
        if status != 200 or acknowledged_sha256 != expected or json.loads(body).get("sha256") != expected:
            lost += 1
            continue
        status, body = client.call("GET", f"/v1/{name}:download")
        if status != 200:
            lost += 1
            continue
        rows = [line for line in body.decode().splitlines() if line and not line.startswith("#")][1:]
        stored = [[float(v) for v in row.split(",")] for row in rows]
        if stored != sent:
            lost += 1
    return lost


def check_analyses(port, token, names, timeout_s):
    client = Client(port, token)
    pending, bad = set(names), []
    deadline = time.monotonic() + timeout_s
    while pending and time.monotonic() < deadline:
        for name in sorted(pending):
            status, body = client.call("GET", f"/v1/{name}")
            if status != 200:
                continue
            a = json.loads(body)
            if a["state"] in ("SUCCEEDED", "FAILED", "CANCELLED"):
                pending.discard(name)
                if a["state"] != "SUCCEEDED" or int(a.get("attempts", 0)) != 1:
                    bad.append((name, a["state"], a.get("attempts")))
        time.sleep(1.0)
    return bad, sorted(pending)


def percentile(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--clients", type=int, default=8)
    parser.add_argument("--workers", type=int, default=1, help="analysis workers of the server this script starts")
    parser.add_argument("--insdiagd", default=SERVER, help="the server this script starts (default: build/'s)")
    parser.add_argument("--server-http", type=int, help="the HTTP port of a running insdiagd (with --token)")
    parser.add_argument("--token", help="an OPERATOR token of that server")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--out")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="insdiag-load-") as tmp:
        proc = None
        if args.server_http:
            port, token = args.server_http, args.token
        else:
            proc, port, token = start_server(args.insdiagd, tmp, args.workers)
        try:
            load = Load(port, token, args.seconds, args.seed)
            threads = [threading.Thread(target=load.worker, args=(i,)) for i in range(args.clients)]
            started = time.monotonic()
            for t in threads:
                t.start()
            for t in threads:
                t.join()
            elapsed = time.monotonic() - started
            lost = check_uploads(port, token, load.uploads)
            bad, unfinished = check_analyses(port, token, load.analyses, timeout_s=600)
        finally:
            if proc:
                proc.terminate()
                proc.wait(60)
    print(f"{args.clients} clients, {elapsed:.0f} s, loopback\n")
    print("| operation | count | per second | p50 (ms) | p99 (ms) | errors |")
    print("|---|---|---|---|---|---|")
    for op, values in sorted(load.latency.items()):
        errors = sum(n for (o, _), n in load.errors.items() if o == op)
        print(f"| {op} | {len(values)} | {len(values) / elapsed:.1f} | {1000 * statistics.median(values):.0f} | "
              f"{1000 * percentile(values, 0.99):.0f} | {errors} |")
    print(f"\nacknowledged uploads: {len(load.uploads)}; not stored byte-exact (sha256 and samples): {lost}")
    print(f"repeated request ids answered with another run: {load.idempotency_failures}")
    print(f"acknowledged analyses: {len(load.analyses)}; not succeeded exactly once: {len(bad)}; "
          f"unfinished after 600 s: {len(unfinished)}")
    if load.errors:
        print("errors by status:", {f"{o} {s}": n for (o, s), n in load.errors.items()})
    if args.out:
        with open(args.out, "w") as f:
            json.dump({"latency": load.latency, "lost": lost, "bad": bad, "unfinished": unfinished}, f)
    if not load.uploads or not load.analyses:
        print("nothing was acknowledged: the load proves nothing")
        return 1
    return 1 if lost or bad or unfinished or load.idempotency_failures else 0


if __name__ == "__main__":
    sys.exit(main())
