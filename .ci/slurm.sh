#!/usr/bin/env bash
# CI step: a sharded campaign through a real single-node Slurm cluster (slurmctld +
# slurmd on localhost, munge authentication). Submits the job array of 4 shards and the
# dependent merge written by `fathom campaign slurm`, waits for them, and checks that
# the merged summary.json equals the single-process one byte for byte.
#
# Needs root and apt-get (to install slurm-wlm and munge and to start the daemons);
# where either is missing it says so and exits 0 without running (never silently).
set -euo pipefail
cd "$(dirname "$0")/.."

SCENARIO=scenarios/beacons.toml
RUNS=40
SHARDS=4
start=$(date +%s)

if [ "$(id -u)" != 0 ]; then
  echo "SKIPPED: the Slurm step needs root (to install slurm-wlm/munge and start slurmctld/slurmd); running as uid $(id -u)"
  exit 0
fi
if ! command -v slurmctld >/dev/null || ! command -v munged >/dev/null; then
  if ! command -v apt-get >/dev/null; then
    echo "SKIPPED: slurm-wlm/munge are not installed and there is no apt-get to install them"
    exit 0
  fi
  echo "installing slurm-wlm and munge"
  DEBIAN_FRONTEND=noninteractive apt-get update -q >/dev/null
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q slurm-wlm munge >/dev/null
fi

# the release binary (already built by .ci/python.sh when called from .ci/run)
cargo build --release -q -p fathom-cli --bin fathom
FATHOM="$(realpath -m "${CARGO_TARGET_DIR:-target}")/release/fathom"

work=$(mktemp -d /tmp/fathom-slurm.XXXXXX)
pids=()
cleanup() {
  for pid in "${pids[@]}"; do kill "$pid" 2>/dev/null || true; done
  wait 2>/dev/null || true
}
trap cleanup EXIT

# munge: one key on this machine (the package's postinst writes it; create it if absent)
if [ ! -s /etc/munge/munge.key ]; then
  mungekey --create --keyfile=/etc/munge/munge.key 2>/dev/null ||
    dd if=/dev/urandom bs=1 count=1024 of=/etc/munge/munge.key 2>/dev/null
  chown munge:munge /etc/munge/munge.key
  chmod 400 /etc/munge/munge.key
fi
if ! munge -n >/dev/null 2>&1; then
  mkdir -p /run/munge /var/log/munge /var/lib/munge
  chown munge:munge /run/munge /var/log/munge /var/lib/munge
  runuser -u munge -- /usr/sbin/munged
  for _ in $(seq 50); do munge -n >/dev/null 2>&1 && break; sleep 0.1; done
fi
munge -n | unmunge >/dev/null

node=$(hostname -s)
cpus=$(nproc)
export SLURM_CONF="$work/slurm.conf"
mkdir -p "$work/state" "$work/spool"
cat >"$SLURM_CONF" <<EOF
ClusterName=fathomci
SlurmctldHost=${node}(127.0.0.1)
SlurmUser=root
SlurmdUser=root
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
StateSaveLocation=$work/state
SlurmdSpoolDir=$work/spool
SlurmctldPidFile=$work/slurmctld.pid
SlurmdPidFile=$work/slurmd.pid
SlurmctldLogFile=$work/slurmctld.log
SlurmdLogFile=$work/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
MinJobAge=3600
NodeName=${node} NodeAddr=127.0.0.1 CPUs=${cpus} State=UNKNOWN
PartitionName=ci Nodes=${node} Default=YES MaxTime=INFINITE State=UP
EOF

/usr/sbin/slurmctld -D -i -f "$SLURM_CONF" >"$work/slurmctld.out" 2>&1 &
pids+=($!)
/usr/sbin/slurmd -D -N "$node" -f "$SLURM_CONF" >"$work/slurmd.out" 2>&1 &
pids+=($!)
ready=
for _ in $(seq 100); do
  if sinfo -h -o '%T' 2>/dev/null | grep -qE '^(idle|mixed|allocated)'; then ready=1; break; fi
  sleep 0.2
done
if [ -z "$ready" ]; then
  echo "FAILED: the single-node Slurm cluster did not come up"
  sinfo 2>&1 || true
  tail -n 20 "$work/slurmctld.log" "$work/slurmd.log" 2>/dev/null || true
  exit 1
fi
echo "slurm $(sinfo -V): node $node with $cpus CPUs is up"

# The campaign as a user runs it: the script `fathom campaign slurm` writes, then sbatch.
campaign="$work/campaign"
"$FATHOM" campaign slurm "$SCENARIO" --runs "$RUNS" --shards "$SHARDS" --dir "$campaign"
submitted=$(FATHOM="$FATHOM" bash "$campaign/campaign.sh")
echo "$submitted"
merge_job=$(echo "$submitted" | sed -n 's/.* and merge \([0-9]*\).*/\1/p')

state=
for _ in $(seq 1800); do
  state=$(scontrol show job "$merge_job" 2>/dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p')
  case "$state" in
    COMPLETED | FAILED | CANCELLED | TIMEOUT | NODE_FAIL | OUT_OF_MEMORY) break ;;
  esac
  sleep 1
done
if [ "$state" != COMPLETED ]; then
  echo "FAILED: the merge job $merge_job ended as '${state:-unknown}'"
  squeue 2>&1 || true
  tail -n 20 "$campaign"/logs/*.out 2>/dev/null || true
  exit 1
fi
for task in $(seq 0 $((SHARDS - 1))); do
  test -s "$campaign/shard-$task/manifest.json" || {
    echo "FAILED: shard $task wrote no manifest"
    exit 1
  }
done

"$FATHOM" run "$SCENARIO" --runs "$RUNS" --out "$work/single" >/dev/null
if cmp "$work/single/summary.json" "$campaign/merged/summary.json"; then
  echo "OK: $SHARDS Slurm array tasks + the dependent merge give the single-process summary.json byte for byte"
else
  echo "FAILED: the merged summary.json differs from the single-process one"
  exit 1
fi
echo "slurm step wall time: $(($(date +%s) - start)) s"
