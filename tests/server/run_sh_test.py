#!/usr/bin/env python3
"""./run.sh as a newcomer runs it, on free ports and a fresh data directory:

1. `./run.sh --http-port N --grpc-port M` (INSDIAG_RUN_NO_BUILD=1: the
   build under test, no install or build step): REST answers on N, gRPC on
   M, the banner says how to get the admin token and the token file is
   there (mode 0600); the demonstration loads, and once its analyses end,
   every analysis listed through the API has SUCCEEDED, the demonstration's
   units and the real record among them; the page opens on the loop at work
   (the healthy unit not FAULTY, the hidden scale factor found, the faulty
   unit FAULTY with its step, each unit diagnosed once, a fleet of 40).
   SIGTERM stops it all.
2. `./run.sh --no-demo` on another fresh data directory: the database stays
   empty (no run, no analysis).

Every wait polls with a deadline. Usage: run_sh_test.py BUILD_DIR
"""
import json
import os
import signal
import socket
import stat
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEMO_SERIALS = {"DEMO-1", "DEMO-2", "DEMO-3", "PSINS-RLG-2014"}


def fail(message):
    print("run.sh test: FAILED:", message, file=sys.stderr)
    sys.exit(1)


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def poll(what, deadline_s, probe, process=None, output=None):
    """Calls probe() until it returns a true value; fails after deadline_s."""
    deadline = time.monotonic() + deadline_s
    while time.monotonic() < deadline:
        value = probe()
        if value:
            return value
        if process is not None and process.poll() is not None:
            fail(f"run.sh exited ({process.returncode}) while waiting for {what}:\n{read(output)[-3000:]}")
        time.sleep(0.2)
    fail(f"no {what} within {deadline_s} s" + (f":\n{read(output)[-3000:]}" if output else ""))


def read(path):
    with open(path, errors="replace") as f:
        return f.read()


class Rest:
    def __init__(self, port, token=""):
        self.base, self.token = f"http://127.0.0.1:{port}", token

    def get(self, path):
        request = urllib.request.Request(self.base + path)
        if self.token:
            request.add_header("Authorization", f"Bearer {self.token}")
        try:
            with urllib.request.urlopen(request, timeout=30) as answer:
                return answer.status, answer.read()
        except urllib.error.HTTPError as error:
            return error.code, error.read()
        except OSError:
            return 0, b""

    def every(self, collection, field):
        """Every item of a listing, page after page."""
        items, token = [], ""
        while True:
            status, body = self.get(f"/v1/{collection}?pageSize=1000" + (f"&pageToken={token}" if token else ""))
            if status != 200:
                fail(f"GET /v1/{collection}: {status} {body[:300]!r}")
            page = json.loads(body)
            items += page.get(field, [])
            token = page.get("nextPageToken", "")
            if not token:
                return items


