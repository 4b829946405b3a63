#!/usr/bin/env bash
# The README's second command (and CI's): install, build everything, run the whole ctest suite.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
tools/configure.sh  # the quick start's configuration: nothing it built is rebuilt
cmake --build build -j"$(nproc)"
cd build
# the soak test (label soak, built only with -DFETCHSCOPE_SOAK=ON) is never part of this run
ctest --output-on-failure -j"$(nproc)" -LE soak "$@"
