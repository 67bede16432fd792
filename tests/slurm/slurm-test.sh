#!/usr/bin/env bash
# The Slurm test of issue 10 (opt-in: `make test-slurm`; docs/slurm.md). Brings up a one-node Slurm
# cluster on this machine from Debian packages (munge, slurmctld, slurmd, slurm-client): daemons
# started as plain processes (no systemd), configuration in a temporary folder (SLURM_CONF),
# localhost only, proctrack/linuxproc and task/none (no cgroups). Then submits the quick preset
# at 48x27 as a job array of SHARDS shards plus the dependent merge job (scripts/slurm/submit.sh),
# waits, runs the same matrix on one machine, and checks that the merged result equals it cell for
# cell: keys and order hashes, ANC, SIMT model and status exactly (the rules scripts/golden.sh
# uses), no cell missing on either side, and timings present in every merged cell.
# The daemons are stopped (by their process ids) on every exit, failure included.
#
#   tests/slurm/slurm-test.sh RAYSORT_BIN [SHARDS]     as root (re-runs itself under sudo otherwise)
set -euo pipefail
bin="$(realpath "${1:?usage: slurm-test.sh RAYSORT_BIN [SHARDS]}")"
shards="${2:-3}"
root="$(cd "$(dirname "$0")/../.." && pwd)"
run_args=(--preset quick --resolution 48x27 --reps 1 --warmup 0)

# slurmd must run as root to start jobs; so do the daemons here.
if [ "$(id -u)" -ne 0 ]; then exec sudo -E bash "$0" "$@"; fi

# --- Debian packages (installed here, not in scripts/install-deps.sh: only this test needs them) ---
need=()
for p in munge slurmctld slurmd slurm-client; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || need+=("$p")
done
if [ "${#need[@]}" -gt 0 ]; then
  echo "slurm-test: installing ${need[*]}"
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -q
  apt-get install -y -q --no-install-recommends "${need[@]}"
fi

