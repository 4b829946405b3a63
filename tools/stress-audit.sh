#!/usr/bin/env bash
# The timing audit of issue 43: the tests that start processes, send signals, wait or rely on a
# timeout, run ROUNDS times with `stress-ng --cpu LOAD` busy beside them (a slow host: on 2 cores,
# LOAD 2 gives each test about half the CPU it has alone), through ctest -j$(nproc) as CI runs
# them. Prints one line per round (passed, failed, seconds) and the failed tests' names; exits 1
# when any failed.
#   tools/stress-audit.sh BUILD_DIR [ROUNDS] [LOAD] [REGEX]
#   tools/stress-audit.sh build-asan 3 2          # the sanitizer suite's process and signal tests
#   tools/stress-audit.sh build 3 2               # the Release suite's
#   tools/stress-audit.sh build-asan 20 4 'ExecClosesItsStdin$'   # one row, 20 times
# The tests are those of the test binaries below: the ones whose tests start processes and signal
# or kill them, end them by a timeout, or wait for a child, a worker or a server (tests/CMakeLists.txt
# builds a subset of them under the sanitizers); or, with REGEX, the tests whose names match it. Needs stress-ng (apt-get install stress-ng).
set -euo pipefail
build=${1:?usage: tools/stress-audit.sh BUILD_DIR [ROUNDS] [LOAD] [REGEX]}
rounds=${2:-3}
load=${3:-2}
regex=${4:-}
binaries="bad_input_test cli_record_exec_interrupt_test cli_record_jobs_test
  cli_record_kill_anywhere_test cli_serve_test hostile_folder_test minari_test process_test
  scheduler_test serve_attack_test shared_node_test signals_test slurm_test"
command -v stress-ng >/dev/null || { echo "stress-audit: stress-ng is not installed" >&2; exit 2; }
list=$(mktemp)
trap 'rm -f "$list"; kill "${stress_pid:-0}" 2>/dev/null || true' EXIT
# the numbers of the chosen tests, as ctest -I takes them (0,0,0 then each number)
ctest --test-dir "$build" --show-only=json-v1 | python3 -c '
import json, os, re, sys
binaries, regex = set(sys.argv[1].split()), sys.argv[2]
tests = json.load(sys.stdin)["tests"]
chosen = [str(i + 1) for i, t in enumerate(tests)
          if (re.search(regex, t["name"]) if regex else
              t.get("command") and os.path.basename(t["command"][0]) in binaries)
          and not any(p["name"] == "LABELS" and ("soak" in p["value"] or "docs" in p["value"])
                      for p in t.get("properties", []))]
print("0,0,0," + ",".join(chosen))
print(len(chosen), file=sys.stderr)
' "$binaries" "$regex" >"$list" 2>"$list.count"
count=$(cat "$list.count"); rm -f "$list.count"
echo "stress-audit: $count tests of $build, $rounds rounds, stress-ng --cpu $load beside them"
stress-ng --cpu "$load" --timeout 0 >/dev/null 2>&1 &
stress_pid=$!
failed_any=0
for ((r = 1; r <= rounds; r++)); do
  t0=$SECONDS
  log="$build/stress-audit-round-$r.log"
  # the sanitizer build's options, as tools/ci-extra.sh sets them
  supp="$(cd "$(dirname "$0")" && pwd)/sanitizers"
  if ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:check_initialization_order=1" \
     LSAN_OPTIONS="use_tls=0:suppressions=$supp/lsan.supp:print_suppressions=0" \
     UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$supp/ubsan.supp" \
     ctest --test-dir "$build" -I "$list" -j"$(nproc)" --output-on-failure >"$log" 2>&1; then
    verdict="green"
  else
    verdict="FAILED"
    failed_any=1
  fi
  summary=$(grep -E "tests passed|tests failed" "$log" | tail -1)
  echo "stress-audit: round $r: $verdict, $summary, $((SECONDS - t0)) s"
  grep -E "^\s+[0-9]+ - " "$log" | sed 's/^/stress-audit:   /' || true
done
exit $failed_any
