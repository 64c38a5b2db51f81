#!/usr/bin/python3
"""A small insdiag client in Python over gRPC (Debian's python3-grpcio):
upload a bench-run file, have the server analyse it, diagnose the unit.

    /usr/bin/python3 clients/python/insdiag_client.py RUN.csv --server localhost:50051 --token TOKEN [--json]

The token (an OPERATOR's at least) comes from --token or $INSDIAG_TOKEN and
travels as `authorization: Bearer <token>` on every call.

The stubs are generated from proto/ at start (protoc with grpc_python_plugin)
into --stubs-dir (default: a temporary directory); nothing generated is
committed. Exit status: 0 diagnosed, 1 refused or failed, 2 bad usage.
"""
import argparse
import hashlib
import importlib
import os
import struct
import subprocess
import sys
import tempfile
import uuid

HERE = os.path.dirname(os.path.abspath(__file__))
PROTO_DIR = os.path.normpath(os.path.join(HERE, "..", "..", "proto"))
PROTOS = ["insdiag/v1/access.proto", "insdiag/v1/runs.proto", "insdiag/v1/analyses.proto", "insdiag/v1/knowledge.proto",
          "insdiag/v1/history.proto",
          "google/api/annotations.proto", "google/api/http.proto", "google/api/httpbody.proto", "google/rpc/status.proto"]
COLUMNS = ["t", "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z", "ref_roll", "ref_pitch", "ref_yaw"]
DATASHEET = {"gyro_arw": "gyro_arw_rad_rts", "gyro_bias_sigma": "gyro_bias_sigma_rad_s",
             "gyro_bias_tau": "gyro_bias_tau_s", "acc_vrw": "acc_vrw_mps_rts",
             "acc_bias_sigma": "acc_bias_sigma_mps2", "acc_bias_tau": "acc_bias_tau_s"}


def generate_stubs(out_dir):
    os.makedirs(out_dir, exist_ok=True)
    # Debian's grpc_tools bundles a protoc too old for proto3 `optional`:
    # the system protoc with Debian's grpc_python_plugin (protobuf-compiler-grpc)
    # generates the same stubs.
    subprocess.run(["protoc", "-I", PROTO_DIR, "--python_out", out_dir, "--grpc_python_out", out_dir,
                    "--plugin=protoc-gen-grpc_python=/usr/bin/grpc_python_plugin"] + PROTOS, check=True)
    # google/ stays a namespace package, shared with the installed google.protobuf.
    for package in ("insdiag", "insdiag/v1"):
        open(os.path.join(out_dir, package, "__init__.py"), "a").close()
    sys.path.insert(0, out_dir)


def read_run(path, pb):
    """The bench-run file as (RunMetadata, rows); the server validates the values."""
    metadata = pb.RunMetadata()
    rows, header = [], None
    with open(path) as f:
        for line in f:
            line = line.strip()
            if not line:
                continue
            if line.startswith("#") and header is None:
                key, _, value = line[1:].partition(":")
                key, value = key.strip(), value.strip()
                if key in ("format", "unit_serial", "unit_type"):
                    setattr(metadata, key, value)
                elif key.startswith("site_"):
                    setattr(metadata.site, key[5:], float(value))
                elif key in DATASHEET:
                    setattr(metadata.datasheet, DATASHEET[key], float(value))
                else:
                    metadata.extra.add(key=key, value=value)
            elif header is None:
                header = line.split(",")
            else:
                rows.append([float(v) for v in line.split(",")])
    metadata.has_temperature = header is not None and "temp" in header
    order = COLUMNS + (["temp"] if metadata.has_temperature else [])
    index = [header.index(c) for c in order]
    return metadata, [[r[i] for i in index] for r in rows], order


def upload(stub, pb, metadata, rows, order):
    digest = hashlib.sha256()
    for r in rows:
        digest.update(struct.pack("<%dd" % len(r), *r))
    metadata.request_id = str(uuid.uuid4())

    def messages():
        yield pb.UploadRunRequest(metadata=metadata)
        for start in range(0, len(rows), 10000):
            chunk = pb.SampleChunk()
            for r in rows[start:start + 10000]:
                chunk.samples.add(**dict(zip(order, r)))
            yield pb.UploadRunRequest(samples=chunk)
        yield pb.UploadRunRequest(sha256=digest.hexdigest())
    return stub.UploadRun(messages())


