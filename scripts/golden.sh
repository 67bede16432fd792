#!/usr/bin/env bash
# The PoCL regression test of issue 5: run the quick preset at a tiny resolution and compare its
# deterministic figures (key and order hashes, ANC, SIMT model, status) with the committed golden
# result set in tests/golden/quick-tiny through `raysort compare --fail-if`.
#
#   scripts/golden.sh check  RAYSORT_BIN   compare a fresh run with the golden set (ctest runs this)
#   scripts/golden.sh update RAYSORT_BIN   rewrite the golden set (commit it and say why)
set -euo pipefail
mode="${1:?usage: golden.sh check|update RAYSORT_BIN}"
bin="${2:?usage: golden.sh check|update RAYSORT_BIN}"
root="$(cd "$(dirname "$0")/.." && pwd)"
golden="$root/tests/golden/quick-tiny"
args=(run --preset quick --resolution 48x27 --reps 1 --warmup 0 --max-time 0)

if [ "$mode" = update ]; then
  rm -rf "$golden"
  "$bin" "${args[@]}" --out "$golden"
  # Keep only what the comparison reads: meta.json and the per-cell records.
  rm -f "$golden"/*.png "$golden"/cells.csv "$golden"/cells.json "$golden"/.raysort-lock
  echo "golden set rewritten in $golden"
  exit 0
fi

out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
"$bin" "${args[@]}" --out "$out/run"
"$bin" compare "$golden" "$out/run" --metrics keys_hash,order_hash,anc,simt_lane_efficiency \
  --fail-if 'keys_hash!=' --fail-if 'order_hash!=' --fail-if 'anc!=' \
  --fail-if 'simt_lane_efficiency!=' --fail-if 'simt_distinct_per_visit!=' --fail-if 'status!=' \
  --fail-if missing --out "$out/compare.md" > /dev/null
echo "golden check: every deterministic figure equals tests/golden/quick-tiny"
