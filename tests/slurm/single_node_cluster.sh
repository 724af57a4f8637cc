#!/usr/bin/env bash
# A real Slurm run on one node (issue 17): starts munged, slurmctld and slurmd with a generated
# single-node configuration in a temporary folder (their own ports on 127.0.0.1, state and log folders,
# munge socket), submits `caustics sweep SPEC --slurm 3`, waits (bounded) for the merge job, checks the
# merged result and the report, and stops exactly the daemons it started, by their process ids.
#
# Usage: single_node_cluster.sh CAUSTICS_BINARY SOURCE_DIR [TASKS...]
# Exit 77 (ctest: skipped, with the reason printed) when the daemons cannot be started (not root, the
# packages missing); never passes without having run the jobs.
set -euo pipefail
bin=$1
src=$2
shift 2
tasks=("${@:-3}")

skip() { echo "SKIPPED: $*"; exit 77; }
[ "$(id -u)" = 0 ] || skip "starting munged, slurmctld and slurmd needs root (CI runs as root)"
for p in munged slurmctld slurmd sbatch squeue; do
  command -v "$p" >/dev/null || [ -x "/usr/sbin/$p" ] || skip "$p is missing: scripts/setup.sh installs slurm-wlm and munge"
done
export PATH=$PATH:/usr/sbin

tmp=$(mktemp -d /tmp/caustics-slurm-XXXXXX)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2>/dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2>/dev/null || true
  done
  rm -rf "$tmp"
}
trap cleanup EXIT

# Free ports: the kernel picks them.
port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
ctld_port=$(port)
slurmd_port=$(port)
node=$(hostname -s)
cpus=$(nproc)
mem=$(( $(awk '/MemTotal/ {print $2}' /proc/meminfo) / 1024 / 2 ))
mkdir -p "$tmp"/{state,spool,log,munge}
chmod 700 "$tmp/munge"

# munge: its own key, socket and files.
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
munged --force --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/socket" --pid-file="$tmp/munge/munged.pid" \
  --log-file="$tmp/log/munged.log" --seed-file="$tmp/munge/seed"
for _ in $(seq 50); do [ -s "$tmp/munge/munged.pid" ] && break; sleep 0.1; done
[ -s "$tmp/munge/munged.pid" ] || { cat "$tmp/log/munged.log"; skip "munged did not start"; }
pids+=("$(cat "$tmp/munge/munged.pid")")

cat > "$tmp/slurm.conf" <<CONF
ClusterName=caustics-test
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
AuthInfo=socket=$tmp/munge/socket
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
SchedulerType=sched/backfill
MpiDefault=none
ReturnToService=2
JobCompType=jobcomp/none
AccountingStorageType=accounting_storage/none
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
MinJobAge=300
NodeName=$node NodeAddr=127.0.0.1 CPUs=$cpus RealMemory=$mem State=UNKNOWN
PartitionName=test Nodes=$node Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF=$tmp/slurm.conf
slurmctld -f "$SLURM_CONF" -i
for _ in $(seq 100); do [ -s "$tmp/slurmctld.pid" ] && break; sleep 0.1; done
[ -s "$tmp/slurmctld.pid" ] || { cat "$tmp/log/slurmctld.log"; skip "slurmctld did not start"; }
pids+=("$(cat "$tmp/slurmctld.pid")")
slurmd -f "$SLURM_CONF" -N "$node"
for _ in $(seq 100); do [ -s "$tmp/slurmd.pid" ] && break; sleep 0.1; done
[ -s "$tmp/slurmd.pid" ] || { cat "$tmp/log/slurmd.log"; skip "slurmd did not start"; }
pids+=("$(cat "$tmp/slurmd.pid")")
for _ in $(seq 100); do sinfo -h -o %t 2>/dev/null | grep -q idle && break; sleep 0.2; done
sinfo -h -o %t | grep -q idle || { sinfo; tail -20 "$tmp/log/slurmctld.log"; echo "FAILED: the node never became idle"; exit 1; }

cat > "$tmp/small.json" <<'SPEC'
{"scenes": ["sine", "flat_oblique"], "reference": {"photons": 20000, "replicas": 4},
 "timing": {"warmup": 0, "repeats": 1, "max_time_s": 0.2},
 "methods": {"caustic_triangles": {"grid": [16, 32, 64]}, "caustic_mapping": {"grid": [32], "iterations": [1, 2]}}}
SPEC
cd "$tmp"
for n in "${tasks[@]}"; do
  out=$tmp/out$n
  start=$(date +%s.%N)
  "$bin" sweep small.json --out "$out" --cache "$tmp/cache" --slurm "$n" --threads 1
  # Bounded wait for the merge job (the manifest with its `shards` list is written last).
  for _ in $(seq 600); do
    [ -f "$out/report.md" ] && break
    sleep 0.5
  done
  end=$(date +%s.%N)
  if [ ! -f "$out/report.md" ]; then
    squeue; ls -R "$out" | head -40; cat "$out"/slurm/*.log 2>/dev/null | tail -40; tail -20 "$tmp/log/slurmctld.log"
    echo "FAILED: no merged report after 300 s ($n tasks)"; exit 1
  fi
  rows=$(wc -l < "$out/results.jsonl")
  shards=$(python3 -c "import json; print(len(json.load(open('$out/manifest.json'))['shards']))")
  [ "$rows" = 10 ] || { echo "FAILED: $rows merged rows, expected 10"; exit 1; }
  [ "$shards" = "$n" ] || { echo "FAILED: $shards shards merged, expected $n"; exit 1; }
  grep -q '"SLURM_ARRAY_TASK_ID"' "$out/manifest.json" || { echo "FAILED: the manifest records no Slurm task"; exit 1; }
  echo "slurm: $n array tasks: 10 runs merged and reported in $(python3 -c "print(f'{$end - $start:.1f}')") s"
done
echo "PASSED"
