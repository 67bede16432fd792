#!/usr/bin/env bash
# NVIDIA build check without a GPU (issue 19, item 4): compiles every kernel file in cl/ for
# nvptx64-nvidia-nvcl (NVIDIA's OpenCL) with clang-15 and libclc, as OpenCL C 1.2, with the options
# and -D defines the host passes at run time (host/runtime/runtime.cpp build_options, and each
# rt.build() call: trace.cl for every trace class (-DRS_TRACE_BINARY, -DRS_TRACE_WIDE8, -DRS_TRACE_STREAM,
# -DRS_TRACE_PACKET=W with and without -DRS_PACKET_SINGLE_AT), radix_sort.cl in both shapes and
# key widths), and an encoder from a file: the example docs/examples/morton_zyx.cl after
# cl/encode_file.h, as host/encode/encoder_file.cpp puts them together. Fails on any error, on any warning (except libclc's triple spelling, below), and on
# any function the PTX declares but does not define (.extern .func: a builtin libclc lacks, or one
# only x86 has). Prints each kernel's local (stack) memory from the PTX's __local_depot sizes.
#
# usage: scripts/nvptx-build.sh [OUT_DIR]      (default: a temporary folder, removed at the end)
# Exit 77 (ctest: skipped) when clang-15 or libclc-15 is missing, except under CI=true (exit 1).
set -euo pipefail
cd "$(dirname "$0")/.."

CLANG="${CLANG:-clang-15}"
LIBCLC="${LIBCLC:-/usr/lib/clc/nvptx64--nvidiacl.bc}"
if ! command -v "$CLANG" >/dev/null || [ ! -f "$LIBCLC" ]; then
  msg="nvptx-build: needs $CLANG and $LIBCLC (Debian: clang-15 libclc-15, scripts/install-deps.sh)"
  if [ "${CI:-}" = "true" ]; then echo "$msg" >&2; exit 1; fi
  echo "SKIPPED: $msg"
  exit 77
fi

OUT="${1:-}"
if [ -z "$OUT" ]; then
  OUT="$(mktemp -d)"
  trap 'rm -rf "$OUT"' EXIT
fi
mkdir -p "$OUT"

# Runtime::build_options: OpenCL C 1.2, correctly rounded divide/sqrt (NVIDIA's driver reports
# CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT). __OPENCL_VERSION__ is defined by an OpenCL driver's own
# compiler (NVIDIA's, PoCL's, Oclgrind's), not by clang for this target; the kernels key on it.
# -Werror=pedantic: clang accepts language extensions that NVIDIA's compiler refuses (variadic
# macros stopped every encode kernel on an H200, 9b63aa0); OpenCL C 1.2 as written, nothing more.
COMMON=(-x cl -cl-std=CL1.2 -cl-fp32-correctly-rounded-divide-sqrt -target nvptx64-nvidia-nvcl -O2 -S
        -Xclang -finclude-default-header -Xclang -mlink-bitcode-file -Xclang "$LIBCLC"
        -D__OPENCL_VERSION__=120 -Icl -Werror=pedantic)

# Radix sort shapes (host/sort/radix_sort.cpp): the GPU shape RadixSortTuning::for_device picks for
# an NVIDIA device (48 KiB local memory, 1024 work-items: 6-bit digits, 128 work-items, 8 keys each,
# scan work-group 1024), and the CPU shape (one work-item per tile, 8-bit digits).
GPU_SORT="-DRS_RADIX_BITS=6 -DRS_WG=128 -DRS_MAX_ITEMS=8 -DRS_SCAN_WG=1024"
CPU_SORT="-DRS_RADIX_BITS=8 -DRS_WG=1 -DRS_MAX_ITEMS=8 -DRS_SCAN_WG=1"
BUILDS=(
  "trace-wide|cl/trace.cl|"
  "trace-wide8|cl/trace.cl|-DRS_TRACE_WIDE8"
  "trace-stream|cl/trace.cl|-DRS_TRACE_STREAM"
  "trace-cwbvh|cl/trace.cl|-DRS_TRACE_CWBVH"
  "trace-binary-ww|cl/trace.cl|-DRS_TRACE_BINARY_WW"
  "trace-binary|cl/trace.cl|-DRS_TRACE_BINARY"
  "trace-packet4|cl/trace.cl|-DRS_TRACE_PACKET=4"
  "trace-packet8|cl/trace.cl|-DRS_TRACE_PACKET=8"
  "trace-packet16|cl/trace.cl|-DRS_TRACE_PACKET=16"
  "trace-hybrid8|cl/trace.cl|-DRS_TRACE_PACKET=8 -DRS_PACKET_SINGLE_AT=2"
  "trace-hybrid16|cl/trace.cl|-DRS_TRACE_PACKET=16 -DRS_PACKET_SINGLE_AT=4"
  "trace-coherent8|cl/trace.cl|-DRS_TRACE_PACKET=8 -DRS_TRACE_COHERENT"
  "trace-coherent16|cl/trace.cl|-DRS_TRACE_PACKET=16 -DRS_TRACE_COHERENT"
  "encode|cl/encode.cl|"
  "permute|cl/permute.cl|"
  "shade|cl/shade.cl|"
  "encode-file-example|docs/examples/morton_zyx.cl|-include cl/encode_file.h"
  "sort-gpu-k32|cl/radix_sort.cl|-DRS_KEY_BITS=32 $GPU_SORT"
  "sort-gpu-k64|cl/radix_sort.cl|-DRS_KEY_BITS=64 $GPU_SORT"
  "sort-cpu-k32|cl/radix_sort.cl|-DRS_KEY_BITS=32 $CPU_SORT"
  "sort-cpu-k64|cl/radix_sort.cl|-DRS_KEY_BITS=64 $CPU_SORT"
)

