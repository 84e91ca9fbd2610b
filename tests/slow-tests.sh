#!/usr/bin/env bash
# Regenerates tests/slow_tests.txt from the last ctest run's measured costs in a build
# folder: the tests that took at least THRESHOLD_S seconds (default 0.4) are labelled
# `slow`, every other test `quick` (tests/labels.cmake.in).
#   bash tests/slow-tests.sh [BUILD_DIR] [THRESHOLD_S]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
threshold=${2:-0.4}
costs=$build/Testing/Temporary/CTestCostData.txt
[ -f "$costs" ] || { echo "slow-tests.sh: no $costs; run ctest in $build first" >&2; exit 1; }
existing=$(mktemp)
trap 'rm -f "$existing"' EXIT
ctest --test-dir "$build" -N | sed -n 's/^ *Test *#[0-9]*: \([^ ]*\).*/\1/p' | sort -u > "$existing"
{
  echo "# Tests labelled 'slow' (ctest -L slow); all others are 'quick' (ctest -L quick)."
  echo "# Measured: at least ${threshold} s each on a 2-core machine. Regenerate with"
  echo "#   bash tests/slow-tests.sh build ${threshold}"
  awk -v t="$threshold" 'NF == 3 && $3 >= t {print $1}' "$costs" | sort -u | comm -12 - "$existing"
} > tests/slow_tests.txt
echo "slow-tests.sh: $(grep -vc '^#' tests/slow_tests.txt) slow tests written to tests/slow_tests.txt" >&2
