#!/usr/bin/env bash
# Every kernel on Oclgrind, an independent OpenCL 1.2 implementation that interprets the kernels and
# checks each memory access (issue 19, items 1-2). Runs, on tiny inputs, with Oclgrind's data-race,
# API and uninitialised-value checks on (out-of-bounds accesses and barrier divergence are always
# checked):
#   trace        both variants (robust, fast), the classes wide, wide8, binary, binary-ww, packet4, packet16, hybrid8, stream and
#                cwbvh,
#                closest and any hit
#   encodebench  every encoder at 16, 32 and 64 bits (the *_k32 and *_k64 kernels), HCC_DIR with 2
#                direction bits (its two-pass encode_direction_* / encode_box_set_or_* kernels), and
#                an encoder from a file (the example, inside cl/encode_file.h's encode_file_* kernels)
#   render       generate, shade, the (fast, wide) counted closest hit, accumulate, compaction
#   sortcheck    the radix sort in the shape Oclgrind gets (the GPU shape: local-memory tiles),
#                a small GPU shape whose tiles are 256 keys, with and without the Onesweep
#                passes, and the CPU shape, at
#                N = 1, 255, 256, 257, 4097 and 32/64-bit keys, against the host twin
# Every run must exit 0 (its results equal the host twins) and Oclgrind must report nothing.
#
# Oclgrind is registered for these runs only: OCL_ICD_VENDORS points the ICD loader at a temporary
# folder with the system's .icd files plus one for Oclgrind; /etc/OpenCL/vendors is not touched.
# It also checks that the default device (`raysort devices`) is not the simulator.
#
# usage: scripts/oclgrind-check.sh [RAYSORT_BINARY]     (default: build/raysort)
# KERNELS=DIR checks the kernels in DIR/cl instead of the binary's embedded copies (raysort --kernels).
# Exit 77 (ctest: skipped) when Oclgrind is not installed, except under CI=true (exit 1).
# JOBS (default 2) runs as many cases at once; sortcheck runs one size per process (see docs/trace.md,
# "Oclgrind": its uninitialised-value check misreports buffers created after others were released).
set -euo pipefail
cd "$(dirname "$0")/.."
RAYSORT="$(realpath "${1:-build/raysort}")"
JOBS="${JOBS:-2}"

source scripts/oclgrind-env.sh  # (the working folder is the repository root)
oclgrind_register oclgrind-check
mkdir -p "$work/logs"
export RAYSORT_SCENE_ROOT="${RAYSORT_SCENE_ROOT:-$(cd .. && pwd)/shared/scenes}"

# Item 5: with Oclgrind registered, the default device is still real hardware.
"$RAYSORT" devices >"$work/devices.txt"
if ! grep -q "Oclgrind" "$work/devices.txt"; then
  echo "oclgrind-check: Oclgrind registered but not listed by raysort devices:" >&2
  cat "$work/devices.txt" >&2
  exit 1
fi
if grep "(default)" "$work/devices.txt" | grep -q "Oclgrind"; then
  echo "oclgrind-check: the simulator is the default device" >&2
  exit 1
fi

export OCLGRIND_DATA_RACES=1 OCLGRIND_CHECK_API=1 OCLGRIND_UNINITIALIZED=1
DEV=(--device oclgrind)
GLOBAL=()
if [ -n "${KERNELS:-}" ]; then GLOBAL=(--kernels "$(realpath "$KERNELS")"); fi
PROTO=(--reps 1 --warmup 0 --max-time 0)
cases=(
  "trace-wide|trace ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --variant both --layout wide"
  "trace-binary|trace ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --variant both --layout binary,binary-ww"
  "trace-wide8|trace ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --variant both --layout wide8"
  "trace-packets|trace ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --variant both --layout packet4,packet16,hybrid8"
  "trace-coherent|trace ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --variant both --layout coherent8,coherent16"
  "trace-stream|trace ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --variant both --layout stream"
  "trace-cwbvh|trace ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --variant both --layout cwbvh"
  "encode-all|encodebench ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --bits 16,32,64"
  "encode-hcc-dir|encodebench ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --bits 16,32,64 --encoders hcc-dir --direction-bits 2"
  "encode-file|encodebench ${DEV[*]} --scene cornell --resolution 16x9 ${PROTO[*]} --bits 16,32,64 --encoders file:docs/examples/morton_zyx.cl"
  "render|render ${DEV[*]} --scene cornell --resolution 16x9 --spp 1 --out $work/render"
)
# Sort shapes: Oclgrind's own (its device type includes GPU: local-memory tiles of 128 x 8 keys),
# a small GPU shape (32 x 8 = 256-key tiles: 255, 256, 257 sit on a tile boundary), the same with
# the Onesweep passes (4097 keys: 17 tiles looking back) and the CPU shape (one work-item per
# tile, 8-bit digits, 4096-key tiles: 4097 is two tiles).
shapes=("gpu|" "gpu-wg32|--work-group 32 --scan-work-group 32"
  "gpu-wg32-onesweep|--work-group 32 --scan-work-group 32 --onesweep"
  "cpu|--work-group 1 --scan-work-group 1 --radix-bits 8")
for s in "${shapes[@]}"; do
  IFS='|' read -r shape opts <<<"$s"
  for bits in 32 64; do
    for n in 1 255 256 257 4097; do
      cases+=("sort-$shape-k$bits-n$n|sortcheck ${DEV[*]} --sizes $n --bits $bits $opts")
    done
  done
done

# One case: its exit status and Oclgrind's diagnostics (every kernel-level report names the kernel
# on a "Kernel:" line; API errors and fatal errors have their own headers).
run_case() {
  local name="$1" args="$2" log="$work/logs/$1.log" t0 rc=0
  t0=$(date +%s%N)
  # shellcheck disable=SC2086  # args is a word list
  timeout 600 "$RAYSORT" "${GLOBAL[@]}" $args >"$log" 2>&1 || rc=$?
  local ms=$((($(date +%s%N) - t0) / 1000000))
  local reports
  reports=$(grep -c -E "^[[:space:]]+Kernel: |Oclgrind - |OCLGRIND FATAL|^Oclgrind: " "$log" || true)
  local verdict="clean"
  if [ "$rc" -ne 0 ] || [ "$reports" -ne 0 ]; then verdict="FAILED (exit $rc, $reports Oclgrind reports)"; fi
  printf '%s|%d.%d|%s\n' "$name" $((ms / 1000)) $((ms % 1000 / 100)) "$verdict" >"$work/logs/$name.result"
}

running=0
for c in "${cases[@]}"; do
  IFS='|' read -r name args <<<"$c"
  run_case "$name" "$args" &
  running=$((running + 1))
  if [ "$running" -ge "$JOBS" ]; then wait -n; running=$((running - 1)); fi
done
wait

fail=0
printf '| case | seconds | Oclgrind checks |\n|---|---:|---|\n'
for c in "${cases[@]}"; do
  name="${c%%|*}"
  IFS='|' read -r _ secs verdict <"$work/logs/$name.result"
  printf '| %s | %s | %s |\n' "$name" "$secs" "$verdict"
  if [ "$verdict" != "clean" ]; then
    fail=1
    echo "---- $name: first lines of its log" >&2
    grep -m1 -B2 -A8 -E "^[[:space:]]+Kernel: |Oclgrind - |OCLGRIND FATAL|error" "$work/logs/$name.log" >&2 || tail -20 "$work/logs/$name.log" >&2
  fi
done
if [ "$fail" -ne 0 ]; then
  echo "oclgrind-check: FAILED" >&2
  exit 1
fi
echo "oclgrind-check: every case ran on Oclgrind with its checks clean"
