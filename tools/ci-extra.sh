#!/usr/bin/env bash
# CI's reliability stages after tools/test.sh (which leaves the Release build in build/):
#   1. AddressSanitizer + UndefinedBehaviorSanitizer build (clang) of the libraries, fetchscope
#      and the test binaries that tests/CMakeLists.txt lists in FETCHSCOPE_SANITIZER_TESTS (every
#      unit test and the black-box tests of parsers, signals, crashes, workers and datasets), run
#      without the `external` and `docs` labels (Chromium's, tar's and the guides' time: the
#      Release stage runs them) and the `bench --what node` tests (timings, meaningless under ASan)
#   2. each libFuzzer target (clang) for FUZZ_SECONDS over its seed corpus, $JOBS at a time; any
#      finding fails
#   3. valgrind memcheck (no errors, no definite leaks) of the core and renderer's test binaries,
#      and of one short `record` (build/fetchscope) where valgrind can run it: on hosts whose CPU
#      hides RDTSCP it cannot run anything that loads libavcodec (tools/valgrind-probe.sh says so
#      in one line and the stage goes on)
# Usage: tools/ci-extra.sh [asan|fuzz|valgrind ...]   (default: all three, in that order)
# Needs tools/install-deps.sh --ci (clang, libclang-rt-14-dev, valgrind). Jobs: $JOBS (nproc).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
jobs=${JOBS:-$(nproc)}
fuzz_seconds=${FUZZ_SECONDS:-12}
stages=("$@")
[[ ${#stages[@]} -eq 0 ]] && stages=(asan fuzz valgrind)
supp="$root/tools/sanitizers"

stamp() { echo "ci-extra: $* ($(date -u +%H:%M:%S))"; }
# ccache when installed (tools/install-deps.sh installs it): a second CI run on the same machine
# recompiles only what changed
launcher=()
if command -v ccache >/dev/null; then
  # pch_defines,time_macros: what ccache needs to cache files compiled with a precompiled header
  # CCACHE_BASEDIR: paths inside the checkout are hashed relative to it, so a second clone or
  # worktree (CI's fresh clone on the same machine) hits the objects another one compiled
  cc="env;CCACHE_SLOPPINESS=pch_defines,time_macros;CCACHE_BASEDIR=$(pwd);ccache"
  launcher=("-DCMAKE_CXX_COMPILER_LAUNCHER=$cc" "-DCMAKE_C_COMPILER_LAUNCHER=$cc")
fi

run_asan() {
  stamp "ASan+UBSan build"
  local t0=$SECONDS
  # clang: on the 2-core CI machine g++ 12 built the same targets with the sanitizers at -O1 in
  # 891 s, clang 14 in 632 s (a build folder an older script configured with g++ starts afresh)
  if [[ -f build-asan/CMakeCache.txt ]] &&
      ! grep -q '^CMAKE_CXX_COMPILER:FILEPATH=.*clang++' build-asan/CMakeCache.txt; then
    rm -rf build-asan
  fi
  CC=clang CXX=clang++ cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Debug \
    -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g1" -DCMAKE_C_FLAGS_DEBUG="-O1 -g1" -DFETCHSCOPE_SANITIZE=ON \
    -DBUILD_TESTING=ON "${launcher[@]}" >/dev/null
  cmake --build build-asan -j"$jobs"
  stamp "ASan+UBSan ctest"
  # the test binaries and the fetchscope they run inherit these; a report fails the test.
  # use_tls=0: LeakSanitizer's tracer crashed (signal 11 while scanning the main thread's TLS)
  # at the exit of some processes that rendered through llvmpipe. Without TLS as a root, a few
  # library blocks held only through thread-local pointers look leaked: lsan.supp names them.
  ASAN_OPTIONS="detect_leaks=1:abort_on_error=0:strict_string_checks=1:check_initialization_order=1" \
  LSAN_OPTIONS="use_tls=0:suppressions=$supp/lsan.supp:print_suppressions=0" \
  UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$supp/ubsan.supp" \
    ctest --test-dir build-asan --output-on-failure -j"$jobs" -LE 'soak|external|docs' \
      -E 'BenchNode|PixelReachReachesTheGoal|MemoryStaysFlatOverALongRun'
  stamp "ASan+UBSan done in $((SECONDS - t0)) s"
}

# one fuzzer over its seeds for $fuzz_seconds; its verdict in build-fuzz/NAME.verdict
fuzz_one() {  # fuzz_one SEEDS_DIR
  local seeds=$1 name work
  name=$(basename "$seeds")
  work="build-fuzz/corpus/$name"  # grows while fuzzing; the committed seeds stay as they are
  mkdir -p "$work" build-fuzz/artifacts
  rm -f "build-fuzz/$name.verdict"  # a fuzzer killed before its verdict shows none, not an old one
  if ! ASAN_OPTIONS="detect_leaks=1" UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1" \
      "build-fuzz/fuzz/$name" -max_total_time="$fuzz_seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len=4096 -print_final_stats=1 -artifact_prefix="build-fuzz/artifacts/$name-" \
      "$work" "$seeds" >"build-fuzz/$name.log" 2>&1; then
    { echo "ci-extra: FINDING in $name (crash input in build-fuzz/artifacts/):"
      tail -40 "build-fuzz/$name.log"; } >"build-fuzz/$name.verdict"
    return 1
  fi
  echo "ci-extra: fuzz $name ($(ls "$seeds" | wc -l) seeds): $(grep -E \
    "stat::number_of_executed_units|stat::peak_rss_mb" "build-fuzz/$name.log" | tr '\n' ' ')corpus \
now $(ls "$work" | wc -l) files" >"build-fuzz/$name.verdict"
}

run_fuzz() {
  stamp "fuzz build (clang)"
  local t0=$SECONDS
  CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DFETCHSCOPE_FUZZ=ON -DBUILD_TESTING=OFF "${launcher[@]}" >/dev/null
  cmake --build build-fuzz -j"$jobs" --target fuzzers
  # each fuzzer is one single-threaded process: $jobs of them at a time, each for its full time
  local failed=0 all=(fuzz/corpus/*/) i pid pids name seeds
  stamp "${#all[@]} fuzzers for ${fuzz_seconds} s each, $jobs at a time"
  for ((i = 0; i < ${#all[@]}; i += jobs)); do
    pids=()
    for seeds in "${all[@]:i:jobs}"; do
      fuzz_one "$seeds" &
      pids+=($!)
    done
    for pid in "${pids[@]}"; do wait "$pid" || failed=1; done
    for seeds in "${all[@]:i:jobs}"; do
      name=$(basename "$seeds")
      cat "build-fuzz/$name.verdict" 2>/dev/null || echo "ci-extra: $name ended without a verdict"
    done
  done
  stamp "fuzzers done in $((SECONDS - t0)) s"
  return $failed
}

# memcheck of one program: no errors, no definite leaks (log in build/valgrind-NAME.log)
memcheck() {  # memcheck NAME PROGRAM [ARGS...]
  local name=$1 log="build/valgrind-$1.log"
  shift
  valgrind --tool=memcheck --leak-check=full --errors-for-leak-kinds=definite \
    --show-leak-kinds=definite --error-exitcode=99 --num-callers=30 \
    --suppressions="$supp/valgrind.supp" --gen-suppressions=all --log-file="$log" "$@" \
    >"build/valgrind-$name.out" 2>&1 || {
      echo "ci-extra: valgrind found errors in $name (exit $?):"; tail -80 "$log"; return 1; }
  # a test binary whose filter matched nothing checked nothing
  if grep -q "PASSED  \] 0 tests" "build/valgrind-$name.out"; then
    echo "ci-extra: memcheck $name ran no test (its --gtest_filter matches none)"; return 1
  fi
  echo "ci-extra: memcheck $name: $(grep -hoE "PASSED  \] [0-9]+ tests?" "build/valgrind-$name.out" |
    sed 's/PASSED  ] //') passed, $(grep -hoE "ERROR SUMMARY: [0-9]+ errors" "$log"), $(grep -hoE \
    "definitely lost: [0-9,]+ bytes" "$log" || echo "no definite leak")"
}

# The core and the renderer's own test binaries, which load no libavcodec (tests are linked
# --as-needed), so that valgrind runs them on every host: an episode stepped and checked, the
# generator, an episode restored from its checkpoints (contacts included), trajectories read,
# written and replayed, and frames rendered in process (EGL on llvmpipe) with and without MSAA.
# About 45 s on the 2-core machine (the scripted policy's tests alone took 97 s under memcheck).
memcheck_core_tests=(
  "fetch_env_test --gtest_filter=FetchEnv.*:Fetch/EveryTask.*/2"
  "rng_test"
  "trajectory_test"
  "msaa_test --gtest_filter=MsaaTest.ZeroAndFourDifferAlongEdgesOnly"
)

run_valgrind() {
  stamp "valgrind memcheck"
  local t0=$SECONDS out
  [[ -x build/fetchscope ]] || { cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null;
                                 cmake --build build -j"$jobs" --target fetchscope; }
  local entry name
  for entry in "${memcheck_core_tests[@]}"; do
    read -r -a argv <<<"$entry"
    name=${argv[0]}
    [[ -x "build/tests/$name" ]] || cmake --build build -j"$jobs" --target "$name" >/dev/null
    if ldd "build/tests/$name" | grep -q libavcodec; then
      echo "ci-extra: $name loads libavcodec: left to the ASan+UBSan stage"
      continue
    fi
    # valgrind may not run on this host at all; the probe says so in one line
    tools/valgrind-probe.sh "build/tests/$name" --gtest_list_tests || return 0
    memcheck "$name" "build/tests/$name" "${argv[@]:1}" || return 1
  done
  # the whole binary (libavcodec and all): one short record on OSMesa (llvmpipe either way, but
  # without EGL's device probing: fewer uninstrumented paths), where valgrind can run it at all
  if tools/valgrind-probe.sh build/fetchscope --version; then
    out=$(mktemp -d)
    memcheck record build/fetchscope record --env-id FetchReach-v4 --episodes 1 --steps 3 \
      --width 64 --height 48 --msaa 0 --backend osmesa --quiet --out "$out" || {
        rm -rf "$out"; return 1; }
    rm -rf "$out"
  else
    echo "ci-extra: memcheck of fetchscope itself skipped on this host; the ASan+UBSan stage covers it"
  fi
  stamp "valgrind done in $((SECONDS - t0)) s"
}

for s in "${stages[@]}"; do
  case "$s" in
    asan) run_asan ;;
    fuzz) run_fuzz ;;
    valgrind) run_valgrind ;;
    *) echo "ci-extra: unknown stage '$s' (accepted: asan, fuzz, valgrind)" >&2; exit 2 ;;
  esac
done
