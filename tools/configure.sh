#!/usr/bin/env bash
# The one build configuration of tools/quickstart.sh and tools/test.sh (and so CI): the same
# flags, so that the test command after the quick start reuses every object the quick start built.
# -Werror: a warning (g++ -Wall -Wextra) fails the build. ccache is used when installed.
set -euo pipefail
cd "$(dirname "$0")/.."
launcher=()
if command -v ccache >/dev/null; then
  # pch_defines,time_macros: what ccache needs to cache files compiled with a precompiled header
  # CCACHE_BASEDIR: paths inside the checkout are hashed relative to it, so a second clone or
  # worktree (CI's fresh clone on the same machine) hits the objects another one compiled
  cc="env;CCACHE_SLOPPINESS=pch_defines,time_macros;CCACHE_BASEDIR=$(pwd);ccache"
  launcher=("-DCMAKE_CXX_COMPILER_LAUNCHER=$cc" "-DCMAKE_C_COMPILER_LAUNCHER=$cc")
fi
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=ON -DFETCHSCOPE_WERROR=ON \
  "${launcher[@]}" "$@" >/dev/null
