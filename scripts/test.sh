#!/usr/bin/env bash
# Sets up, builds (Release) and runs every test with output on failure. Fails when a test
# fails, and also when one was skipped or did not run: on a fresh clone every test runs.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup-deps
werror=OFF
[ "${CI:-}" = "true" ] && werror=ON
cmake --preset release -DFULLARM_WERROR=${werror} >/dev/null
cmake --build --preset release -j "$(nproc)"
log=build/release/ctest-output.log
ctest --preset release -j "$(nproc)" 2>&1 | tee "$log"
# ctest lists skipped tests ("(Skipped)", a GTEST_SKIP) and tests it could not run ("Not Run",
# "(Disabled)") after its summary line.
if grep -Eq '\((Skipped|Disabled)\)|\*\*\*Not Run|Not Run ' "$log"; then
  echo "test.sh: FAIL: tests were skipped or did not run:" >&2
  grep -E '\((Skipped|Disabled)\)|Not Run' "$log" >&2
  exit 1
fi
