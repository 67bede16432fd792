#!/usr/bin/env bash
# What a lent GPU machine runs (docs/gpu-runs.md), in one command, from the repository root, with
# the bundle of scripts/device-bundle.sh carried in .device/:
#   1. finds NVIDIA's OpenCL library and an ICD file naming it (writes one if the machine has none);
#   2. lists the OpenCL devices, and checks the sort in the device's own shape (sortcheck);
#   3. the golden check (scripts/golden.sh) on the GPU: keys, orders, ANC, SIMT and GPU-model
#      figures of the quick preset must equal the committed PoCL ones, bit for bit;
#   4. every trace class (`--layout all`: the CPU classes too, for the record), both variants, on the
#      paper's sibenik and breakfast_room batches at 1920x1080: speed per class and mismatches
#      against each class's host twin, in check.log and classes.log;
#   5. measures the GPU model's validation matrix (results/gpu-model/README.md: five scenes,
#      bounce1 and shadow0, eight encoders at 32 bits, gather) on the GPU: a result set whose
#      speedups are measured, to set beside the model's predictions (scripts/gpu_model_validate.py
#      --measured);
#   6. `raysort sortbench`: the sort against the copy bound and Boost.Compute, in sortbench.md.
# Everything goes to $OUT (the device tool's folder; ./device-out elsewhere): check.log, classes.log,
# sortbench.md and sets.tar.gz (the result sets). Exit status: 0 when every step passed, else the first failure's.
# A lease is short (docs/gpu-runs.md), so steps 3-5 can be given seconds each:
# DEVICE_CHECK_GOLDEN_S, DEVICE_CHECK_CLASSES_S, DEVICE_CHECK_MATRIX_S, DEVICE_CHECK_SORT_S (0 or
# unset: no limit). A
# step past its limit gets SIGTERM: `run` then stops at its next arm and keeps the cells it measured
# (resumable), and what it wrote still comes back in sets.tar.gz.
#
#   bash scripts/device-check.sh                 on the GPU machine
#   DEVICE_CHECK_ANY=1 DEVICE_CHECK_QUICK=1 RAYSORT_BIN=build/raysort bash scripts/device-check.sh
#                                                here, on PoCL: the same steps on a tiny matrix
#                                                (ctest: device_check_script)
set -uo pipefail
# The validation matrix's scenes (scripts/device-bundle.sh packs their OBJ folders from this line).
VALIDATION_SCENES="sibenik,breakfast_room,grey_white_room,multi-instance-real,landscape"
root="$(cd "$(dirname "$0")/.." && pwd)"
bundle="$root/.device"
bin="${RAYSORT_BIN:-$bundle/raysort}"
out="${OUT:-$root/device-out}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
mkdir -p "$out"
exec > >(tee -a "$out/check.log") 2>&1
status=0
step() { echo; echo "== $*"; }
fail() { echo "FAILED: $*"; [ "$status" -ne 0 ] || status=1; }
# DEVICE_CHECK_STEPS: the steps from 3 on to run, e.g. "3,5" (default all: 3,4,5,6), for a second lease.
wanted() { [[ ",${DEVICE_CHECK_STEPS:-3,4,5,6}," == *",$1,"* ]]; }
# Runs a step's command under its limit in seconds (0: none); says so when the limit ended it.
limited() {
  local seconds="$1"; shift
  timeout -k 20 "$seconds" "$@"
  local rc=$?
  [ "$rc" -ne 124 ] || echo "(stopped at its limit of ${seconds} s)"
  return "$rc"
}

