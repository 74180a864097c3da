#!/usr/bin/env bash
# A one-node Slurm cluster on this machine, for tests/test_sweep_slurm (Debian's slurm-wlm and
# munge). Everything lives under DIR: configuration, state, logs, pid files.
#   local_slurm.sh start DIR   starts munged, slurmctld and slurmd; exit 0 when the node is idle,
#                              else non-zero with the reason on stderr (the test is then skipped)
#   local_slurm.sh stop DIR    stops them
# The environment of the caller must set SLURM_CONF=DIR/slurm.conf to talk to this cluster.
set -u
cmd=${1:-}; dir=${2:-}
[ -n "$cmd" ] && [ -n "$dir" ] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }
mkdir -p "$dir"
dir=$(cd "$dir" && pwd)

stop() {
  for p in slurmd slurmctld munged; do
    [ -f "$dir/$p.pid" ] && kill "$(cat "$dir/$p.pid")" 2>/dev/null
  done
  sleep 1
  for p in slurmd slurmctld munged; do
    [ -f "$dir/$p.pid" ] && kill -9 "$(cat "$dir/$p.pid")" 2>/dev/null
    rm -f "$dir/$p.pid"
  done
  return 0
}

if [ "$cmd" = stop ]; then stop; exit 0; fi
[ "$cmd" = start ] || { echo "usage: $0 start|stop DIR" >&2; exit 2; }

for b in munged mungekey slurmctld slurmd sinfo sbatch; do
  command -v "$b" >/dev/null 2>&1 || { echo "$b not found (Debian packages slurm-wlm and munge)" >&2; exit 3; }
done
[ "$(id -u)" = 0 ] || { echo "a local slurmd needs root (running as uid $(id -u))" >&2; exit 3; }

host=$(hostname -s)
cpus=$(nproc)
mem_mb=$(awk '/MemTotal/ {print int($2 / 1024)}' /proc/meminfo)
user=$(id -un)
mkdir -p "$dir/munge" "$dir/state" "$dir/spool" "$dir/log"
chmod 700 "$dir/munge"
[ -f "$dir/munge/munge.key" ] || mungekey -c -k "$dir/munge/munge.key" -b 1024 >/dev/null 2>&1 \
  || dd if=/dev/urandom of="$dir/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$dir/munge/munge.key"
munged --key-file="$dir/munge/munge.key" --socket="$dir/munge/munge.socket" \
  --pid-file="$dir/munged.pid" --log-file="$dir/log/munged.log" --seed-file="$dir/munge/seed" -f \
  || { echo "munged did not start (see $dir/log/munged.log)" >&2; exit 4; }

cat > "$dir/slurm.conf" <<CONF
ClusterName=stokesian-test
SlurmctldHost=$host
SlurmUser=$user
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$dir/munge/munge.socket
CredType=cred/munge
SlurmctldPort=16817
SlurmdPort=16818
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/log/slurmctld.log
SlurmdLogFile=$dir/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
NodeName=$host CPUs=$cpus RealMemory=$mem_mb State=UNKNOWN
PartitionName=test Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$dir/slurm.conf"
slurmctld -f "$dir/slurm.conf" -i >/dev/null 2>&1 || { echo "slurmctld did not start (see $dir/log/slurmctld.log)" >&2; stop; exit 4; }
slurmd -f "$dir/slurm.conf" >/dev/null 2>&1 || { echo "slurmd did not start (see $dir/log/slurmd.log)" >&2; stop; exit 4; }
for _ in $(seq 1 60); do
  state=$(sinfo -h -N -o %T 2>/dev/null | head -1)
  case "$state" in idle*|mix*) exit 0 ;; esac
  sleep 0.5
done
echo "the local Slurm node did not become idle (state \"$state\"; logs in $dir/log)" >&2
stop
exit 5
