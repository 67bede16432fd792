#!/usr/bin/env bash
# The PoCL regression test of issue 5: run the quick preset at a tiny resolution and compare its
# deterministic figures (key and order hashes, ANC, SIMT model, GPU cost model, status) with the committed golden
# result sets in tests/golden/ through `raysort compare --fail-if`.
#
#   scripts/golden.sh check  RAYSORT_BIN   compare a fresh run with the golden set (ctest runs this)
#   scripts/golden.sh update RAYSORT_BIN   rewrite the golden set (commit it and say why)
set -euo pipefail
mode="${1:?usage: golden.sh check|update RAYSORT_BIN}"
bin="${2:?usage: golden.sh check|update RAYSORT_BIN}"
root="$(cd "$(dirname "$0")/.." && pwd)"
# With the GPU cost model on (docs/gpu-model.md): its columns are deterministic too.
args=(run --preset quick --resolution 48x27 --reps 1 --warmup 0 --max-time 0 --gpu-model rtx3060)
# Two golden sets: the default layout (wide) with both baseline orders, and the binary layout. The
# SIMT model walks the layout the kernel walks, so each layout's model figures are pinned.
sets=("quick-tiny:--layout wide --baseline all" "quick-tiny-binary:--layout binary")

out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
for entry in "${sets[@]}"; do
  name="${entry%%:*}"
  read -r -a extra <<< "${entry#*:}"
  golden="$root/tests/golden/$name"
  if [ "$mode" = update ]; then
    rm -rf "$golden"
    "$bin" "${args[@]}" "${extra[@]}" --out "$golden"
    # Keep only what the comparison reads: meta.json and the per-cell records.
    rm -f "$golden"/*.png "$golden"/*.md "$golden"/cells.csv "$golden"/cells.json "$golden"/.raysort-lock
    echo "golden set rewritten in $golden"
    continue
  fi
  "$bin" "${args[@]}" "${extra[@]}" --out "$out/$name"
  "$bin" compare "$golden" "$out/$name" --metrics keys_hash,order_hash,anc,simt_lane_efficiency \
    --fail-if 'keys_hash!=' --fail-if 'order_hash!=' --fail-if 'anc!=' \
    --fail-if 'simt_lane_efficiency!=' --fail-if 'simt_distinct_per_visit!=' --fail-if 'status!=' \
    --fail-if 'gpu_model_speedup!=' --fail-if 'gpu_dram_bytes!=' --fail-if 'gpu_warp_steps!=' \
    --fail-if missing --out "$out/$name-compare.md" > /dev/null
  echo "golden check: every deterministic figure equals tests/golden/$name"
done
