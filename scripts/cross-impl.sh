#!/usr/bin/env bash
# Cross-implementation equality (issue 19, item 3, reduced): the same small matrix on PoCL's pthread
# device, PoCL's single-threaded basic device and Oclgrind must give identical deterministic figures
# (key and order hashes, ANC, SIMT figures, status) under the golden rules of scripts/golden.sh.
# Reduced to what Oclgrind interprets in well under a minute: cornell at 16x9, primary and shadow0,
# origin/hcc/mlhcc/ppc at 16 and 32 bits (18 cells). The full quick preset (744 cells at 48x27)
# would take Oclgrind hours; PoCL's run of it is compared with tests/golden by golden_quick_preset.
#
# usage: scripts/cross-impl.sh [RAYSORT_BINARY]        (default: build/raysort)
# Exit 77 (ctest: skipped) when Oclgrind is not installed, except under CI=true (exit 1).
set -euo pipefail
cd "$(dirname "$0")/.."
RAYSORT="$(realpath "${1:-build/raysort}")"

source scripts/oclgrind-env.sh  # (the working folder is the repository root)
oclgrind_register cross-impl
# PoCL asked to list its basic device too.
export POCL_DEVICES="basic pthread"
unset RAYSORT_DEVICE

args=(run --scenes cornell --batches primary,shadow0 --encoders origin,hcc,mlhcc,ppc --bits 16,32
      --resolution 16x9 --reps 1 --warmup 0 --max-time 0)
for dev in pthread basic oclgrind; do
  if ! "$RAYSORT" "${args[@]}" --device "$dev" --out "$work/$dev" >"$work/$dev.log" 2>&1; then
    echo "cross-impl: the run on '$dev' failed:" >&2
    tail -20 "$work/$dev.log" >&2
    exit 1
  fi
  grep "cells run" "$work/$dev.log"
done
fail=0
for dev in basic oclgrind; do
  if "$RAYSORT" compare "$work/pthread" "$work/$dev" --metrics keys_hash,order_hash,anc,simt_lane_efficiency \
       --fail-if 'keys_hash!=' --fail-if 'order_hash!=' --fail-if 'anc!=' --fail-if 'simt_lane_efficiency!=' \
       --fail-if 'simt_distinct_per_visit!=' --fail-if 'status!=' --fail-if missing \
       --out "$work/pthread-$dev.md" >"$work/compare-$dev.log" 2>&1; then
    echo "cross-impl: PoCL pthread and $dev give identical figures in every cell"
  else
    echo "cross-impl: PoCL pthread and $dev differ:" >&2
    cat "$work/compare-$dev.log" >&2
    fail=1
  fi
done
exit "$fail"