# Every cl/*.cl file must appear above: a new kernel file fails here until it is added.
for f in cl/*.cl; do
  printf '%s\n' "${BUILDS[@]}" | grep -q "|$f|" || { echo "nvptx-build: $f is not in BUILDS" >&2; exit 1; }
done

fail=0
printf '| build | kernel | local (stack) bytes |\n|---|---|---:|\n' >"$OUT/local-memory.md"
for b in "${BUILDS[@]}"; do
  IFS='|' read -r name file defs <<<"$b"
  # shellcheck disable=SC2086  # defs is a list of options
  if ! "$CLANG" "${COMMON[@]}" $defs -o "$OUT/$name.ptx" "$file" 2>"$OUT/$name.log"; then
    echo "nvptx-build: $name ($file $defs) failed:" >&2
    cat "$OUT/$name.log" >&2
    fail=1
    continue
  fi
  # libclc-15's bitcode names the triple nvptx64-unknown-nvidiacl; the link warns that the spellings
  # differ. Any other warning fails.
  if grep -v -e "Linking two modules of different target triples" -e "^ \[-Wlinker-warnings\]" \
       -e "^[0-9]* warnings\? generated" "$OUT/$name.log" | grep -q .; then
    echo "nvptx-build: $name ($file $defs) warns:" >&2
    cat "$OUT/$name.log" >&2
    fail=1
  fi
  # A function the PTX declares (its header ends in ';') but never defines (header then '{'): a
  # builtin libclc lacks, or a C99 plain-inline function the compiler did not inline.
  undefined="$(awk '
    /^(\.visible |\.extern |\.weak )?\.func/ { infunc = 1; name = ""; next_is_name = 0 }
    infunc && name == "" { if (match($0, /[A-Za-z_$][A-Za-z0-9_$]*[ \t]*\(?[ \t]*$/) || match($0, /[A-Za-z_$][A-Za-z0-9_$]*\(/)) {
        n = substr($0, RSTART, RLENGTH); gsub(/[( \t]/, "", n); if (n != "func" && n !~ /^\.?b[0-9]/) name = n } }
    infunc && /^;/ { declared[name] = 1; infunc = 0 }
    infunc && /^\{/ { defined[name] = 1; infunc = 0 }
    END { for (n in declared) if (!(n in defined)) print n }' "$OUT/$name.ptx")"
  if [ -n "$undefined" ]; then
    echo "nvptx-build: $name calls functions neither the kernels nor libclc define: $undefined" >&2
    fail=1
  fi
  # Each .entry's local (stack) memory: its own __local_depot plus the deepest chain of the
  # functions it calls (clang keeps large static inline functions, e.g. the robust traversal,
  # out of line, each with its own depot).
  awk -v build="$name" '
    FNR == NR { if ($0 ~ /^(\.visible )?\.func/) want = 1
                if (want && match($0, /[A-Za-z_][A-Za-z0-9_]*[ \t]*\($/)) { n = substr($0, RSTART, RLENGTH); sub(/[ \t]*\($/, "", n); isfunc[n] = 1; want = 0 }
                next }
    /^\.entry / { unit = $2; sub(/\(.*/, "", unit); entries[++ne] = unit; depot[unit] = 0; next }
    /^(\.visible )?\.func/ { unit = ""; pending = 1 }
    pending && match($0, /[A-Za-z_][A-Za-z0-9_]*[ \t]*\($/) { unit = substr($0, RSTART, RLENGTH); sub(/[ \t]*\($/, "", unit); depot[unit] = 0; pending = 0; next }
    unit != "" && /__local_depot[0-9]+\[/ { match($0, /\[[0-9]+\]/); depot[unit] = substr($0, RSTART + 1, RLENGTH - 2) + 0 }
    unit != "" { c = $1; sub(/[,;]$/, "", c); if (c in isfunc && c != unit) calls[unit] = calls[unit] " " c }
    function total(u, depth,   best, i, n, list, t) {
      if (depth > 8) return depot[u]
      best = 0; n = split(calls[u], list, " ")
      for (i = 1; i <= n; ++i) { t = total(list[i], depth + 1); if (t > best) best = t }
      return depot[u] + best
    }
    END { for (i = 1; i <= ne; ++i) printf "| %s | %s | %d |\n", build, entries[i], total(entries[i], 0) }' \
    "$OUT/$name.ptx" "$OUT/$name.ptx" >>"$OUT/local-memory.md"
done
cat "$OUT/local-memory.md"
if [ "$fail" -ne 0 ]; then
  echo "nvptx-build: FAILED" >&2
  exit 1
fi
echo "nvptx-build: every kernel file compiles for nvptx64-nvidia-nvcl (PTX in $OUT)"
