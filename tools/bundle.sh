#!/usr/bin/env bash
# Makes dist/fetchscope-VERSION-linux-x86_64.tar.xz: a relocatable fetchscope for machines without
# our Debian packages (GPU nodes running a CUDA image, clusters without root). It holds the
# binary, the bundled models, the DejaVu Sans font for labels (bin/fonts/, found beside the
# binary before any system font), a launcher that sets the library path, and every shared library
# the binary needs that a bare CUDA image lacks (whatever ldd lists: libav* with libavfilter,
# libvpx and libx264, libmujoco and its dependencies, libpng, libcrypto, libfreetype,
# libfontconfig, libstdc++, and libglvnd's libEGL/libGL/libOpenGL dispatchers, which the binary
# opens at run time). It never holds glibc (the node's must be used) nor a GL vendor or GPU driver library
# (the node's NVIDIA driver, or its Mesa, provides those).
#
#   tools/bundle.sh [BUILD_DIR]      default BUILD_DIR: build (made with tools/quickstart.sh)
#   XZ_LEVEL=0 tools/bundle.sh       faster, larger archive (tests use it); default 6
#   DIST_DIR=/tmp/d tools/bundle.sh  where the archive goes (default: dist/)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
binary=$build/fetchscope
if [[ ! -x $binary ]]; then
  echo "bundle: $binary not found: build first (tools/quickstart.sh)" >&2
  exit 2
fi
for tool in ldd tar xz objdump; do
  command -v "$tool" >/dev/null || { echo "bundle: needs $tool (Debian: binutils, xz-utils)" >&2; exit 2; }
done
version=$(sed -n 's/^project(fetchscope VERSION \([0-9.]*\).*/\1/p' CMakeLists.txt)
name=fetchscope-$version-linux-x86_64
dist=${DIST_DIR:-dist}
stage=$(mktemp -d)
trap 'rm -rf "$stage"' EXIT
root=$stage/$name
mkdir -p "$root/bin/models" "$root/bin/fonts" "$root/lib"

# glibc's own libraries, by exact name: they must come from the node (a bundled ld.so or libc
# would not match the node's kernel interface and NSS). Names are compared whole, never as
# patterns: "libc.so" must not drop libcjson.so.1.
glibc=(ld-linux-x86-64.so.2 libc.so.6 libm.so.6 libmvec.so.1 libpthread.so.0 libdl.so.2 librt.so.1
       libresolv.so.2 libutil.so.1 libanl.so.1 libnsl.so.1 libBrokenLocale.so.1 libthread_db.so.1
       libc_malloc_debug.so.0 libnss_compat.so.2 libnss_dns.so.2 libnss_files.so.2
       libnss_hesiod.so.2 libmemusage.so libpcprofile.so linux-vdso.so.1)
# GL vendor and GPU driver libraries, by exact name, plus NVIDIA's libnvidia-* family: the
# node's driver provides them, matched to its kernel module.
vendor=(libEGL_mesa.so.0 libGLX_mesa.so.0 libOSMesa.so.8 libgallium_dri.so libglapi.so.0
        libEGL_nvidia.so.0 libGLX_nvidia.so.0 libGLESv2_nvidia.so.2 libGLESv1_CM_nvidia.so.1
        libcuda.so.1 libnvcuvid.so.1 libnvoptix.so.1)
is_excluded() {
  local base=$1 n
  for n in "${glibc[@]}" "${vendor[@]}"; do [[ $base == "$n" ]] && return 0; done
  [[ $base == libnvidia-*.so* ]] && return 0
  return 1
}

# The dispatchers the binary dlopens (not in its ELF dependencies): libglvnd's libEGL and
# libOpenGL/libGL, with what they need.
libdir=$(dirname "$(ldconfig -p | awk '/libEGL.so.1 \(libc6,x86-64\)/ {print $NF; exit}')")
dlopened=()
for lib in libEGL.so.1 libOpenGL.so.0 libGL.so.1 libGLX.so.0 libGLdispatch.so.0; do
  if [[ -e $libdir/$lib ]]; then
    dlopened+=("$libdir/$lib")
  else
    echo "bundle: $libdir/$lib missing (Debian: libegl1 libglvnd0 libopengl0 libgl1 libglx0)" >&2
    exit 2
  fi
