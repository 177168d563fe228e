#!/usr/bin/env bash
# examples/slurm/sweep.sbatch on a real Slurm: starts munged and a
# single-node cluster (slurmctld and slurmd on 127.0.0.1, a generated
# slurm.conf, everything under one temporary folder), submits the example
# as a 4-task array over 8 seeds, waits for it, merges the shards and
# requires the merged table to equal the same sweep on one machine, byte
# for byte. Needs root and Debian's slurm-wlm and munge (.ci/run installs
# them); bounded to four minutes; the daemons are stopped and the folder
# removed however it ends. Run from anywhere:
#
#     tests/slurm.sh            # uses target/debug/ctlgraph, or $CTLGRAPH_BIN
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
bin="${CTLGRAPH_BIN:-$root/target/debug/ctlgraph}"
work="$(mktemp -d)"
stop() {
    for pid in slurmd slurmctld munged; do
        [ -f "$work/$pid.pid" ] && kill "$(cat "$work/$pid.pid")" 2> /dev/null || true
    done
    sleep 1
    rm -rf "$work"
}
trap stop EXIT
fail() {
    echo "slurm test: $1" >&2
    tail -n 20 "$work"/*.log >&2 || true
    exit 1
}

# munge: a fresh key and a daemon of our own on its own socket.
mkdir -m 755 "$work/munge" "$work/state" "$work/spool"
mungekey --create --keyfile="$work/munge/munge.key" --force
chmod 600 "$work/munge/munge.key"
munged --force --socket="$work/munge/socket" --key-file="$work/munge/munge.key" \
    --log-file="$work/munged.log" --pid-file="$work/munged.pid" --seed-file="$work/munge/seed"

node="$(hostname -s)"
cat > "$work/slurm.conf" << CONF
ClusterName=ctlgraph
SlurmctldHost=$node(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
AuthInfo=socket=$work/munge/socket
CredType=cred/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MpiDefault=none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
NodeName=$node NodeAddr=127.0.0.1 CPUs=2 State=UNKNOWN
PartitionName=ctlgraph Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$work/slurm.conf"
slurmctld || fail "slurmctld did not start"
slurmd || fail "slurmd did not start"
for _ in $(seq 30); do
    sinfo -h -o %t 2> /dev/null | grep -q idle && break
    sleep 1
done
sinfo -h -o %t | grep -q idle || fail "the node did not come up"

# The example as a user submits it, from a folder holding the graphs, with
# `ctlgraph` on the PATH.
mkdir "$work/bin" "$work/run"
ln -s "$bin" "$work/bin/ctlgraph"
ln -s "$root/graphs" "$work/run/graphs"
export PATH="$work/bin:$PATH"
cd "$work/run"
SHARDS=4 SEEDS=1..8 timeout 240 sbatch --wait --quiet --array=0-3 "$root/examples/slurm/sweep.sbatch" \
    || fail "the array did not finish"
ctlgraph sweep merge out/seeds-*.csv --out merged.csv > /dev/null
ctlgraph sweep graphs/fladrc/compare.yaml --seeds 1..8 --out single.csv > /dev/null
cmp merged.csv single.csv || fail "the merged table differs from one machine's"
rows=$(($(wc -l < merged.csv) - 1))
[ "$rows" -eq 8 ] || fail "the merged table has $rows rows, not 8"
echo "slurm: 4 array tasks on a single-node cluster, merged table = one machine's (8 cases), byte for byte"
