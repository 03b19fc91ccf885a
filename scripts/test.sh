#!/usr/bin/env bash
# Sets up, builds (Release) and runs every test with output on failure.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup-deps
werror=OFF
[ "${CI:-}" = "true" ] && werror=ON
cmake --preset release -DFULLARM_WERROR=${werror} >/dev/null
cmake --build --preset release -j "$(nproc)"
ctest --preset release -j "$(nproc)"
