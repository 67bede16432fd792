#!/usr/bin/env bash
# Submits a sharded raysort matrix run to Slurm (issue 10; docs/slurm.md): a job array of N shard
# tasks (raysort-matrix.sbatch), then a merge job (raysort-merge.sbatch) that starts once every
# shard succeeded (--dependency=afterok). Everything lands in OUT, a folder every node sees:
#   OUT/shard-<i>-of-<N>/   each shard's result set (a resubmission resumes it)
#   OUT/merged/             the merged result set: tables.md, cells.csv, cells.json, plots
#   OUT/logs/               one log per task
#
#   scripts/slurm/submit.sh --shards 8 --out /shared/raysort/paper --partition gpu --gpu -- --preset paper
#   scripts/slurm/submit.sh --shards 4 --out /shared/raysort/quick --partition cpu -- --preset quick
#
# Options: --shards N (default 4), --out DIR (required), --partition P (default: the cluster's
# default partition; env RAYSORT_PARTITION), --gpu (one GPU per task: --gres=gpu:1 and
# RAYSORT_DEVICE=gpu) or --cpu (RAYSORT_DEVICE=cpu), --bin PATH (default build/raysort),
# --time T (per-task limit, sbatch --time), --shared (tasks may share a node; the default gives
# each task a whole node, so no other job disturbs its timings), --sbatch OPT (repeatable: passed
# to both sbatch calls, e.g. --sbatch=--account=lab). Arguments after -- go to `raysort run`.
set -euo pipefail

here="$(cd "$(dirname "$0")" && pwd)"
shards=4 out="" partition="${RAYSORT_PARTITION:-}" device="" gres="" bin="build/raysort" time="" exclusive=1
extra=()
usage() { sed -n '2,20p' "$0" | sed 's/^# \{0,1\}//'; exit "${1:-2}"; }
while [ $# -gt 0 ]; do
  case "$1" in
    --shards) shards="$2"; shift 2 ;;
    --out) out="$2"; shift 2 ;;
    --partition) partition="$2"; shift 2 ;;
    --gpu) device=gpu gres="--gres=gpu:1"; shift ;;
    --cpu) device=cpu; shift ;;
    --bin) bin="$2"; shift 2 ;;
    --time) time="$2"; shift 2 ;;
    --shared) exclusive=0; shift ;;
    --sbatch=*) extra+=("${1#--sbatch=}"); shift ;;
    --sbatch) extra+=("$2"); shift 2 ;;
    -h|--help) usage 0 ;;
    --) shift; break ;;
    *) echo "submit.sh: unknown option '$1' (raysort run's arguments go after --)" >&2; usage ;;
  esac
done
[ -n "$out" ] || { echo "submit.sh: --out DIR is required (a folder every node sees)" >&2; usage; }
[[ "$shards" =~ ^[1-9][0-9]*$ ]] || { echo "submit.sh: --shards '$shards': expected a number, 1 or more" >&2; exit 2; }
[ $# -gt 0 ] || { echo "submit.sh: name the matrix after --, e.g. -- --preset quick" >&2; exit 2; }
for arg in "$@"; do
  case "$arg" in
    --out|--out=*|--shard|--shard=*|--shard-plan*)
      echo "submit.sh: '$arg' is set per task by raysort-matrix.sbatch; use submit.sh's --out and --shards" >&2; exit 2 ;;
  esac
done
bin="$(realpath "$bin")"
[ -x "$bin" ] || { echo "submit.sh: no raysort binary at $bin (build it, or pass --bin)" >&2; exit 2; }
mkdir -p "$out/logs"
out="$(realpath "$out")"
# The plan is checked here, before anything is queued: a bad matrix fails now, not in N tasks.
"$bin" run "$@" --shard-plan "$shards" > "$out/plan.txt"
head -n $((shards + 3)) "$out/plan.txt"

common=(--parsable --export="ALL,RAYSORT_BIN=$bin,RAYSORT_OUT=$out,RAYSORT_SHARDS=$shards${device:+,RAYSORT_DEVICE=$device}")
[ -n "$partition" ] && common+=(--partition="$partition")
[ -n "$time" ] && common+=(--time="$time")
common+=("${extra[@]}")
shard_opts=(--array="1-$shards" --output="$out/logs/shard-%a.out")
[ -n "$gres" ] && shard_opts+=("$gres")
[ "$exclusive" = 1 ] && shard_opts+=(--exclusive)

array_job="$(sbatch "${common[@]}" "${shard_opts[@]}" "$here/raysort-matrix.sbatch" "$@")"
array_job="${array_job%%;*}"  # --parsable prints "jobid[;cluster]"
merge_job="$(sbatch "${common[@]}" --dependency="afterok:$array_job" --kill-on-invalid-dep=yes \
             --output="$out/logs/merge.out" "$here/raysort-merge.sbatch")"
merge_job="${merge_job%%;*}"
echo "shards: job array $array_job (tasks 1-$shards${partition:+, partition $partition})"
echo "merge:  job $merge_job (after every shard succeeded)"
echo "results: $out/merged (shards in $out/shard-<i>-of-$shards, logs in $out/logs)"
