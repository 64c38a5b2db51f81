#!/usr/bin/env python3
"""How insdiag scales past one server process, measured on this machine
(docs/ARCHITECTURE.md, "Past one machine"). A few minutes, loopback only.

Sets up a PostgreSQL primary and its streaming replica of its own (unix
sockets only, in a temporary directory), then:

1. The job queue shared: --analyses identical analyses queued through an
   API-only insdiagd (--workers 0), then drained by one insdiagd with one
   worker, and on a fresh database by two insdiagd with one worker each.
   Reported: the makespan (first claim to last end, from the analyses'
   own start and end times), jobs a minute, the worker processes that took
   jobs, and that every job succeeded with one attempt.
2. Fleet reads on the primary and on the replica: a generated fleet
   (insdiag-fleet, --units), then for --seconds each, one insdiagd at a
   time taking an upload load (2 clients, 1,200-sample runs as text/csv)
   and fleet queries (2 clients: statistics, Pareto, ranking, failure
   counts, Weibull), first reading from the primary, then with
   --read-database-url on the replica. Reported: fleet queries and uploads
   a second with p50 / p99, and the CPU seconds the primary's PostgreSQL
   spent in each phase.

Usage: scripts/scaling_benchmark.py [--analyses 12] [--units 300] [--seconds 20] [--build-dir DIR]
"""
import argparse
import glob
import http.client
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import uuid

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "scripts"))
from load_test import free_port, percentile, synthetic_run  # noqa: E402

FLEET_QUERIES = ["/v1/fleetStatistics", "/v1/fleet/pareto", "/v1/fleet/unitRanking?pageSize=50",
                 "/v1/fleet/failureCounts?period=month", "/v1/fleet/weibull?moduleRole=gyro.x"]


