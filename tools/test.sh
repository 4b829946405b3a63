#!/usr/bin/env bash
# The README's second command (and CI's): install, build everything, run the whole ctest suite.
set -euo pipefail
cd "$(dirname "$0")/.."
tools/install-deps.sh
# -Werror: a warning (g++ -Wall -Wextra) fails the build
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=ON -DFETCHSCOPE_WERROR=ON >/dev/null
cmake --build build -j"$(nproc)"
cd build
# the soak test (label soak, built only with -DFETCHSCOPE_SOAK=ON) is never part of this run
ctest --output-on-failure -j"$(nproc)" -LE soak "$@"
