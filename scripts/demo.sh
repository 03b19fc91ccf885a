#!/usr/bin/env bash
# Sets up, builds (Release) and runs `fullarm demo`; prints where the report is.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup-deps
cmake --preset release >/dev/null
cmake --build --preset release -j "$(nproc)" --target fullarm
out="${1:-out/demo}"
build/release/apps/fullarm demo --out "$out"
echo "Open $(pwd)/$out/report.html in a browser (it needs no network)."
