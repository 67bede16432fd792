#!/usr/bin/env bash
# make test-sanitize: the host-side tests under AddressSanitizer + UndefinedBehaviorSanitizer.
# Builds in build-asan (gcc, -fsanitize=address,undefined -fno-omit-frame-pointer, any UB report is
# fatal) and runs every test binary that needs no OpenCL device, plus the device-free tests of
# bench_test (result sets, compare, matrix validation) and cli_test (refusals before any work, which
# run the sanitized raysort binary). Device tests are left out: PoCL compiles kernels with LLVM
# inside the process, which under ASan is slow and reports leaks inside the driver that are not
# ours. detect_leaks stays on for these tests: none of them loads the OpenCL ICD.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${ASAN_BUILD:-build-asan}"
JOBS="${JOBS:-$(nproc 2>/dev/null || echo 2)}"
# -Wno-maybe-uninitialized: gcc 12 warns falsely inside std::regex/std::function under ASan (and CI
# builds with -Werror).
SAN="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined -Wno-maybe-uninitialized"
HOST_TESTS=(bvh_test cut_test metrics_test odd_input_test scene_test shared_math_test)

start=$(date +%s)
cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_FLAGS="$SAN" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
cmake --build "$BUILD" -j "$JOBS" --target raysort bench_test cli_test adjudicate_test frame_memory_test "${HOST_TESTS[@]}"

export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
for t in "${HOST_TESTS[@]}"; do
  echo "test-sanitize: $t"
  "$BUILD/$t" --gtest_brief=1
done
echo "test-sanitize: bench_test (device-free tests)"
"$BUILD/bench_test" --gtest_brief=1 --gtest_filter='ResultSet.*:Compare.*:Matrix.RefusesImpossibleCombinationsBeforeWork'
echo "test-sanitize: cli_test (refusals)"
"$BUILD/cli_test" --gtest_brief=1 --gtest_filter='Cli.UnknownNamesListTheValidOnes:Cli.ImpossibleCombinationsRefusedBeforeWork:CliNumbers.*:CliExitCodes.*'
echo "test-sanitize: adjudicate_test and frame_memory_test (the exact oracle, the memory model)"
"$BUILD/adjudicate_test" --gtest_brief=1 --gtest_filter='ExactOracle.HandMadeTruths:ExactOracle.RaysRoundTripThroughJson'
"$BUILD/frame_memory_test" --gtest_brief=1 --gtest_filter='FrameMemory.ModelCountsEveryBatchTheEffectsImply:FrameMemory.RenderIsSizedByItsPassesNotItsSamples'
echo "test-sanitize: clean in $(( $(date +%s) - start )) s"
