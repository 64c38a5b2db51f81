#!/usr/bin/env python3
"""Seeds of the REST and JSON fuzzers, taken from the tests (scripts/fuzz.sh).

  rest_request_fuzzer  (template, path, query, body): every REST path the
                       server tests, the page's end-to-end test and the load
                       script request, under the http rule template it
                       matches (proto/insdiag/v1), else under each template
                       the path-template tests parse; bodies are the JSON
                       literals of the server tests, in turn.
  json_request_fuzzer  (method byte, JSON): every JSON literal of the server
                       tests, for every method whose request has a body.
  rest_gateway_fuzzer  ("FLAGS METHOD PATH?QUERY", headers, body): every
                       REST path above as a GET with a bearer token, and
                       every http rule's template with a body, POSTed with
                       the server tests' JSON bodies in turn.
  bench_run_csv_fuzzer the CSV texts the reader tests spell out literally
                       (malformed ones included); the fixtures they build in
                       code come from the write_fuzz_seeds program.

Usage: tests/fuzz/seeds_from_tests.py CORPUS_DIR   (writes CORPUS_DIR/<fuzzer>/test-*)
"""
import glob
import hashlib
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# C++ string literals, adjacent ones joined ("a\n" "b\n"), and raw ones R"(…)".
LITERAL = re.compile(r'R"\((.*?)\)"|((?:"(?:[^"\\\n]|\\.)*"\s*)+)', re.S)
ESCAPES = {"n": "\n", "r": "\r", "t": "\t", '"': '"', "\\": "\\", "0": "\0"}


def literals(path):
    text = open(path, errors="replace").read()
    for m in LITERAL.finditer(text):
        if m.group(1) is not None:
            yield m.group(1)
            continue
        parts = re.findall(r'"((?:[^"\\\n]|\\.)*)"', m.group(2))
        yield "".join(re.sub(r"\\(.)", lambda e: ESCAPES.get(e.group(1), e.group(1)), p) for p in parts)


def files(*patterns):
    return sorted(f for p in patterns for f in glob.glob(os.path.join(ROOT, p)))


def http_rules():
    """(template, has_body) of every google.api.http rule, in the order of the
    json fuzzer's methods: its services' order, each file's methods in order."""
    fuzzer = open(os.path.join(ROOT, "tests/fuzz/json_request_fuzzer.cc")).read()
    order = re.findall(r'"insdiag\.v1\.(\w+Service)"', fuzzer)
    methods = {}
    for proto in files("proto/insdiag/v1/*.proto"):
        service = None
        for line in open(proto):
            if m := re.match(r"service (\w+)", line):
                service, methods[m.group(1)] = m.group(1), []
            elif service and (m := re.match(r"\s*rpc (\w+)", line)):
                methods[service].append([None, False])
            elif service and methods[service] and (m := re.search(r'(get|post|delete): "([^"]+)"', line)):
                methods[service][-1] = [m.group(2), m.group(1) == "post"]
    return [rule for service in order for rule in methods.get(service, [])]


def template_regex(template):
    pattern = re.escape(template)
    pattern = re.sub(r"\\\{[^}=]+=([^}]*)\\\}", lambda m: m.group(1).replace(r"\*\*", ".+").replace(r"\*", "[^/:]+"),
                     pattern)
    return re.compile("^" + re.sub(r"\\\{[^}]+\\\}", "[^/:]+", pattern) + "$")


def write(corpus, fuzzer, content):
    directory = os.path.join(corpus, fuzzer)
    os.makedirs(directory, exist_ok=True)
    data = content.encode() if isinstance(content, str) else content
    with open(os.path.join(directory, "test-" + hashlib.sha1(data).hexdigest()[:12]), "wb") as f:
        f.write(data)


def main():
    corpus = sys.argv[1]
    server_tests = files("tests/server/*.cc")
    bodies = sorted({s for f in server_tests for s in literals(f) if s.startswith("{") and s.endswith("}")})
    paths = sorted({s for f in server_tests + files("tests/server/*.py", "clients/web/tests/*.mjs",
                                                    "scripts/load_test.py")
                    for s in (literals(f) if f.endswith(".cc") else re.findall(r"""["'`](/v1/[^"'`]*)""",
                                                                                open(f).read()))
                    if s.startswith("/v1/")})
    test_templates = sorted({s for s in literals(os.path.join(ROOT, "tests/server/path_template_test.cc"))
                             if s.startswith("/") and "{" in s})
    rules = http_rules()
    templates = [t for t, _ in rules if t]
    count = {"rest_request_fuzzer": 0, "json_request_fuzzer": 0, "rest_gateway_fuzzer": 0,
             "bench_run_csv_fuzzer": 0}
    headers = "Authorization: Bearer fuzz-token\nContent-Type: application/json"
    for i, url in enumerate(paths):
        write(corpus, "rest_gateway_fuzzer", f"{'o' if i % 2 else '-'} GET {url}\n{headers}\n\n")
        count["rest_gateway_fuzzer"] += 1
    for index, (template, has_body) in enumerate(rules):
        if template and has_body and bodies:
            path = re.sub(r"\{[^}=]+=([^}]*)\}", lambda m: m.group(1).replace("*", "x"), template)
            write(corpus, "rest_gateway_fuzzer", f"o POST {path}\n{headers}\n\n{bodies[index % len(bodies)]}")
            count["rest_gateway_fuzzer"] += 1
    for i, url in enumerate(paths):
        path, _, query = url.partition("?")
        matched = [t for t in templates if template_regex(t).match(path)] or test_templates
        for template in matched:
            write(corpus, "rest_request_fuzzer", f"{template}\n{path}\n{query}\n{bodies[i % len(bodies)] if bodies else ''}")
            count["rest_request_fuzzer"] += 1
    for index, (template, has_body) in enumerate(rules):
        if not has_body:
            continue
        for body in bodies:
            write(corpus, "json_request_fuzzer", bytes([index]) + body.encode())
            count["json_request_fuzzer"] += 1
    for f in files("tests/benchrun/*.cc", "tests/server/*.cc"):
        for s in literals(f):
            if "# format:" in s and "\n" in s:
                write(corpus, "bench_run_csv_fuzzer", s)
                count["bench_run_csv_fuzzer"] += 1
    print(" ".join(f"{k}: {v}" for k, v in count.items()))


if __name__ == "__main__":
    main()