def bearer_token_interceptor(grpc, token):
    """A client interceptor adding `authorization: Bearer <token>` to every call
    (gRPC's own call credentials are withheld from channels without TLS)."""
    import collections

    class Details(collections.namedtuple("Details", ("method", "timeout", "metadata", "credentials",
                                                     "wait_for_ready", "compression")),
                  grpc.ClientCallDetails):
        pass

    class Interceptor(grpc.UnaryUnaryClientInterceptor, grpc.UnaryStreamClientInterceptor,
                      grpc.StreamUnaryClientInterceptor, grpc.StreamStreamClientInterceptor):
        def _with_token(self, details):
            metadata = list(details.metadata or [])
            if token:
                metadata.append(("authorization", "Bearer " + token))
            return Details(details.method, details.timeout, metadata, details.credentials,
                           getattr(details, "wait_for_ready", None), getattr(details, "compression", None))

        def intercept_unary_unary(self, continuation, details, request):
            return continuation(self._with_token(details), request)

        def intercept_unary_stream(self, continuation, details, request):
            return continuation(self._with_token(details), request)

        def intercept_stream_unary(self, continuation, details, requests):
            return continuation(self._with_token(details), requests)

        def intercept_stream_stream(self, continuation, details, requests):
            return continuation(self._with_token(details), requests)

    return Interceptor()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", help="bench-run file")
    parser.add_argument("--server", default=os.environ.get("INSDIAG_SERVER", "localhost:50051"))
    parser.add_argument("--token", default=os.environ.get("INSDIAG_TOKEN", ""),
                        help="bearer token (default $INSDIAG_TOKEN)")
    parser.add_argument("--ca-file", default=os.environ.get("INSDIAG_CA_FILE", ""),
                        help="PEM certificates to verify a TLS server against (default: plaintext)")
    parser.add_argument("--json", action="store_true", help="print the diagnosis as JSON")
    parser.add_argument("--stubs-dir", help="where to generate the gRPC stubs (default: a temporary directory)")
    args = parser.parse_args()
    generate_stubs(args.stubs_dir or tempfile.mkdtemp(prefix="insdiag-stubs-"))
    import grpc
    from google.protobuf import json_format
    runs_pb = importlib.import_module("insdiag.v1.runs_pb2")
    runs_grpc = importlib.import_module("insdiag.v1.runs_pb2_grpc")
    analyses_pb = importlib.import_module("insdiag.v1.analyses_pb2")
    analyses_grpc = importlib.import_module("insdiag.v1.analyses_pb2_grpc")
    knowledge_pb = importlib.import_module("insdiag.v1.knowledge_pb2")
    knowledge_grpc = importlib.import_module("insdiag.v1.knowledge_pb2_grpc")

    if args.ca_file:
        try:
            with open(args.ca_file, "rb") as f:
                transport = grpc.secure_channel(args.server, grpc.ssl_channel_credentials(root_certificates=f.read()))
        except OSError as error:
            print("insdiag_client: --ca-file %s: %s" % (args.ca_file, error), file=sys.stderr)
            return 2
    else:
        transport = grpc.insecure_channel(args.server)
    channel = grpc.intercept_channel(transport, bearer_token_interceptor(grpc, args.token))
    try:
        metadata, rows, order = read_run(args.run, runs_pb)
        run = upload(runs_grpc.RunServiceStub(channel), runs_pb, metadata, rows, order)
        print("uploaded", run.name, file=sys.stderr)
        analyses = analyses_grpc.AnalysisServiceStub(channel)
        analysis = analyses.CreateAnalysis(analyses_pb.CreateAnalysisRequest(
            analysis=analyses_pb.Analysis(run=run.name), request_id=str(uuid.uuid4())))
        for analysis in analyses.WatchAnalysis(analyses_pb.WatchAnalysisRequest(name=analysis.name)):
            print("%s %s %3.0f%% %s" % (analysis.name, analyses_pb.Analysis.State.Name(analysis.state),
                                         100 * analysis.progress.fraction, analysis.progress.stage), file=sys.stderr)
        if analysis.state != analyses_pb.Analysis.SUCCEEDED:
            print("analysis %s: %s" % (analyses_pb.Analysis.State.Name(analysis.state), analysis.error.message),
                  file=sys.stderr)
            return 1
        diagnosis = knowledge_grpc.KnowledgeServiceStub(channel).CreateDiagnosis(
            knowledge_pb.CreateDiagnosisRequest(analysis=analysis.name))
    except grpc.RpcError as error:
        print("insdiag_client: %s: %s" % (error.code().name, error.details()), file=sys.stderr)
        return 1
    except (OSError, ValueError) as error:
        print("insdiag_client: %s: %s" % (args.run, error), file=sys.stderr)
        return 1
    if args.json:
        print(json_format.MessageToJson(diagnosis))
    else:
        for c in diagnosis.candidates:
            print("%6.1f %%  %-16s %s" % (100 * c.probability, c.module, c.failure_mode))
    return 0


if __name__ == "__main__":
    sys.exit(main())
