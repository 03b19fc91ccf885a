#!/usr/bin/env bash
# Sets up, builds (Release) and runs `fullarm demo`; prints where the report is.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup-deps
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)" --target fullarm
out="${1:-out/demo}"
# The demo exits 1 when a step's verdict fails; the report is written either way, so say where
# it is, then pass the verdict on.
status=0
build/release/apps/fullarm demo --out "$out" || status=$?
[ -f "$out/report.html" ] && echo "Open $(pwd)/$out/report.html in a browser (it needs no network)."
exit "$status"
