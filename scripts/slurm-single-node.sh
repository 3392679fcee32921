#!/usr/bin/env bash
# A single-node Slurm cluster on this machine, for the test of the README's array-job example
# (tests/slurm.rs) and for trying sharded batches by hand. Debian's slurm-wlm and munge must be
# installed (.ci/run installs them). Runs as root; every file lives under STATE_DIR.
#
#   scripts/slurm-single-node.sh start STATE_DIR   # munged, slurmctld and slurmd; waits until idle
#   SLURM_CONF=STATE_DIR/slurm.conf sbatch ...      # then submit as usual
#   scripts/slurm-single-node.sh stop STATE_DIR
#
# Process tracking without cgroups (proctrack/linuxproc, task/none), so it runs in containers.
set -euo pipefail
cmd=${1:?usage: slurm-single-node.sh start|stop STATE_DIR}
dir=$(realpath -m "${2:?usage: slurm-single-node.sh start|stop STATE_DIR}")
node=$(hostname -s)

# Daemons are found by their command lines, which name STATE_DIR, so a cluster whose folder was
# deleted under it still stops.
stop() {
  for daemon in slurmd slurmctld munged; do
    pkill -f -- "^[^ ]*$daemon .*$dir/" 2>/dev/null || true
  done
  for _ in $(seq 1 50); do
    pgrep -f -- "^[^ ]*(slurmd|slurmctld|munged) .*$dir/" >/dev/null || break
    sleep 0.1
  done
  rm -f "$dir"/*.pid
}

case $cmd in
stop) stop; exit 0 ;;
start) ;;
*) echo "slurm-single-node.sh: unknown command $cmd (start or stop)" >&2; exit 2 ;;
esac

for tool in munged slurmctld slurmd sinfo; do
  command -v "$tool" >/dev/null || { echo "slurm-single-node.sh: $tool is not installed (Debian: apt-get install slurm-wlm munge)" >&2; exit 1; }
done
stop
mkdir -p "$dir"/state "$dir"/spool "$dir"/munge
chmod 700 "$dir"/munge

# munge: a key of our own and a socket under STATE_DIR, so a system munged is left alone.
key=$dir/munge/munge.key
[[ -f $key ]] || dd if=/dev/urandom of="$key" bs=1024 count=1 status=none
chmod 400 "$key"
socket=$dir/munge/munge.socket
# The daemons' standard streams go nowhere: a caller reading this script's output would
# otherwise wait for daemons that never close it.
munged --force --key-file="$key" --socket="$socket" --pid-file="$dir/munged.pid" \
  --log-file="$dir/munged.log" --seed-file="$dir/munge/munge.seed" </dev/null >/dev/null 2>&1

cpus=$(nproc)
cat >"$dir/slurm.conf" <<CONF
ClusterName=terrain-test
SlurmctldHost=$node
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$socket
CredType=cred/munge
StateSaveLocation=$dir/state
SlurmdSpoolDir=$dir/spool
SlurmctldPidFile=$dir/slurmctld.pid
SlurmdPidFile=$dir/slurmd.pid
SlurmctldLogFile=$dir/slurmctld.log
SlurmdLogFile=$dir/slurmd.log
SlurmctldPort=16817
SlurmdPort=16818
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
ReturnToService=2
SchedulerType=sched/backfill
NodeName=$node CPUs=$cpus State=UNKNOWN
PartitionName=local Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$dir/slurm.conf
slurmctld -i -f "$SLURM_CONF" </dev/null >/dev/null 2>&1
slurmd -f "$SLURM_CONF" </dev/null >/dev/null 2>&1
for _ in $(seq 1 60); do
  if sinfo -h -o %t 2>/dev/null | grep -qx idle; then
    echo "slurm: node $node idle; SLURM_CONF=$SLURM_CONF"
    exit 0
  fi
  sleep 0.5
done
echo "slurm-single-node.sh: the node did not come up within 30 s; see $dir/slurmctld.log and $dir/slurmd.log" >&2
sinfo >&2 || true
exit 1