step "1. NVIDIA's OpenCL library and ICD"
if [ -z "${DEVICE_CHECK_ANY:-}" ]; then
  nvidia-smi -L || fail "nvidia-smi"
  lib="$(ldconfig -p 2>/dev/null | awk '/libnvidia-opencl\.so\.1/ {print $NF; exit}')"
  [ -n "$lib" ] || lib="$(find /usr/local/nvidia /usr/lib /usr/lib64 /usr/lib/x86_64-linux-gnu -name 'libnvidia-opencl.so.1' 2>/dev/null | head -n 1)"
  if [ -z "$lib" ]; then
    echo "no libnvidia-opencl.so.1 on this machine: NVIDIA's OpenCL driver is not installed here"
    exit 2
  fi
  echo "library: $lib"
  export RAYSORT_EXTRA_LIBS="$(dirname "$lib")"
  if grep -qs nvidia /etc/OpenCL/vendors/*.icd; then
    echo "ICD: $(grep -ls nvidia /etc/OpenCL/vendors/*.icd | head -n 1)"
  else
    mkdir -p "$work/vendors"
    echo "$lib" > "$work/vendors/nvidia.icd"
    export OCL_ICD_VENDORS="$work/vendors"
    echo "ICD: none under /etc/OpenCL/vendors; wrote $OCL_ICD_VENDORS/nvidia.icd"
  fi
  export RAYSORT_DEVICE="${RAYSORT_DEVICE:-gpu}"
fi

step "2. OpenCL devices"
"$bin" devices || { echo "raysort cannot list OpenCL devices"; exit 3; }
# The sort in the device's own shape against its host twin (on NVIDIA: the Onesweep passes, whose
# look-back needs the forward progress OpenCL does not promise), before anything sorts with it.
limited 120 "$bin" sortcheck --sizes 1,255,257,4097,1000003 --bits 32,64 || fail "raysort sortcheck"

# The real scenes of steps 4 and 5, unpacked from the bundle.
if [ -z "${DEVICE_CHECK_QUICK:-}" ] && [ -f "$bundle/scenes.tar.gz" ]; then
  tar -C "$work" -xzf "$bundle/scenes.tar.gz"
  export RAYSORT_SCENE_ROOT="$work/$(tar -tzf "$bundle/scenes.tar.gz" | head -n 1 | cut -d/ -f1)"
fi

if wanted 3; then
step "3. golden check on this device"
limited "${DEVICE_CHECK_GOLDEN_S:-0}" bash "$root/scripts/golden.sh" check "$bin" || fail "golden check: a deterministic figure differs from PoCL's, or the step ran past its limit"
fi

if wanted 4; then
step "4. every trace class on this device"
if [ -n "${DEVICE_CHECK_QUICK:-}" ]; then
  classes=(--scene cornell --resolution 48x27 --reps 2 --warmup 0 --max-time 0)
else
  classes=(--scene sibenik,breakfast_room --resolution 1920x1080 --reps 5 --warmup 1 --max-time 8)
fi
limited "${DEVICE_CHECK_CLASSES_S:-0}" "$bin" trace "${classes[@]}" --layout all --variant both 2>&1 | tee "$out/classes.log"
[ "${PIPESTATUS[0]}" -eq 0 ] || fail "raysort trace --layout all"
fi

if wanted 5; then
step "5. the GPU model's validation matrix, measured"
if [ -n "${DEVICE_CHECK_QUICK:-}" ]; then
  matrix=(--preset quick --resolution 96x54 --scenes cornell,multi-instance --batches bounce1,shadow0
          --encoders hcc,twopoint --bits 32 --reps 3 --warmup 1 --max-time 0)
else
  matrix=(--preset paper-1spp --scenes "$VALIDATION_SCENES"
          --batches bounce1,shadow0 --encoders hcc,mlhcc,grid,twopoint,aila,reis,origin,ppc --bits 32
          --access gather --reps 7 --warmup 1 --max-time 1)
fi
commit="$(cut -d' ' -f1 "$(dirname "$bin")/commit" 2>/dev/null || git -C "$root" rev-parse --short HEAD 2>/dev/null || echo unknown)"
set_name="gpu-validation-$commit"
if limited "${DEVICE_CHECK_MATRIX_S:-0}" "$bin" run "${matrix[@]}" --out "$work/$set_name"; then
  tar -C "$work" -czf "$out/sets.tar.gz" "$set_name"
  echo "result set: $out/sets.tar.gz ($set_name)"
else
  fail "raysort run"
  [ -d "$work/$set_name" ] && tar -C "$work" -czf "$out/sets.tar.gz" "$set_name"
fi
fi

if wanted 6; then
step "6. the radix sort on this device"
# On the first NVIDIA run (an H200) the sort took longer than the trace it orders: 2 % of the copy
# bound (results/README.md, "The first NVIDIA run"). Every lease measures it again.
if [ -n "${DEVICE_CHECK_QUICK:-}" ]; then
  sorts=(--no-large --reps 2 --ref-reps 1 --bits 32)
else
  sorts=(--reps 10 --ref-reps 1)
fi
limited "${DEVICE_CHECK_SORT_S:-0}" "$bin" sortbench "${sorts[@]}" 2>&1 | tee "$out/sortbench.md"
[ "${PIPESTATUS[0]}" -eq 0 ] || fail "raysort sortbench"
fi

echo
[ "$status" -eq 0 ] && echo "device check: every step passed" || echo "device check: a step failed (above)"
exit "$status"
