#!/usr/bin/env bash
# A one-node Slurm for tests/slurm_test.cc, everything under one folder:
#   tests/slurm/local_cluster.sh start DIR   munged, slurmctld and slurmd started in the background,
#                                            returns once sinfo shows the node idle; prints the
#                                            environment to use it (SLURM_CONF=..., PATH=...)
#   tests/slurm/local_cluster.sh stop DIR    stops them by the PIDs start wrote in DIR/pids
# Needs root (SlurmUser=root, munged's key) and Debian's slurm-wlm and munge. No accounting, no
# cgroups (ProctrackType=proctrack/linuxproc, TaskPlugin=task/none), ports away from the defaults.
set -euo pipefail
cmd=${1:?start or stop}
dir=${2:?folder}
dir=$(cd "$dir" && pwd)

stop() {
  [[ -f $dir/pids ]] || return 0
  local pid
  # slurmd first (it ends the steps it runs), then slurmctld, then munged
  for pid in $(tac "$dir/pids"); do kill -TERM "$pid" 2>/dev/null || true; done
  for _ in $(seq 50); do
    local alive=0
    for pid in $(cat "$dir/pids"); do kill -0 "$pid" 2>/dev/null && alive=1; done
    [[ $alive == 0 ]] && break
    sleep 0.1
  done
  for pid in $(cat "$dir/pids"); do kill -KILL "$pid" 2>/dev/null || true; done
  rm -f "$dir/pids"
}

if [[ $cmd == stop ]]; then
  stop
  exit 0
fi
[[ $cmd == start ]] || { echo "local_cluster.sh: unknown command '$cmd' (start, stop)" >&2; exit 2; }

for tool in munged slurmctld slurmd sinfo sbatch; do
  command -v "$tool" >/dev/null || PATH=$PATH:/usr/sbin
  command -v "$tool" >/dev/null || { echo "local_cluster.sh: $tool is not installed" >&2; exit 3; }
done
node=$(hostname -s)
cpus=$(nproc --all)
mkdir -p "$dir"/{munge,run,spool/ctld,spool/d,log}
chmod 700 "$dir/munge"
chmod 755 "$dir/run"  # munged's socket folder: clients must reach the socket
dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge/munge.key"
# ports from the folder's name, away from Slurm's 6817/6818 and from one another's
base=$((20000 + $(cksum <<<"$dir" | cut -d' ' -f1) % 20000))
cat >"$dir/slurm.conf" <<CONF
ClusterName=fetchscope-test
SlurmctldHost=$node
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$base
SlurmdPort=$((base + 1))
AuthType=auth/munge
AuthInfo=socket=$dir/run/munge.socket
CredType=cred/munge
StateSaveLocation=$dir/spool/ctld
SlurmdSpoolDir=$dir/spool/d
SlurmctldPidFile=$dir/run/slurmctld.pid
SlurmdPidFile=$dir/run/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
ReturnToService=2
SchedulerParameters=sched_interval=1
MessageTimeout=10
KillWait=5
InactiveLimit=0
MinJobAge=300
NodeName=$node CPUs=$cpus State=UNKNOWN
PartitionName=test Nodes=$node Default=YES MaxTime=INFINITE State=UP OverSubscribe=YES
CONF
: >"$dir/pids"
export SLURM_CONF=$dir/slurm.conf
munged --key-file="$dir/munge/munge.key" --socket="$dir/run/munge.socket" \
  --pid-file="$dir/run/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/seed" \
  --force
for _ in $(seq 50); do [[ -s $dir/run/munged.pid ]] && break; sleep 0.1; done
cat "$dir/run/munged.pid" >>"$dir/pids"
slurmctld -D -f "$dir/slurm.conf" >"$dir/log/slurmctld.out" 2>&1 &
echo $! >>"$dir/pids"
slurmd -D -f "$dir/slurm.conf" >"$dir/log/slurmd.out" 2>&1 &
echo $! >>"$dir/pids"
for _ in $(seq 300); do
  if [[ $(sinfo -h -n "$node" -o %t 2>/dev/null) == idle ]]; then
    echo "SLURM_CONF=$dir/slurm.conf"
    exit 0
  fi
  sleep 0.1
done
echo "local_cluster.sh: the node never became idle; logs in $dir/log:" >&2
tail -n 5 "$dir"/log/* >&2 || true
stop
exit 1
