#!/usr/bin/env bash
# Cross-implementation equality (issue 19, item 3, reduced): the same small matrix on PoCL's pthread
# device, PoCL's single-threaded basic device and Oclgrind must give identical deterministic figures
# (key and order hashes, ANC, SIMT figures, status) under the golden rules of scripts/golden.sh.
# Reduced to what Oclgrind interprets in about two minutes: cornell at 16x9, primary and shadow0,
# (1) origin/hcc/mlhcc/ppc and the encoder from a file docs/examples/morton_zyx.cl (which has no host
# twin: its keys are checked across implementations only) at 16 and 32 bits on the wide class (22
# cells: keys, orders, ANC, SIMT)
# and (2) origin and hcc at 32 bits in every trace class (wide, wide8, binary, packet4/8/16,
# hybrid8/16: 48 cells). Each cell's NoSort trace must equal the class's host twin bit for bit on
# every implementation (a mismatch fails the cell, so its status differs), and the deterministic
# figures must be equal. The full quick preset (744 cells at 48x27) would take Oclgrind hours;
# PoCL's run of it is compared with tests/golden by golden_quick_preset.
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

common=(run --scenes cornell --batches primary,shadow0 --resolution 16x9 --reps 1 --warmup 0 --max-time 0)
declare -A matrix
matrix[keys]="--encoders origin,hcc,mlhcc,ppc,file:docs/examples/morton_zyx.cl --bits 16,32"
matrix[classes]="--encoders origin,hcc --bits 32 --layout all"
for m in keys classes; do
  read -r -a margs <<<"${matrix[$m]}"
  for dev in pthread basic oclgrind; do
    if ! "$RAYSORT" "${common[@]}" "${margs[@]}" --device "$dev" --out "$work/$m-$dev" >"$work/$m-$dev.log" 2>&1; then
      echo "cross-impl: the $m run on '$dev' failed:" >&2
      tail -20 "$work/$m-$dev.log" >&2
      exit 1
    fi
    echo "$m on $dev: $(grep "cells run" "$work/$m-$dev.log")"
  done
done
fail=0
for m in keys classes; do
  for dev in basic oclgrind; do
    if "$RAYSORT" compare "$work/$m-pthread" "$work/$m-$dev" --metrics keys_hash,order_hash,anc,simt_lane_efficiency \
         --fail-if 'keys_hash!=' --fail-if 'order_hash!=' --fail-if 'anc!=' --fail-if 'simt_lane_efficiency!=' \
         --fail-if 'simt_distinct_per_visit!=' --fail-if 'status!=' --fail-if missing \
         --out "$work/$m-pthread-$dev.md" >"$work/compare-$m-$dev.log" 2>&1; then
      echo "cross-impl ($m): PoCL pthread and $dev give identical figures in every cell"
    else
      echo "cross-impl ($m): PoCL pthread and $dev differ:" >&2
      cat "$work/compare-$m-$dev.log" >&2
      fail=1
    fi
  done
done
exit "$fail"
