#!/usr/bin/env bash
# Installs the Debian 12 packages fetchscope needs (only those missing). Run as root or with sudo.
#   tools/install-deps.sh           build + test dependencies
#   tools/install-deps.sh --bench   also the benchmark peers (mujoco-record, xvfb)
#   tools/install-deps.sh --ci      also what CI needs: tools/ci-extra.sh's clang + libFuzzer and
#                                   valgrind, and slurm-wlm + munge for tests/slurm_test.cc
# Then the npm packages of web/ (uPlot, embedded into the binary by the build; playwright-core,
# which drives chromium in the browser tests), exactly as web/package-lock.json pins them.
set -euo pipefail
packages=(cmake g++ make pkg-config
  libmujoco-dev libqhull-dev
  libegl-dev libegl1 libegl-mesa0 libgl1-mesa-dri libosmesa6-dev
  libeigen3-dev libpng-dev libavcodec-dev libavformat-dev libavutil-dev libswscale-dev
  libavfilter-dev libssl-dev libfreetype-dev libfontconfig-dev fonts-dejavu-core libhdf5-dev
  libcli11-dev nlohmann-json3-dev libgtest-dev libcpp-httplib-dev libturbojpeg0-dev
  ffmpeg python3 python3-numpy python3-h5py python3-pil
  binutils xz-utils ccache
  chromium)
# Node.js and npm: Debian's, unless a Node.js (e.g. NodeSource's, which bundles npm) is present
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then packages+=(nodejs npm); fi
for flag in "$@"; do
  case "$flag" in
    --bench) packages+=(libmujoco-samples xvfb xauth time) ;;
    # libclang-rt-14-dev holds libFuzzer and the clang sanitizer runtimes; slurm-wlm and munge:
    # the one-node Slurm tests/slurm_test.cc starts under a temp folder (it skips without them)
    --ci) packages+=(clang clang-format libclang-rt-14-dev valgrind slurm-wlm munge) ;;
    *) echo "install-deps: unknown option '$flag' (accepted: --bench, --ci)" >&2; exit 2 ;;
  esac
done
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [[ ${#missing[@]} -eq 0 ]]; then
  echo "install-deps: all ${#packages[@]} Debian packages present"
else
  sudo=""
  if [[ $(id -u) -ne 0 ]]; then sudo="sudo"; fi
  echo "install-deps: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
# npm ci again only when the lock file changed since the last install (a stamp in node_modules)
web="$(cd "$(dirname "$0")/.." && pwd)/web"
stamp="$web/node_modules/.fetchscope-lock.sha256"
lock_sum=$(sha256sum "$web/package-lock.json" | cut -d' ' -f1)
if [[ ! -f "$stamp" || "$(cat "$stamp")" != "$lock_sum" ]]; then
  echo "install-deps: npm ci in web/"
  (cd "$web" && npm ci --no-audit --no-fund --loglevel=error)
  echo "$lock_sum" >"$stamp"
else
  echo "install-deps: web/node_modules matches web/package-lock.json"
fi
echo "install-deps: done"
