#!/usr/bin/env bash
# The whole test suite, from a fresh machine: installs what is missing, then
#   1. builds the release tree and runs every test (unit, integration, e2e),
#   2. builds with AddressSanitizer + UndefinedBehaviorSanitizer and runs them again,
#      with every fuzz target replaying its corpus, regressions and seeded mutants,
#   3. cross-builds the controller board's part for arm64 and runs its tests (and
#      its package's) under qemu's user-mode emulator.
# Set LIGHTSTAGE_TEST_FLAVOURS="release" (or "release sanitize") to run fewer; add
# "fuzz" to also build the coverage-guided libFuzzer targets with clang and run each
# for LIGHTSTAGE_FUZZ_SECONDS (a third build of the tree: too long for CI's 90 min).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
flavours=${LIGHTSTAGE_TEST_FLAVOURS:-release sanitize arm64}
# shellcheck disable=SC2086  # one word per flavour
"$root/scripts/install-deps.sh" $flavours

# The real-data tests (DiLiGenT ball, UW sets) read LIGHTSTAGE_SHARED_DATA, or
# else ../shared/data next to the checkout.
if [ -z "${LIGHTSTAGE_SHARED_DATA:-}" ] && [ -d "$root/../shared/data/diligent" ]; then
  LIGHTSTAGE_SHARED_DATA=$(cd "$root/../shared/data" && pwd)
  export LIGHTSTAGE_SHARED_DATA
fi
echo "real data: ${LIGHTSTAGE_SHARED_DATA:-not found (set LIGHTSTAGE_SHARED_DATA; those tests skip)}"

jobs=${LIGHTSTAGE_JOBS:-$(nproc)}
# Each stage's wall time, so a CI log shows where the 90 minutes go.
started=$SECONDS
stage() { echo "=== $1 (at $((SECONDS - started)) s) ==="; }
# The name and the last 40 output lines of every test a ctest log marks as failed. With -j
# a test's output follows its result line, up to the next result or start line.
failed_tests_output() {
  awk -v flavour="$1" '
    function flush() { if (name != "") { print "--- " flavour ": " name; n = count < 40 ? count : 40;
                       for (i = count - n + 1; i <= count; i++) print lines[i % 40] } name = "" }
    /^ *[0-9]+\/[0-9]+ Test +#[0-9]+: / { flush()
      if ($0 ~ /\*\*\*|Failed|Timeout|Exception|Not Run/ && $0 !~ /Passed|Skipped/) {
        name = $0; sub(/^ *[0-9]+\/[0-9]+ Test +#[0-9]+: /, "", name); count = 0 }
      next }
    /^ +Start +[0-9]+: / { flush(); next }
    /^[0-9]+% tests passed/ { flush(); next }
    name != "" { count++; lines[count % 40] = $0 }
    END { flush() }' "$2"
}
passed=0
failed=0
failures=""
for flavour in $flavours; do
  stage "$flavour: build"
  "$root/scripts/build.sh" "$flavour"
  case "$flavour" in
    release) dir=$root/build ;;
    sanitize) dir=$root/build-sanitize ;;
    fuzz) dir=$root/build-fuzz ;;
    arm64) dir=$root/build-arm64 ;;
  esac
  stage "$flavour: test"
  log=$dir/ctest.log
  set +e
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir "$dir" --output-on-failure -j "$jobs" --timeout 900 2>&1 | tee "$log"
  set -e
  summary=$(grep -E "tests passed, [0-9]+ tests failed out of" "$log" | tail -1 || true)
  total=$(echo "$summary" | sed -E 's/.* out of ([0-9]+).*/\1/')
  bad=$(echo "$summary" | sed -E 's/.* ([0-9]+) tests failed.*/\1/')
  if [ -z "$summary" ]; then
    echo "$flavour: ctest did not finish" >&2
    failed=$((failed + 1))
    continue
  fi
  passed=$((passed + total - bad))
  failed=$((failed + bad))
  if [ "$bad" -gt 0 ]; then
    failures+=$(failed_tests_output "$flavour" "$log")$'\n'
  fi
done
echo
# CI keeps only the end of its log: repeat what each failed test printed here.
if [ -n "$failures" ]; then
  echo "=== failed tests, with the last lines each printed ==="
  echo "$failures"
fi
echo "all flavours ($flavours), $((SECONDS - started)) s:"
echo "tests: $passed passed, $failed failed"
[ "$failed" -eq 0 ]
