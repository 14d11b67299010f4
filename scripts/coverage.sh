#!/usr/bin/env bash
# Line and branch coverage of src/ under the default test suite (issue 20),
# as CI runs it (.ci/run): a debug build with gcov instrumentation in
# build-cov/, the default suite, then gcovr's per-file table for src/ and
# its summary; fails (exit 2) under 95% of lines or 90% of branches for
# src/ as a whole. Branches gcov marks unreachable and C++ exception
# branches are not counted; nothing in src/ is excluded.
# Usage: scripts/coverage.sh [meson test options, e.g. --num-processes 1]
set -euo pipefail
cd "$(dirname "$0")/.."
command -v gcovr >/dev/null || { echo "coverage: gcovr missing (scripts/bootstrap.sh installs it)" >&2; exit 1; }
if [[ ! -f build-cov/build.ninja ]]; then
    meson setup build-cov -Db_coverage=true --buildtype=debug -Denable_bench=false >/dev/null
fi
ninja -C build-cov
# Counts from an earlier run would add up: start from zero.
find build-cov -name '*.gcda' -delete
# Debug code without optimisation is slower: the tests' own limits scaled
# (e2e_reference's per-command limit by 6: message mode on 2,500
# cospherical points took over 360 s at -O0 on a loaded 2-core machine).
FDT_E2E_TIMEOUT_SCALE=6 meson test -C build-cov --print-errorlogs --timeout-multiplier 4 "$@"
gcovr -r . --filter 'src/' --exclude-unreachable-branches --exclude-throw-branches \
    --print-summary --fail-under-line 95 --fail-under-branch 90 build-cov