# --- A cluster of one node in a temporary folder ------------------------------------------------
tmp="$(mktemp -d /tmp/raysort-slurm.XXXXXX)"
chmod 755 "$tmp"  # jobs read the binary's output folder below it
pids=()
teardown() {
  local rc=$?
  set +e
  # Jobs first (while slurmctld can still cancel them), then the daemons, by their process ids.
  if [ -n "${SLURM_CONF:-}" ] && [ -S "$tmp/munge/munge.sock" ]; then
    scancel --quiet --user=root 2> /dev/null
    for _ in $(seq 1 30); do [ -z "$(squeue -h 2> /dev/null)" ] && break; sleep 1; done
  fi
  for ((i = ${#pids[@]} - 1; i >= 0; --i)); do kill "${pids[i]}" 2> /dev/null; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 1 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
    kill -9 "$pid" 2> /dev/null
  done
  if [ "$rc" -ne 0 ]; then
    echo "slurm-test: FAILED (exit $rc); daemon logs:" >&2
    for f in "$tmp"/log/*.log "$tmp"/shared/run/logs/*.out; do
      [ -f "$f" ] && { echo "--- $f" >&2; tail -n 25 "$f" >&2; }
    done
  fi
  rm -rf "$tmp"
  exit "$rc"
}
trap teardown EXIT
trap 'exit 130' INT TERM

mkdir -p "$tmp/munge" "$tmp/log" "$tmp/state" "$tmp/spool" "$tmp/shared"
chmod 755 "$tmp/munge"  # clients reach the socket; the key itself is 0400
free_port() { python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'; }
ctld_port="$(free_port)"
slurmd_port="$(free_port)"
node="raysort-node"
host="$(hostname -s)"
# This machine's CPUs, sockets and memory as slurmd sees them ("CPUs=2 Boards=1 ... RealMemory=N").
hardware="$(slurmd -C | head -n 1 | sed 's/^NodeName=[^ ]* //')"

# munge: a fresh key, its socket in the temporary folder (Slurm finds it through AuthInfo).
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
munged --force --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/munge.sock" \
       --pid-file="$tmp/munge/munged.pid" --log-file="$tmp/log/munged.log" --seed-file="$tmp/munge/munged.seed" \
       --foreground > "$tmp/log/munged.out" 2>&1 &
pids+=($!)
for _ in $(seq 1 50); do [ -S "$tmp/munge/munge.sock" ] && break; sleep 0.1; done
munge --socket="$tmp/munge/munge.sock" -n | unmunge --socket="$tmp/munge/munge.sock" > /dev/null

export SLURM_CONF="$tmp/slurm.conf"
cat > "$SLURM_CONF" << EOF
ClusterName=raysort-test
SlurmctldHost=$host(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge/munge.sock
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
MpiDefault=none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
ReturnToService=2
MinJobAge=3600
MailProg=/bin/true
NodeName=$node NodeHostname=$host NodeAddr=127.0.0.1 $hardware State=UNKNOWN
PartitionName=cpu Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF

slurmctld -D -i -f "$SLURM_CONF" > "$tmp/log/slurmctld.out" 2>&1 &
pids+=($!)
slurmd -D -N "$node" -f "$SLURM_CONF" > "$tmp/log/slurmd.out" 2>&1 &
pids+=($!)
for _ in $(seq 1 60); do
  state="$(sinfo -h -N -o '%t' 2> /dev/null || true)"
  [ "$state" = idle ] && break
  sleep 1
done
[ "$state" = idle ] || { echo "slurm-test: node not idle after 60 s (state '$state')" >&2; exit 1; }
echo "slurm-test: cluster up: $(sinfo -h -o '%P %D node(s), %c CPUs, %T')"

# --- The sharded run through Slurm ----------------------------------------------------------------
out="$tmp/shared/run"
t0=$(date +%s.%N)
submit_out="$(bash "$root/scripts/slurm/submit.sh" --shards "$shards" --partition cpu --cpu --bin "$bin" --out "$out" \
              -- "${run_args[@]}")"
echo "$submit_out"
array_job="$(sed -n 's/^shards: job array \([0-9]*\).*/\1/p' <<< "$submit_out")"
merge_job="$(sed -n 's/^merge:  job \([0-9]*\).*/\1/p' <<< "$submit_out")"
[ -n "$array_job" ] && [ -n "$merge_job" ] || { echo "slurm-test: could not read the job ids" >&2; exit 1; }

job_state() { scontrol show job "$1" 2> /dev/null | sed -n 's/.*JobState=\([A-Z_]*\).*/\1/p' | sort -u | tr '\n' ' '; }
deadline=$((SECONDS + 1500))
while :; do
  merge_state="$(job_state "$merge_job")"
  case "$merge_state" in
    "COMPLETED ") break ;;
    *FAILED*|*CANCELLED*|*TIMEOUT*|*NODE_FAIL*|*OUT_OF_MEMORY*)
      echo "slurm-test: merge job $merge_job ended $merge_state; shards: $(job_state "$array_job")" >&2; exit 1 ;;
  esac
  [ "$SECONDS" -lt "$deadline" ] || { echo "slurm-test: timed out waiting for job $merge_job" >&2; exit 1; }
  sleep 2
done
t1=$(date +%s.%N)
echo "slurm-test: shards $(job_state "$array_job")and merge $(job_state "$merge_job")"
grep -h "finished in" "$out"/logs/shard-*.out
for ((i = 1; i <= shards; ++i)); do
  echo "  shard $i/$shards: $(ls "$out/shard-$i-of-$shards/cells" | wc -l) cells"
done
head -n 3 "$out/logs/merge.out"

# --- The same matrix on one machine, and the comparison ---------------------------------------------
"$bin" run "${run_args[@]}" --out "$tmp/single" 2> "$tmp/log/single.log" | tail -n 2
t2=$(date +%s.%N)
rules=(--fail-if 'keys_hash!=' --fail-if 'order_hash!=' --fail-if 'anc!=' --fail-if 'simt_lane_efficiency!='
       --fail-if 'simt_distinct_per_visit!=' --fail-if 'status!=' --fail-if missing)
"$bin" compare "$tmp/single" "$out/merged" --metrics keys_hash,order_hash,anc,simt_lane_efficiency "${rules[@]}" \
  --out "$tmp/compare.md" > /dev/null
"$bin" compare "$out/merged" "$tmp/single" --metrics keys_hash "${rules[@]}" > /dev/null
python3 - "$out/merged" "$tmp/single" << 'EOF'
import json, os, sys
merged, single = (json.load(open(os.path.join(d, "cells.json"))) for d in sys.argv[1:3])
assert len(merged) == len(single), f"{len(merged)} merged cells vs {len(single)} in the single run"
for c in merged:
    assert c["status"] == "ok", f"{c['id']}: {c['status']}"
    assert c["trace_ms"]["median"] > 0 and c["trace_mrays"] > 0, f"{c['id']}: no trace time"
    if c["encoder"] != "nosort":
        assert c["encode_ms"]["median"] > 0 and c["sort_ms"]["median"] > 0, f"{c['id']}: no encode/sort time"
for view in ("tables.md", "cells.csv", "cells.json", "meta.json"):
    assert os.path.getsize(os.path.join(sys.argv[1], view)) > 0, view
print(f"slurm-test: {len(merged)} cells: merged == single run on every deterministic figure; timings present")
EOF
awk -v n="$shards" -v t0="$t0" -v t1="$t1" -v t2="$t2" 'BEGIN {
  printf "slurm-test: wall time: Slurm run (%d shards + merge, submit to merged) %.1f s; single run %.1f s\n", n, t1 - t0, t2 - t1 }'
echo "slurm-test: PASSED"
