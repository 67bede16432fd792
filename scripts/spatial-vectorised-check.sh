#!/usr/bin/env bash
# ctest spatial_kernels_vectorised: PoCL's work-group vectoriser widens every spatial encode kernel
# (encode_<origin|reis|costa|aila|twopoint>_<k32|k64>) across work-items. A kernel it does not widen
# runs one ray at a time, 2-5x slower, with the same keys, so no key test sees it: TwoPoint ran so
# from commit 609a4b9 to issue 42 (cl/keys.h, rs_exit_ray). Compiles the kernels afresh
# (POCL_KERNEL_CACHE=0) with PoCL's vectoriser remarks on; each kernel's first (whole work-group)
# compile must report "vectorized loop" before the next kernel's. Needs the PoCL CPU device.
# usage: scripts/spatial-vectorised-check.sh RAYSORT_BINARY   (KERNELS=DIR: the kernels in DIR, raysort --kernels)
set -euo pipefail
bin="${1:?usage: spatial-vectorised-check.sh RAYSORT_BINARY}"
global=()
if [ -n "${KERNELS:-}" ]; then global=(--kernels "$(realpath "$KERNELS")"); fi
log=$(POCL_KERNEL_CACHE=0 POCL_VECTORIZER_REMARKS=1 "$bin" "${global[@]}" encodebench --device cpu --scene cornell \
  --resolution 64x36 --reps 1 --warmup 0 --max-time 0 --no-verify \
  --encoders origin,reis,costa,aila,twopoint --bits 32,64 2>&1 | sed 's/<unknown>:0:0: /\n/g')
if ! grep -q "inlined into '_pocl_kernel_" <<<"$log"; then
  echo "spatial-vectorised-check: no PoCL vectoriser remarks (is the cpu device PoCL?):" >&2
  head -5 <<<"$log" >&2
  exit 1
fi
fail=0
for code in origin reis costa aila twopoint; do
  for suffix in k32 k64; do
    k="encode_${code}_${suffix}"
    # The remarks from this kernel's first work-group function up to the next kernel's.
    # (Each kernel's work-group function comes as _workgroup and _workgroup_fast.)
    verdict=$(awk -v k="_pocl_kernel_${k}_workgroup" '
      index($0, "inlined into '\''_pocl_kernel_") {
        if (index($0, k "'\''")) { if (seen) exit; on = seen = 1 } else if (!index($0, k) && on) exit
        next }
      on && /vectorized loop \(vectorization width/ { v = 1 }
      END { print seen ? (v ? "vectorised" : "scalar") : "absent" }' <<<"$log")
    echo "$k: $verdict"
    [ "$verdict" = vectorised ] || fail=1
  done
done
if [ "$fail" = 1 ]; then
  echo "spatial-vectorised-check: a spatial kernel is not vectorised across work-items (see above;" \
       "POCL_VECTORIZER_REMARKS=1 says why, results/history/encoder-kernels.md)" >&2
  exit 1
fi
