#!/usr/bin/env bash
# The sources `make fuzz` compiles with clang, checked in every `make test` without building the
# fuzzers: clang++-15 -fsyntax-only, C++20, over fuzz/*.cpp and the host files the fuzz targets link
# (host/scene, host/util, the result-set reader in host/bench and the trace class names it checks, and
# the CLI's files that cli_fuzzer compiles, host/app but main.cpp; CMakeLists.txt, RAYSORT_FUZZ).
# gcc accepts some C++20 that clang 14/15 do not (a structured binding captured by a lambda broke
# `make fuzz` twice); CI has clang-15 for the NVIDIA build anyway. A few seconds a file, two at once.
# Exit 77 (ctest: skipped) without clang++-15, except under CI=true (exit 1).
set -euo pipefail
cd "$(dirname "$0")/.."
CXX="${CLANGXX:-clang++-15}"
if ! command -v "$CXX" >/dev/null; then
  msg="fuzz-sources-clang: needs $CXX (Debian: clang-15, scripts/install-deps.sh)"
  if [ "${CI:-}" = "true" ]; then echo "$msg" >&2; exit 1; fi
  echo "SKIPPED: $msg"
  exit 77
fi
files=(fuzz/*.cpp host/scene/*.cpp host/util/*.cpp host/bench/record.cpp host/bench/record_fields.cpp
       host/bench/record_json.cpp host/bench/record_columns.cpp host/bench/result_set.cpp host/bench/encoder_files.cpp
       host/bench/compare.cpp host/bench/protocol.cpp host/bench/tables.cpp host/bench/plots.cpp
       host/trace/trace_class.cpp host/app/cmd_*.cpp host/app/commands.cpp host/app/options.cpp)
printf '%s\n' "${files[@]}" | xargs -P 2 -I{} "$CXX" -std=c++20 -fsyntax-only -w -Ihost -Icl \
  -DCL_TARGET_OPENCL_VERSION=120 -DCL_HPP_ENABLE_EXCEPTIONS -DCL_HPP_MINIMUM_OPENCL_VERSION=120 \
  -DCL_HPP_TARGET_OPENCL_VERSION=120 -DRAYSORT_DEFAULT_SCENE_ROOT='"."' -DRAYSORT_SOURCE_DIR='"."' \
  -DRAYSORT_VERSION='"0"' {}
echo "fuzz-sources-clang: ${#files[@]} files compile with $CXX"
