#!/usr/bin/env bash
# Installs the page's npm packages (the charting library; playwright-core for
# its browser tests) into clients/web/node_modules exactly as
# clients/web/package-lock.json pins them, when that lock changed since the
# last install. Nothing is fetched at run time: the build copies what the page
# needs next to it (clients/web/CMakeLists.txt).
set -euo pipefail
web=$(cd "$(dirname "$0")/../clients/web" && pwd)
stamp=$web/node_modules/.insdiag-lock.sha256
want=$(sha256sum "$web/package-lock.json" | cut -d' ' -f1)
if [[ -f "$stamp" && "$(cat "$stamp")" == "$want" ]]; then
  exit 0
fi
echo "insdiag: installing the page's npm packages (clients/web)" >&2
# No browser download: the tests drive Debian's chromium.
(cd "$web" && PLAYWRIGHT_SKIP_BROWSER_DOWNLOAD=1 npm ci --no-audit --no-fund --loglevel=error)
echo "$want" >"$stamp"
