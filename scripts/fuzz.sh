#!/usr/bin/env bash
# make fuzz: builds the libFuzzer targets (fuzz/, CMake option RAYSORT_FUZZ, clang with
# -fsanitize=fuzzer,address,undefined) in a separate build folder, seeds their corpora from
# scenes/*.toml, the odd-obj folder, the golden result set and fuzz/corpus (the committed corpus
# grown by long runs), and runs each for FUZZ_SECONDS (default 60), or FUZZ_RUNS executions.
# The scene-format fuzzers (ply, gltf, pbrt; issue 45) are seeded by scripts/fuzz_seeds.py and the
# odd-obj folder's PLY files.
# Installs clang from Debian when missing, so the default build and CI stay free of it.
# A finding is written as crash-*/leak-*/timeout-*/oom-* into the build folder and fails the run.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${FUZZ_BUILD:-build-fuzz}"
SECONDS_EACH="${FUZZ_SECONDS:-60}"
RUNS="${FUZZ_RUNS:-}"  # executions per target instead of a time budget (e.g. 10000000)
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
# FUZZ_TARGETS (default: all) picks some, e.g. FUZZ_TARGETS="ply gltf pbrt": only those are built and run.
TARGETS="${FUZZ_TARGETS:-obj scene result_set cli ply gltf pbrt ray_file}"
cmake --build "$BUILD" -j "$JOBS" --target $(for t in $TARGETS; do printf '%s_fuzzer ' "$t"; done)

# Seeds: the scene files, and every OBJ of the odd-obj folder under 256 KiB (when it is there).
mkdir -p "$BUILD/seeds/scene" "$BUILD/seeds/obj" "$BUILD/seeds/result_set" "$BUILD/corpus/scene" "$BUILD/corpus/obj" \
  "$BUILD/corpus/result_set" "$BUILD/seeds/cli" "$BUILD/corpus/cli"
cp scenes/*.toml "$BUILD/seeds/scene/"
if [ -d "$ODD_OBJ" ]; then
  find "$ODD_OBJ" -name '*.obj' -size -256k -exec cp {} "$BUILD/seeds/obj/" \;
else
  echo "fuzz: $ODD_OBJ not found; OBJ seeds are a generated cube only"
fi
printf 'v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\nf -4 -3 -2\n' > "$BUILD/seeds/obj/quad.obj"
# Scene-format seeds (issue 45): the odd-obj folder's PLY files (assimp's own test models, from Debian
# assimp-testmodels) and a small file of each format made here (scripts/fuzz_seeds.py).
mkdir -p "$BUILD/seeds/ply" "$BUILD/seeds/gltf" "$BUILD/seeds/pbrt" "$BUILD/corpus/ply" "$BUILD/corpus/gltf" \
  "$BUILD/corpus/pbrt" "$BUILD/seeds/ray_file" "$BUILD/corpus/ray_file"
[ -d "$ODD_OBJ" ] && find "$ODD_OBJ" -name '*.ply' -size -256k -exec cp {} "$BUILD/seeds/ply/" \;
python3 scripts/fuzz_seeds.py "$BUILD/seeds"
# Result-set seeds: the golden set's cell records (selector byte 0) and meta.json (1), and rules (2).
for f in tests/golden/quick-tiny/cells/cornell__primary__*.json; do
  { printf '\000'; cat "$f"; } > "$BUILD/seeds/result_set/cell-$(basename "$f")"
done
{ printf '\001'; cat tests/golden/quick-tiny/meta.json; } > "$BUILD/seeds/result_set/meta.json"
for rule in 'speedup<-5%' 'overhead_pct>+10%' 'anc!=' 'anc!=0.01' 'status!=ok' 'status==timeout' missing; do
  printf '\002%s' "$rule" > "$BUILD/seeds/result_set/rule-$(printf '%s' "$rule" | tr -c 'a-z0-9' '_')"
done

# Command-line seeds: one command line per file, its arguments separated by NUL bytes.
i=0
while IFS= read -r line; do
  i=$((i + 1))
  printf '%s' "$line" | tr ' ' '\000' > "$BUILD/seeds/cli/line-$i"
done <<'LINES'
run --scenes cornell --encoders hcc,origin --bits 16,32 --resolution 48x27 --reps 3 --warmup 0 --max-time 0.5
run --preset quick --lambda 0.25 --twopoint-length 0.5 --direction-bits 2 --region-bits 4 --traffic-blend 0.5
run --scenes cornell --cost-bits 3 --timeout 10 --shard-plan 4 --seed 7 --spp 2 --shadow-rays 2 --bounces 3
run --scenes cornell --shard 1/2 --out r --top-bits 8 --max-noise 2 --access all --variant both --layout all
trace --scene cornell --resolution 64x64 --reps 1 --layout wide,packet --variant both --adjudicate
encodebench --scene cornell --bits 16,32,64 --versus hcc --direction-bits 2 --cost-bits 4
sortcheck --sizes 1,255,4097 --bits 32,64 --work-group 1 --items 8 --radix-bits 8 --scan-work-group 64
sortbench --reps 3 --ref-reps 2 --no-large
render --scene cornell --bits 16 --exposure -1.5 --host --overlay hcc
scenes --describe cornell --resolution 8x8 --spp 1
compare a b --fail-if speedup<-5% --out x.md
merge a b -o c --force
--kernels cl report r
sweep a b --out s.md
LINES

# Corpora grown by long runs (minimized with -merge=1), committed as one tarball per target.
for grown in fuzz/corpus/*-grown.tar.gz; do
  [ -e "$grown" ] || continue
  target="$(basename "$grown" -grown.tar.gz)"
  tar xzf "$grown" -C "$BUILD/seeds/$target"
done

status=0
for target in $TARGETS; do
  budget=(-max_total_time="$SECONDS_EACH")
  [ -n "$RUNS" ] && budget=(-runs="$RUNS")
  echo "fuzz: ${target}_fuzzer for ${RUNS:+$RUNS runs}${RUNS:-${SECONDS_EACH}s}"
  committed="$PWD/fuzz/corpus/$target"
  (cd "$BUILD" && ./${target}_fuzzer "${budget[@]}" -timeout=10 -rss_limit_mb=2048 \
     -max_len=65536 -print_final_stats=1 "corpus/$target" "seeds/$target" \
     $( [ -d "$committed" ] && echo "$committed" ) 2>"fuzz-$target.log") || status=1
  grep -E "^stat::number_of_executed_units|^Done|ERROR|SUMMARY" "$BUILD/fuzz-$target.log" || true
done
if [ "$status" -ne 0 ]; then
  echo "fuzz: FINDINGS: see $BUILD/fuzz-*.log and $BUILD/crash-* (reproduce: $BUILD/<target> <file>)"
fi
exit "$status"