done

# Everything ldd resolves for the binary and the dispatchers, minus the exclusions.
declare -A wanted=()
missing=()
for object in "$binary" "${dlopened[@]}"; do
  while read -r line; do
    case $line in
      *"=> not found"*) missing+=("${line%% *}") ;;
      *"=> /"*)
        lib=${line%% =>*}; path=${line#*=> }; path=${path%% (*}
        is_excluded "$lib" || wanted[$lib]=$path ;;
    esac
  done < <(ldd "$object")
  base=$(basename "$object")
  [[ $object == "$binary" ]] || wanted[$base]=$object
done
if ((${#missing[@]})); then
  echo "bundle: the build machine itself cannot resolve: ${missing[*]}" >&2
  exit 1
fi
for lib in "${!wanted[@]}"; do
  cp -L "${wanted[$lib]}" "$root/lib/$lib"
done
cp "$binary" "$root/bin/fetchscope"
cp models/*.xml "$root/bin/models/"
# the font the labels are drawn with (render/text.h looks in <binary folder>/fonts/ first)
font=${FETCHSCOPE_FONT:-/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf}
if [[ ! -f $font ]]; then
  echo "bundle: $font missing (Debian: fonts-dejavu-core)" >&2
  exit 2
fi
cp -L "$font" "$root/bin/fonts/DejaVuSans.ttf"
strip --strip-unneeded "$root/bin/fetchscope" "$root"/lib/*.so* 2>/dev/null || true

# The C++ runtime goes to lib/cxx/: the launcher takes the node's own libstdc++/libgcc_s when it
# provides every version the bundle needs (a node's newer Mesa or driver may need its newer one;
# an older copy first on the path would break it), and the bundled pair only when it does not.
mkdir -p "$root/lib/cxx"
for lib in libstdc++.so.6 libgcc_s.so.1; do
  if [[ -e $root/lib/$lib ]]; then mv "$root/lib/$lib" "$root/lib/cxx/$lib"; fi
done
cxx_needed=$(objdump -T "$root/bin/fetchscope" "$root"/lib/*.so* 2>/dev/null |
  grep -o -E '(GLIBCXX|CXXABI)_[0-9][0-9.]*' | sort -u | sort -t_ -k1,1 -k2,2V |
  awk -F_ '{last[$1]=$0} END {for (k in last) print last[k]}' | sort | tr '\n' ' ')

# The newest glibc symbol version anything in the bundle needs: the node's glibc must be at
# least that.
glibc_needed=$(objdump -T "$root/bin/fetchscope" "$root"/lib/*.so* "$root"/lib/cxx/* 2>/dev/null |
  grep -o 'GLIBC_[0-9][0-9.]*' | sed 's/GLIBC_//' | sort -t. -k1,1n -k2,2n | tail -1)

cat > "$root/fetchscope" <<'LAUNCHER'
#!/bin/sh
# fetchscope from a relocatable bundle: the bundled libraries first on the library path.
here=$(dirname "$(readlink -f "$0")")
# the caller's own library path, restored for programs fetchscope starts (exec: policies)
export FETCHSCOPE_CALLER_LD_LIBRARY_PATH="${LD_LIBRARY_PATH-__unset__}"
# the C++ runtime: the node's when it has every version fetchscope needs, else the bundled one
# (FETCHSCOPE_HOST_LIBSTDCXX names the node's copy to check instead of searching for it)
cxx_needed="@CXX_NEEDED@"
cxx_dir="$here/lib/cxx"
if [ -n "${FETCHSCOPE_HOST_LIBSTDCXX+set}" ]; then
  candidates=$FETCHSCOPE_HOST_LIBSTDCXX
else
  candidates="$( (ldconfig -p || /sbin/ldconfig -p) 2>/dev/null |
    awk '/libstdc\+\+\.so\.6 \(libc6,x86-64\)/ {print $NF}')
    /lib/x86_64-linux-gnu/libstdc++.so.6 /usr/lib64/libstdc++.so.6"
fi
for host in $candidates; do
  [ -f "$host" ] || continue
  ok=1
  for v in $cxx_needed; do grep -qaF "$v" "$host" || { ok=""; break; }; done
  if [ -n "$ok" ]; then cxx_dir=""; break; fi
done
export LD_LIBRARY_PATH="$here/lib${cxx_dir:+:$cxx_dir}${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
# libglvnd finds the NVIDIA EGL driver through a vendor file; container runtimes put it in
# different places. Point at one when none of the standard folders holds any.
if [ -z "${__EGL_VENDOR_LIBRARY_FILENAMES:-}" ] && [ -z "${__EGL_VENDOR_LIBRARY_DIRS:-}" ]; then
  found=""
  for d in /etc/glvnd/egl_vendor.d /usr/share/glvnd/egl_vendor.d /usr/local/share/glvnd/egl_vendor.d; do
    for f in "$d"/*.json; do [ -f "$f" ] && found=1; done
  done
  if [ -z "$found" ]; then
    for f in /usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json \
             /usr/lib/x86_64-linux-gnu/nvidia/egl_vendor.d/10_nvidia.json; do
      if [ -f "$f" ]; then export __EGL_VENDOR_LIBRARY_FILENAMES="$f"; break; fi
    done
  fi
fi
exec "$here/bin/fetchscope" "$@"
LAUNCHER
sed -i "s/@CXX_NEEDED@/${cxx_needed% }/" "$root/fetchscope"
chmod +x "$root/fetchscope"

cat > "$root/README.txt" <<README
fetchscope $version for Linux x86_64, relocatable.

Run ./fetchscope (the launcher; it puts lib/ on the library path, and lib/cxx/ too when the
node's own C++ runtime lacks ${cxx_needed% }). Needs glibc >= $glibc_needed on the node, and for rendering an NVIDIA driver (EGL) or the node's Mesa (libegl-mesa0 or
libosmesa6): GL vendor libraries are never bundled. First on a new node:
  ./fetchscope list-gpus
Record on a node (all its usable cores, CUDA's GPU numbering when CUDA_VISIBLE_DEVICES is set):
  ./fetchscope record --env-id FetchPush-v4 --episodes 64 --jobs 0 --out runs/push
Under Slurm, one array task per GPU (Slurm sets CUDA_VISIBLE_DEVICES and the cpuset):
  #SBATCH --gpus=1 --cpus-per-task=16 --array=0-7
  srun ./fetchscope record --env-id FetchPush-v4 --episodes 512 --jobs 0 --out runs/push
  (each task records the episodes of its shard, from SLURM_ARRAY_TASK_ID/COUNT; afterwards
   ./fetchscope merge-manifests runs/push)
./fetchscope record --help and the project's README (section "GPU nodes") say more.
Bundled libraries keep their own licences (Debian packages: see the copyright files of
libavcodec59, libavfilter8, libmujoco2.2.2, libpng16-16, libssl3, libfreetype6,
libfontconfig1, libglvnd0 and their dependencies). bin/fonts/DejaVuSans.ttf is from
fonts-dejavu-core (Bitstream Vera / DejaVu licence).
README

mkdir -p "$dist"
out=$dist/$name.tar.xz
tmp_out=$(mktemp "$dist/.$name.XXXXXX")
tar -C "$stage" -cf - "$name" | xz -T0 -"${XZ_LEVEL:-6}" > "$tmp_out"
chmod 0644 "$tmp_out"  # mktemp made it 0600; a release file is readable by everyone
mv "$tmp_out" "$out"
echo "bundle: $out ($(du -h "$out" | cut -f1), ${#wanted[@]} libraries, needs glibc >= $glibc_needed)"