class Clusters:
    """A primary and its streaming replica, owned by `postgres` when run as root."""

    def __init__(self, work):
        self.work = work
        self.bin = sorted(glob.glob("/usr/lib/postgresql/*/bin"))[-1]
        self.as_owner = ["runuser", "-u", "postgres", "--"] if os.getuid() == 0 else []
        if os.getuid() == 0:
            shutil.chown(work, "postgres")
        self.ports = {"primary": free_port(), "replica": free_port()}
        self.pg("initdb", "-D", f"{work}/primary", "--no-sync", "-A", "trust", "-U", "postgres", "-E", "UTF8")
        self.start("primary")
        self.pg("pg_basebackup", "-h", work, "-p", str(self.ports["primary"]), "-U", "postgres",
                "-D", f"{work}/replica", "-R", "-X", "stream", "-c", "fast")
        self.start("replica")

    def pg(self, tool, *args):
        subprocess.run(self.as_owner + [f"{self.bin}/{tool}", *args], check=True, stdout=subprocess.DEVNULL)

    def start(self, name):
        self.pg("pg_ctl", "-D", f"{self.work}/{name}", "-w", "-l", f"{self.work}/{name}.log",
                "-o", f"-c listen_addresses='' -k {self.work} -p {self.ports[name]}", "start")

    def stop(self):
        for name in ("replica", "primary"):
            subprocess.run(self.as_owner + [f"{self.bin}/pg_ctl", "-D", f"{self.work}/{name}", "-m", "fast",
                                            "stop"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def url(self, name, database):
        return f"postgresql://postgres@/{database}?host={self.work}&port={self.ports[name]}"

    def sql(self, name, database, statement):
        done = subprocess.run(self.as_owner + [f"{self.bin}/psql", "-X", "-q", "-A", "-t", "-h", self.work,
                                               "-p", str(self.ports[name]), "-U", "postgres", "-d", database,
                                               "-c", statement], check=True, capture_output=True, text=True)
        return done.stdout.strip()

    def primary_cpu_s(self):
        """CPU seconds of the primary's postmaster and its backends, those
        that ended included (reaped into the postmaster's children's times)."""
        with open(f"{self.work}/primary/postmaster.pid") as f:
            postmaster = int(f.readline())
        ticks = os.sysconf("SC_CLK_TCK")

        def times(pid, with_children):
            try:
                fields = open(f"/proc/{pid}/stat").read().rsplit(")", 1)[1].split()
            except OSError:
                return 0
            own = int(fields[11]) + int(fields[12])
            return own + (int(fields[13]) + int(fields[14]) if with_children else 0)

        total = times(postmaster, True)
        for entry in os.listdir("/proc"):
            if entry.isdigit():
                try:
                    if int(open(f"/proc/{entry}/stat").read().rsplit(")", 1)[1].split()[1]) == postmaster:
                        total += times(int(entry), False)
                except OSError:
                    pass
        return total / ticks

    def wait_replayed(self, database):
        lsn = self.sql("primary", database, "SELECT pg_current_wal_lsn()")
        for _ in range(600):
            if self.sql("replica", database, f"SELECT pg_last_wal_replay_lsn() >= '{lsn}'::pg_lsn") == "t":
                return
            time.sleep(0.1)
        sys.exit("the replica did not catch up within 60 s")


class Server:
    def __init__(self, build, work, name, args):
        self.data = os.path.join(work, name)
        os.makedirs(self.data)
        self.out = open(os.path.join(work, name + ".log"), "w")
        self.proc = subprocess.Popen([f"{build}/server/insdiagd", "--data-dir", self.data, "--grpc-port", "0",
                                      "--http-port", "0", "--bind", "127.0.0.1", "--fleet-refresh-seconds", "0",
                                      *args], stdout=subprocess.PIPE, stderr=self.out, text=True)
        line = self.proc.stdout.readline()  # "insdiagd: listening grpc=…:N http=…:M …"
        if "listening" not in line:
            sys.exit(f"insdiagd {name} did not start: {open(self.out.name).read()[-2000:]}")
        self.http = int(line.split(" http=")[1].split()[0].rsplit(":", 1)[1])

    def stop(self):
        self.proc.terminate()
        self.proc.wait(120)


def call(conn, token, method, path, body=None, content_type="application/json"):
    headers = {"Authorization": f"Bearer {token}"}
    if body is not None:
        headers["Content-Type"] = content_type
    conn.request(method, path, body=body, headers=headers)
    answer = conn.getresponse()
    return answer.status, answer.read()


def drain_queue(clusters, build, work, processes, analyses):
    database = f"queue{processes}"
    clusters.sql("primary", "postgres", f"CREATE DATABASE {database}")
    url = clusters.url("primary", database)
    api = Server(build, work, f"api{processes}", ["--database-url", url, "--workers", "0"])
    token = open(os.path.join(api.data, "admin-token")).read().strip()
    csv = os.path.join(work, "queue-run.csv")
    if not os.path.exists(csv):
        subprocess.run([f"{build}/clients/insdiag", "simulate", csv, "--profile", "rotations", "--rate", "20",
                        "--seed", "21", "--serial", "SCALE-1"], check=True, stdout=subprocess.DEVNULL)
    conn = http.client.HTTPConnection("127.0.0.1", api.http, timeout=120)
    status, body = call(conn, token, "POST", f"/v1/runs:upload?requestId={uuid.uuid4()}", open(csv, "rb").read(),
                        "text/csv")
    assert status == 200, body
    run = json.loads(body)["name"]
    for _ in range(analyses):
        status, body = call(conn, token, "POST", "/v1/analyses", json.dumps({"run": run}))
        assert status == 200, body
    workers = [Server(build, work, f"worker{processes}-{i}", ["--database-url", url, "--workers", "1"])
               for i in range(processes)]
    owners = set()
    deadline = time.monotonic() + 1800
    while time.monotonic() < deadline:
        running = clusters.sql("primary", database, "SELECT string_agg(lease_owner, ' ') FROM analyses "
                                                    "WHERE state = 'RUNNING'")
        owners.update(o.rsplit(":", 1)[0] for o in running.split())
        if clusters.sql("primary", database, "SELECT count(*) FROM analyses WHERE state IN ('QUEUED', 'RUNNING')") == "0":
            break
        time.sleep(0.2)
    for server in workers + [api]:
        server.stop()
    makespan, succeeded_once, total = clusters.sql(
        "primary", database, "SELECT extract(epoch FROM max(end_time) - min(start_time)), "
                             "count(*) FILTER (WHERE state = 'SUCCEEDED' AND attempts = 1), count(*) FROM analyses"
    ).split("|")
    return {"processes": processes, "makespan_s": float(makespan), "succeeded_once": int(succeeded_once),
            "analyses": int(total), "claiming_processes": len(owners)}


def mixed_load(server, token, seconds):
    """Uploads and fleet queries against one server for `seconds`."""
    latencies = {"upload": [], "fleet query": []}
    errors = {"upload": 0, "fleet query": 0}
    lock = threading.Lock()
    end = time.monotonic() + seconds

    def client(kind, index):
        rng = random.Random(index)
        conn = http.client.HTTPConnection("127.0.0.1", server.http, timeout=120)
        n = 0
        while time.monotonic() < end:
            if kind == "upload":
                text, _ = synthetic_run(rng, f"SCALE-LOAD-{index}-{n}")
                args = ("POST", f"/v1/runs:upload?requestId={uuid.uuid4()}", text.encode(), "text/csv")
            else:
                args = ("GET", FLEET_QUERIES[n % len(FLEET_QUERIES)])
            n += 1
            t0 = time.monotonic()
            status, _ = call(conn, token, *args)
            with lock:
                latencies[kind].append(time.monotonic() - t0)
                errors[kind] += status != 200

    threads = [threading.Thread(target=client, args=(kind, i)) for i, kind in
               enumerate(["upload", "upload", "fleet query", "fleet query"])]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    return latencies, errors


def fleet_reads(clusters, build, work, units, seconds):
    url = clusters.url("primary", "fleet")
    clusters.sql("primary", "postgres", "CREATE DATABASE fleet")
    primary_reader = Server(build, work, "primary-reads", ["--database-url", url, "--workers", "0"])
    token = open(os.path.join(primary_reader.data, "admin-token")).read().strip()
    started = time.monotonic()
    subprocess.run([f"{build}/tools/insdiag-fleet", "--database-url", url, "--units", str(units), "--seed", "1",
                    "--end-time", "2025-06-01"], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    generated_s = time.monotonic() - started
    clusters.wait_replayed("fleet")
    rows = clusters.sql("primary", "fleet", "SELECT (SELECT count(*) FROM units) || ' ' || (SELECT count(*) FROM analyses)")
    results = {"fleet": rows, "generated_s": generated_s}
    replica_reader = None
    for where in ("primary", "replica"):
        if where == "replica":
            primary_reader.stop()
            replica_reader = Server(build, work, "replica-reads", ["--database-url", url, "--read-database-url",
                                                                   clusters.url("replica", "fleet"), "--workers", "0"])
        server = primary_reader if where == "primary" else replica_reader
        cpu0 = clusters.primary_cpu_s()
        latencies, errors = mixed_load(server, token, seconds)
        results[where] = {"latencies": latencies, "errors": errors, "primary_cpu_s": clusters.primary_cpu_s() - cpu0}
    replica_reader.stop()
    return results


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--analyses", type=int, default=12)
    parser.add_argument("--units", type=int, default=300)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--build-dir", default=os.path.join(ROOT, "build"))
    args = parser.parse_args()
    build = os.path.abspath(args.build_dir)
    work = tempfile.mkdtemp(prefix="insdiag-scaling-")
    os.chmod(work, 0o755)
    clusters = Clusters(work)
    try:
        queue = [drain_queue(clusters, build, work, n, args.analyses) for n in (1, 2)]
        reads = fleet_reads(clusters, build, work, args.units, args.seconds)
    finally:
        clusters.stop()
        shutil.rmtree(work, ignore_errors=True)

    print(f"{os.cpu_count()} cores; one PostgreSQL primary and its streaming replica on this machine\n")
    print(f"Job queue: {args.analyses} analyses (a 20 Hz rotations run, simulated), one worker per insdiagd\n")
    print("| insdiagd | makespan (s) | analyses a minute | processes that claimed jobs | succeeded with one attempt |")
    print("|---|---|---|---|---|")
    for q in queue:
        print(f"| {q['processes']} | {q['makespan_s']:.1f} | {60 * q['analyses'] / q['makespan_s']:.1f} | "
              f"{q['claiming_processes']} | {q['succeeded_once']} of {q['analyses']} |")
    units, analyses = reads["fleet"].split()
    print(f"\nFleet reads under an upload load: a fleet of {units} units and {analyses} analyses "
          f"(generated in {reads['generated_s']:.0f} s), {args.seconds:.0f} s a phase, "
          "2 upload and 2 fleet-query clients\n")
    print("| reads from | fleet queries/s | p50 (ms) | p99 (ms) | uploads/s | p50 (ms) | p99 (ms) | errors | "
          "primary's PostgreSQL CPU (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for where in ("primary", "replica"):
        r = reads[where]
        q, u = r["latencies"]["fleet query"], r["latencies"]["upload"]
        print(f"| {where} | {len(q) / args.seconds:.1f} | {1000 * percentile(q, 0.5):.0f} | "
              f"{1000 * percentile(q, 0.99):.0f} | {len(u) / args.seconds:.1f} | {1000 * percentile(u, 0.5):.0f} | "
              f"{1000 * percentile(u, 0.99):.0f} | {sum(r['errors'].values())} | {r['primary_cpu_s']:.1f} |")
    failed = any(q["succeeded_once"] != q["analyses"] for q in queue) or any(
        sum(reads[w]["errors"].values()) for w in ("primary", "replica"))
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
