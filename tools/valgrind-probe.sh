#!/usr/bin/env bash
# Can valgrind run this program on this host? Runs it under valgrind's no-op tool (no checking,
# a few seconds) and tells a program valgrind cannot decode from one that merely fails:
#   tools/valgrind-probe.sh PROGRAM [ARGS...]
# Exit 0: valgrind ran it to its end (whatever its own exit status). Exit 3, with one line on
# stdout saying why: valgrind cannot run it here. Debian 12's valgrind 3.19 decodes RDTSCP only
# where the CPU advertises it (CPUID), and some hypervisors hide it on AMD EPYC hosts whose cores
# still execute it; Highway (libhwy, which libavcodec loads through libjxl) executes RDTSCP in a
# static constructor, so there valgrind stops every program that loads libavcodec with
# "vex amd64->IR: unhandled instruction bytes: 0xF 0x1 0xF9" and SIGILL before main.
# Exit 2: no valgrind, or no such program.
set -uo pipefail
[[ $# -ge 1 ]] || { echo "usage: tools/valgrind-probe.sh PROGRAM [ARGS...]" >&2; exit 2; }
command -v valgrind >/dev/null || { echo "valgrind-probe: valgrind is not installed"; exit 2; }
command -v "$1" >/dev/null || { echo "valgrind-probe: no program '$1'"; exit 2; }
log=$(mktemp)
trap 'rm -f "$log"' EXIT
# in a subshell whose stderr goes nowhere (the shell's "Illegal instruction" notice too) and
# which waits for valgrind rather than becoming it (the trailing ':')
(exec 2>/dev/null; valgrind --tool=none --log-file="$log" "$@" >/dev/null </dev/null; :)
# the bytes VEX could not decode, as it prints them ("0xF 0x1 0xF9 ..."), first three only
bytes=$(sed -n 's/.*unhandled instruction bytes: \(0x[0-9A-F]* 0x[0-9A-F]* 0x[0-9A-F]*\).*/\1/p' \
  "$log" | head -1)
if [[ -n "$bytes" ]] || grep -q "Process terminating with default action of signal 4" "$log"; then
  what="instruction bytes ${bytes:-unknown}"
  [[ "$bytes" == "0xF 0x1 0xF9" ]] && what="RDTSCP (0xF 0x1 0xF9), which this CPU does not advertise"
  # who executed it: the first frame valgrind names under the SIGILL, e.g. libhwy's TimerResolution
  where=$(grep -m1 -A1 "Illegal opcode at address" "$log" | sed -n 's/.*: \(.*\)$/\1/p' | tail -1)
  echo "valgrind $(valgrind --version | sed 's/^valgrind-//') cannot run $(basename "$1") on this" \
    "host: it does not decode $what${where:+, executed by $where}"
  exit 3
fi
exit 0
