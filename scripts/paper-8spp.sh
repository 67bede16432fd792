#!/usr/bin/env bash
# The whole paper preset at the paper's sampling (issue 22: 1920x1080, 8 spp, 2 shadow rays per
# bounce; 546 cells) on this machine's PoCL, as six shards that can run in different sessions.
#
# 3 h 27 min of a 2-core machine in all (about 2 h 15 min when nothing else runs beside it; the
# committed paper-8spp-9dab0ed), longer than a working session leaves free, so the run is split
# with `raysort run --shard K/6` (a contiguous split by cost: each shard holds one to three scenes)
# and each finished shard is committed under results/ by whoever runs this. Every shard must come
# from the same build, or `raysort merge` refuses them; so this script builds the pinned commit in
# a worktree of its own, whatever the checkout holds now, and runs the first shard not yet
# complete (resuming it when a session ended inside it). When all six are there it merges them.
#
#   bash scripts/paper-8spp.sh            # run (or resume) the next shard, or merge when all are done
#   bash scripts/paper-8spp.sh status     # which shards are complete
#   bash scripts/paper-8spp.sh companion  # the same matrix at 1 spp (--preset paper-1spp), same build:
#                                         # what the 8-spp figures are compared with (about 40 min)
#
# Needs RAYSORT_SCENE_ROOT (or ../shared/scenes) with the real scenes.
set -euo pipefail
cd "$(dirname "$0")/.."
REPO=$(pwd)

PIN=9dab0ed     # the build every shard runs (the contiguous shard plan landed in it)
SHARDS=6
SLUG=pocl-cpu-pthread-skylake-avx512-amd-epyc
SET="$REPO/results/$SLUG/paper-8spp-$PIN"
WORK=${PAPER_WORKTREE:-/tmp/raysort-paper-8spp-$PIN}
export RAYSORT_SCENE_ROOT="${RAYSORT_SCENE_ROOT:-$(cd "$REPO/.." && pwd)/shared/scenes}"

shard_dir() { echo "$SET/shards/shard-$1-of-$SHARDS"; }
# A shard is complete when its run ended with exit 0 (every planned cell ok); the marker is
# written only then, so a folder without it is resumed.
complete() { [ -f "$(shard_dir "$1")/COMPLETE" ]; }

if [ "${1:-run}" = status ]; then
  for k in $(seq 1 $SHARDS); do
    d=$(shard_dir "$k")
    n=$(ls "$d/cells" 2>/dev/null | wc -l)
    if complete "$k"; then echo "shard $k/$SHARDS: complete ($n cells)"; else echo "shard $k/$SHARDS: $n cells so far"; fi
  done
  exit 0
fi

if [ ! -x "$WORK/build/raysort" ]; then
  git worktree prune
  [ -d "$WORK" ] || git worktree add --detach "$WORK" "$PIN"
  cmake -S "$WORK" -B "$WORK/build" -DCMAKE_BUILD_TYPE=Release >/dev/null
  cmake --build "$WORK/build" -j "$(nproc)" --target raysort
fi
RAYSORT="$WORK/build/raysort"

if [ "${1:-run}" = companion ]; then
  d="$REPO/results/$SLUG/paper-1spp-$PIN"
  [ -f "$d/COMPLETE" ] && { echo "paper-8spp: companion $d is complete"; exit 0; }
  /usr/bin/time -v -a -o "$d.run-time.txt" \
    "$RAYSORT" run --preset paper-1spp --reps 3 --warmup 0 --max-time 0 --gpu-model rtx3060 --out "$d"
  date -u +%FT%TZ > "$d/COMPLETE"
  mv "$d.run-time.txt" "$d/run-time.txt"
  echo "paper-8spp: companion $d complete; commit it"
  exit 0
fi

for k in $(seq 1 $SHARDS); do
  complete "$k" && continue
  d=$(shard_dir "$k")
  mkdir -p "$(dirname "$d")"
  echo "paper-8spp: shard $k/$SHARDS into $d"
  # --reps 3 --warmup 0 --max-time 0: the protocol of the earlier 8-spp sets (three paired rounds a
  # cell; their PoCL speedups carry per-round min-max, not intervals); --gpu-model: Table 2/3's model.
  /usr/bin/time -v -a -o "$(dirname "$d")/run-time-shard-$k.txt" \
    "$RAYSORT" run --preset paper --shard "$k/$SHARDS" --reps 3 --warmup 0 --max-time 0 --gpu-model rtx3060 --out "$d"
  date -u +%FT%TZ > "$d/COMPLETE"
  echo "paper-8spp: shard $k/$SHARDS complete; commit $d and its run-time file"
  exit 0
done

if [ ! -d "$SET/merged" ]; then
  "$RAYSORT" merge "$SET"/shards/shard-*-of-$SHARDS -o "$SET/merged"
  echo "paper-8spp: merged into $SET/merged"
fi
