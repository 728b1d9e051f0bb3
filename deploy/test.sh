#!/usr/bin/env bash
# Runs every test of the project on this machine, installing what it needs.
# This is the README's test command; .ci/run calls it and nothing else.
#
#   deploy/test.sh              set up, check formatting, build (ci preset), run all tests
#   deploy/test.sh -R PATTERN   only the ctest tests matching PATTERN
#
# Every DDS participant in the tests uses deploy/cyclonedds/loopback.xml
# (interface lo, no multicast): no test traffic leaves the machine.
set -euo pipefail
case "${1:-}" in -h | --help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;; esac
cd "$(dirname "$0")/.."

deploy/setup.sh

export CYCLONEDDS_URI="file://$PWD/deploy/cyclonedds/loopback.xml"
start=$(date +%s)

echo "== format (clang-format --dry-run -Werror over every tracked C/C++ file)"
deploy/check-format.sh

echo "== configure and build (ci preset: release, -Werror, tests and benchmarks)"
cmake --preset ci >/dev/null
cmake --build --preset ci

echo "== tests"
# In the order a clean checkout runs them (CI's), by the tests' COST
# properties (tests/README.md, "Order"): ctest would otherwise start the
# slowest of the last run first, all together.
rm -f build/release/Testing/Temporary/CTestCostData.txt
ctest --preset ci "$@"

# Every decoder that takes outside input, fuzzed: its kept crashes replayed,
# then 20,000 inputs per target from the shipped files with a fixed seed (the
# same inputs every run); the long run is deploy/fuzz.sh --seconds 3600.
if [[ $# -eq 0 ]]; then
  echo "== fuzzing (20,000 inputs per target)"
  deploy/fuzz.sh --runs 20000
fi

# The cell as containers on an internal network, with faults (or, where
# podman cannot run, one network namespace per service; it says which).
if [[ $# -eq 0 ]]; then
  echo "== containerised integration tests"
  tests/integration/containers/run.sh
fi

echo "== all tests done in $(( $(date +%s) - start )) s"
