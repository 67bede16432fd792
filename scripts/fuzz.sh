#!/usr/bin/env bash
# make fuzz: builds the libFuzzer targets (fuzz/, CMake option RAYSORT_FUZZ, clang with
# -fsanitize=fuzzer,address,undefined) in a separate build folder, seeds their corpora from
# scenes/*.toml and the odd-obj folder, and runs each for FUZZ_SECONDS (default 60).
# Installs clang from Debian when missing, so the default build and CI stay free of it.
# A finding is written as crash-*/leak-*/timeout-*/oom-* into the build folder and fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${FUZZ_BUILD:-build-fuzz}"
SECONDS_EACH="${FUZZ_SECONDS:-60}"
JOBS="${JOBS:-$(nproc 2>/dev/null || echo 2)}"
ODD_OBJ="${RAYSORT_SCENE_ROOT:-$(cd .. && pwd)/shared/scenes}/odd-obj"

# Debian 12: clang 14, whose libFuzzer runtime is in libclang-rt-14-dev.
need=()
command -v clang++ >/dev/null || need+=(clang)
ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1 || need+=(libclang-rt-14-dev)
if [ "${#need[@]}" -gt 0 ]; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "fuzz: installing ${need[*]}"
  $SUDO apt-get update -q
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -q --no-install-recommends "${need[@]}"
fi

cmake -S . -B "$BUILD" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ -DRAYSORT_FUZZ=ON \
  -DBUILD_TESTING=OFF >/dev/null
cmake --build "$BUILD" -j "$JOBS" --target obj_fuzzer scene_fuzzer

# Seeds: the scene files, and every OBJ of the odd-obj folder under 256 KiB (when it is there).
mkdir -p "$BUILD/seeds/scene" "$BUILD/seeds/obj" "$BUILD/corpus/scene" "$BUILD/corpus/obj"
cp scenes/*.toml "$BUILD/seeds/scene/"
if [ -d "$ODD_OBJ" ]; then
  find "$ODD_OBJ" -name '*.obj' -size -256k -exec cp {} "$BUILD/seeds/obj/" \;
else
  echo "fuzz: $ODD_OBJ not found; OBJ seeds are a generated cube only"
fi
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf -4 -3 -2\n' > "$BUILD/seeds/obj/quad.obj"

status=0
for target in obj scene; do
  echo "fuzz: ${target}_fuzzer for ${SECONDS_EACH}s"
  (cd "$BUILD" && ./${target}_fuzzer -max_total_time="$SECONDS_EACH" -timeout=10 -rss_limit_mb=2048 \
     -max_len=65536 -print_final_stats=1 "corpus/$target" "seeds/$target" 2>"fuzz-$target.log") || status=1
  grep -E "^stat::number_of_executed_units|^Done|ERROR|SUMMARY" "$BUILD/fuzz-$target.log" || true
done
if [ "$status" -ne 0 ]; then
  echo "fuzz: FINDINGS: see $BUILD/fuzz-*.log and $BUILD/crash-* (reproduce: $BUILD/<target> <file>)"
fi
exit "$status"