class RunSh:
    """./run.sh in its own process group, its output in a file."""

    def __init__(self, build_dir, work, args):
        self.data = os.path.join(work, "data")
        self.output = os.path.join(work, "run.sh.out")
        env = dict(os.environ, INSDIAG_RUN_NO_BUILD="1", INSDIAG_BUILD_DIR=build_dir, INSDIAG_DATA_DIR=self.data)
        for inherited in ("INSDIAG_DATABASE_URL", "INSDIAG_READ_DATABASE_URL", "INSDIAG_TOKEN"):
            env.pop(inherited, None)
        with open(self.output, "w") as out:
            self.process = subprocess.Popen([os.path.join(ROOT, "run.sh")] + args, cwd=work, env=env, stdout=out,
                                            stderr=subprocess.STDOUT, start_new_session=True)

    def stop(self):
        """SIGTERM to run.sh, which stops insdiagd and its PostgreSQL; then the
        rest of its group (a demonstration loader still running)."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(90)
            except subprocess.TimeoutExpired:
                fail("run.sh did not stop within 90 s of SIGTERM")
        try:
            os.killpg(self.process.pid, signal.SIGTERM)
        except ProcessLookupError:
            pass


def wait_until_serving(run, http_port, grpc_port, cli):
    rest = Rest(http_port)
    poll(f"REST on port {http_port}", 120, lambda: rest.get("/healthz")[0] == 200, run.process, run.output)
    token_file = os.path.join(run.data, "admin-token")
    poll("admin token", 30, lambda: os.path.exists(token_file) and os.path.getsize(token_file) > 0,
         run.process, run.output)
    mode = stat.S_IMODE(os.stat(token_file).st_mode)
    if mode != 0o600:
        fail(f"{token_file} has mode {mode:o}, not 600")
    token = read(token_file).strip()
    # gRPC on M, through the CLI.
    listed = subprocess.run([cli, "tokens", "list", "--server", f"127.0.0.1:{grpc_port}", "--token", token],
                            capture_output=True, text=True, timeout=60)
    if listed.returncode != 0:
        fail(f"insdiag tokens list over gRPC port {grpc_port}: {listed.stderr}")
    banner = read(run.output)
    for expected in (f"http://localhost:{http_port}/", f"localhost:{grpc_port}",
                     f"export INSDIAG_TOKEN=$(cat {token_file})"):
        if expected not in banner:
            fail(f"the banner does not say '{expected}':\n{banner}")
    return Rest(http_port, token)


def check_demonstration(build_dir, cli):
    http_port, grpc_port = free_port(), free_port()
    with tempfile.TemporaryDirectory(prefix="insdiag-run-sh-") as work:
        os.chmod(work, 0o755)  # as root, the embedded PostgreSQL runs as `postgres`
        run = RunSh(build_dir, work, ["--http-port", str(http_port), "--grpc-port", str(grpc_port)])
        try:
            started = time.monotonic()
            rest = wait_until_serving(run, http_port, grpc_port, cli)
            print(f"run.sh test: serving REST on {http_port}, gRPC on {grpc_port} after "
                  f"{time.monotonic() - started:.0f} s")
            poll("end of the demonstration's loading", 480,
                 lambda: "the demonstration is loaded" in read(run.output) or "did not load" in read(run.output),
                 run.process, run.output)
            if "did not load" in read(run.output):
                fail("the demonstration did not load:\n" + read(os.path.join(run.data, "demo.log"))[-3000:])
            # The real record's analysis is queued last: wait for every analysis to end.
            ended = ("SUCCEEDED", "FAILED", "CANCELLED")
            analyses = poll("end of every analysis", 480,
                            lambda: (lambda a: a if a and all(x["state"] in ended for x in a) else None)(
                                rest.every("analyses", "analyses")),
                            run.process, run.output)
            not_succeeded = [(a["name"], a["state"]) for a in analyses if a["state"] != "SUCCEEDED"]
            if not_succeeded:
                fail(f"analyses that did not succeed: {not_succeeded}")
            runs = rest.every("runs", "runs")
            by_name = {r["name"]: r["metadata"]["unitSerial"] for r in runs}
            analysed = {by_name.get(a["run"]) for a in analyses}
            missing = DEMO_SERIALS - analysed
            if missing:
                fail(f"no succeeded analysis of {sorted(missing)}; runs: {sorted(set(by_name.values()))[:20]}")
            print(f"run.sh test: the demonstration loaded and analysed in {time.monotonic() - started:.0f} s: "
                  f"{len(runs)} runs, {len(analyses)} analyses, every one SUCCEEDED")
            check_what_the_demonstration_shows(rest, analyses, by_name)
        finally:
            run.stop()
        poll(f"port {http_port} closed after SIGTERM", 30, lambda: Rest(http_port).get("/healthz")[0] == 0)


def check_what_the_demonstration_shows(rest, analyses, serial_of_run):
    """The page opens on the loop at work: the simulated units' hidden effects
    found, the faulty one FAULTY, each unit diagnosed once, and a fleet for
    the fleet views (the real record's analysis is checked with the others')."""
    def report_of(serial):
        names = [a["name"] for a in analyses if serial_of_run.get(a["run"]) == serial]
        if not names:
            fail(f"{serial} has no analysis")
        status, body = rest.get(f"/v1/{names[0]}")
        if status != 200:
            fail(f"GET /v1/{names[0]}: {status} {body[:300]!r}")
        return json.loads(body).get("report", {})

    def has_effect(report, prefix):
        return any(e.startswith(prefix) for e in report.get("model", {}).get("effects", []))

    healthy, hidden_scale_factor, faulty = (report_of(s) for s in ("DEMO-1", "DEMO-2", "DEMO-3"))
    if healthy.get("verdict") == "FAULTY":
        fail("the healthy DEMO-1 is FAULTY")
    if not has_effect(hidden_scale_factor, "gyro_scale_factor.z"):
        fail(f"DEMO-2's hidden gyro z scale factor was not found: {hidden_scale_factor.get('model')}")
    if faulty.get("verdict") != "FAULTY" or not has_effect(faulty, "gyro_bias_step.x@"):
        fail(f"DEMO-3's gyro x step: verdict {faulty.get('verdict')}, model {faulty.get('model')}")
    for serial in ("DEMO-1", "DEMO-2", "DEMO-3"):
        status, body = rest.get(f"/v1/diagnoses?unit=units/{serial}")
        diagnoses = json.loads(body).get("diagnoses", []) if status == 200 else None
        if diagnoses is None or len(diagnoses) != 1:
            fail(f"{serial}: GET /v1/diagnoses answered {status} with {body[:300]!r}, not one diagnosis")
    status, body = rest.get("/v1/fleetStatistics")
    units = int(json.loads(body).get("unitCount", 0)) if status == 200 else 0
    if units < 40:
        fail(f"GET /v1/fleetStatistics: {status}, {units} units, not the fleet of 40")
    print(f"run.sh test: DEMO-1 {healthy.get('verdict')}, DEMO-2's gyro z scale factor found, DEMO-3 FAULTY with "
          f"its gyro x step, each diagnosed once; a fleet of {units} units")


def check_no_demo(build_dir, cli):
    http_port, grpc_port = free_port(), free_port()
    with tempfile.TemporaryDirectory(prefix="insdiag-run-sh-") as work:
        os.chmod(work, 0o755)
        run = RunSh(build_dir, work, ["--no-demo", f"--http-port={http_port}", f"--grpc-port={grpc_port}"])
        try:
            rest = wait_until_serving(run, http_port, grpc_port, cli)
            poll("run.sh's word on --no-demo", 30, lambda: "--no-demo: it stays empty" in read(run.output),
                 run.process, run.output)
            runs, analyses = rest.every("runs", "runs"), rest.every("analyses", "analyses")
            if runs or analyses or "loading the demonstration" in read(run.output):
                fail(f"--no-demo: {len(runs)} runs, {len(analyses)} analyses:\n{read(run.output)}")
            print("run.sh test: --no-demo leaves the new database empty")
        finally:
            run.stop()


def main():
    build_dir = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(ROOT, "build"))
    cli = os.path.join(build_dir, "clients", "insdiag")
    for binary in (cli, os.path.join(build_dir, "server", "insdiagd")):
        if not os.access(binary, os.X_OK):
            fail(f"no {binary}: build first")
    check_no_demo(build_dir, cli)
    check_demonstration(build_dir, cli)
    print("run.sh test: passed")


if __name__ == "__main__":
    main()
