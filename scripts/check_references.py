#!/usr/bin/env python3
"""Checks that every path the docs and the code's comments cite exists.

Usage: scripts/check_references.py [--shared DIR] [--verbose]

Scans README.md, docs/*.md, every folder's README and the comments of the
sources (C++, CMake, Python, shell, JavaScript, SQL) for paths that start at
one of the repository's top-level folders ("docs/API.md",
"engine/src/filter/smoother.cc", "kb/src/store_util.h", "tests/support/poll.h")
and looks each up. A path resolves when it names a file or folder of the
repository, or, written short as the docs write headers, one under the
folder's include or src tree ("kb/diagnosis.h" is
kb/include/insdiag/kb/diagnosis.h, "ident/allan*" a stem under engine/src);
a stem without an extension may name a .h, .cc, .md, .sql, .py or .sh file,
and * and {a,b} stand for what they do in a shell. Paths under shared/ (the
specification and design the project is written from, beside the
repository) are looked up in --shared (default: ../shared beside the
repository, else skipped with a count). build/ paths are what the build
writes and are not checked.

Exit status 0 when every path resolves, 1 with each dangling one as
FILE:LINE: PATH.
"""
import argparse
import glob
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
TOP = ["docs", "engine", "kb", "server", "clients", "proto", "benchrun", "importers", "testreport", "tools",
       "tests", "scripts", "data", "migrations", "cmake", "docker", "shared"]
# Short forms: the folder a header path is written from.
INCLUDE_ROOTS = {
    "engine": ["engine/include/insdiag/engine", "engine/src"],
    "kb": ["kb/include/insdiag/kb", "kb/src", "kb"],
    "server": ["server/include/insdiag/server", "server/src", "server"],
    "benchrun": ["benchrun/include/insdiag/benchrun", "benchrun/src"],
    "importers": ["importers/include/insdiag/importers", "importers/src"],
    "testreport": ["testreport/include/insdiag/testreport", "testreport/src"],
    "clients": ["clients"],
    "proto": ["proto/include/insdiag/api", "proto/src", "proto"],
    "api": ["proto/include/insdiag/api", "proto/src"],
}
# The engine's folders, which the docs cite from the engine ("filter/epoch_run", "ident/allan*").
ENGINE_FOLDERS = ["analysis", "filter", "finder", "ident", "model", "monitor", "nav", "numerics", "sim", "stats"]
for folder in ENGINE_FOLDERS:
    INCLUDE_ROOTS[folder] = [f"engine/src/{folder}", f"engine/include/insdiag/engine/{folder}"]
STEMS = ["", ".h", ".cc", ".md", ".sql", ".py", ".sh", ".js", ".proto", ".json", ".cmake"]
PATH = re.compile(r"(?<![\w/.:-])((?:%s)/[\w.*{},/-]*[\w*}])" % "|".join(TOP + ["api"]))
# In the docs also the engine-relative short forms.
DOC_PATH = re.compile(r"(?<![\w/.:-])((?:%s)/[\w.*{},/-]*[\w*}])" % "|".join(TOP + ["api"] + ENGINE_FOLDERS))
SOURCE_EXT = (".h", ".cc", ".cmake", ".txt", ".py", ".sh", ".js", ".sql", ".proto", ".in")
COMMENT = {".h": "//", ".cc": "//", ".js": "//", ".proto": "//", ".cmake": "#", ".txt": "#", ".py": "#",
           ".sh": "#", ".sql": "--", ".in": "//"}


def expand_braces(path):
    m = re.search(r"\{([^{}]*)\}", path)
    if not m:
        return [path]
    out = []
    for choice in m.group(1).split(","):
        out.extend(expand_braces(path[: m.start()] + choice + path[m.end():]))
    return out


def exists(path, shared):
    path = path.replace("NNNN_name", "[0-9][0-9][0-9][0-9]_*")  # a pattern of numbered files
    if path.startswith("shared/"):
        if shared is None:
            return None
        base, rest = shared, path[len("shared/"):]
        candidates = [os.path.join(base, rest)]
    else:
        top, _, rest = path.partition("/")
        candidates = [os.path.join(ROOT, path)]
        for r in INCLUDE_ROOTS.get(top, []):
            candidates.append(os.path.join(ROOT, r, rest))
    for c in candidates:
        for variant in expand_braces(c.rstrip("/")):
            for ext in STEMS:
                if glob.glob(variant + ext) or glob.glob(variant + "*" + ext if variant.endswith("_") else variant + ext):
                    return True
    return False


def text_lines(path):
    ext = os.path.splitext(path)[1]
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            if path.endswith(".md") or os.path.basename(path) == "README":
                yield number, line
                continue
            marker = COMMENT.get(ext)
            if marker and marker in line:
                yield number, line[line.index(marker):]


def files():
    skip = {"build", "node_modules", ".git", ".cache"}
    for dirpath, dirnames, filenames in os.walk(ROOT):
        dirnames[:] = [d for d in dirnames if d not in skip and not d.startswith("build")]
        for name in filenames:
            if name.endswith(".md") or name.endswith(SOURCE_EXT):
                yield os.path.join(dirpath, name)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shared", default=os.path.join(os.path.dirname(ROOT), "shared"))
    parser.add_argument("--verbose", action="store_true")
    args = parser.parse_args()
    shared = args.shared if os.path.isdir(args.shared) else None
    dangling, checked, unchecked = [], 0, 0
    for path in sorted(files()):
        rel = os.path.relpath(path, ROOT)
        for number, line in text_lines(path):
            for m in (DOC_PATH if rel.endswith(".md") else PATH).finditer(line):
                ref = m.group(1).rstrip(".,")
                if "://" in line[max(0, m.start() - 40): m.start()]:
                    continue  # a URL's path
                ok = exists(ref, shared)
                if ok is None:
                    unchecked += 1
                    continue
                checked += 1
                if not ok:
                    dangling.append(f"{rel}:{number}: {ref}")
    for d in dangling:
        print(d)
    print(f"check_references: {checked} paths checked, {len(dangling)} dangling"
          + (f", {unchecked} under shared/ not checked (no {args.shared})" if unchecked else ""), file=sys.stderr)
    return 1 if dangling else 0


if __name__ == "__main__":
    sys.exit(main())
