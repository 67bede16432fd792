#!/usr/bin/env bash
# Packs a self-contained raysort for a GPU machine that has NVIDIA's driver but none of this
# project's Debian packages and no network (docs/gpu-runs.md): a Release build without OpenImageIO
# and Embree (-DRAYSORT_IMAGES=OFF -DRAYSORT_EMBREE=OFF: no PNGs or plots, the tables and CSV are
# all there), every shared library it loads, this machine's dynamic loader to start it with, and
# the real scenes the GPU model's validation matrix reads, compressed.
#
#   scripts/device-bundle.sh [OUT]       OUT defaults to .device/ (ignored by git; carry it)
#   DEVICE_BUILD_DIR=…                    the build folder (default build-device/)
#
# The bundle runs as OUT/raysort (a wrapper): 15 MB of program and libraries, 7.5 MB of scenes.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
out="${1:-$root/.device}"
build="${DEVICE_BUILD_DIR:-$root/build-device}"
scene_root="${RAYSORT_SCENE_ROOT:-$root/../shared/scenes}"
# The OBJ folders of the validation matrix's scenes (device-check.sh's VALIDATION_SCENES), read from
# their scene files' `obj = "folder/file.obj"` lines (procedural scenes have none).
validation_scenes="$(sed -n 's/^VALIDATION_SCENES="\(.*\)"/\1/p' "$root/scripts/device-check.sh")"
scene_dirs=($(for s in ${validation_scenes//,/ }; do
  sed -n 's/^[[:space:]]*obj[[:space:]]*=[[:space:]]*"\([^/"]*\)\/.*/\1/p' "$root/scenes/$s.toml"
done | sort -u))
[ "${#scene_dirs[@]}" -gt 0 ] || { echo "device-bundle: no scene folders found for '$validation_scenes'" >&2; exit 1; }

# A unity build (several sources per compiler run): the same code and flags, in about half the
# time of a source-by-source build on two cores (the device_bundle test runs this build in CI).
# Two sources that each define the same name in an anonymous namespace fail it ("redefinition
# of ..."): give one of them another name, or share the definition through a header.
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DRAYSORT_IMAGES=OFF -DRAYSORT_EMBREE=OFF \
  -DCMAKE_UNITY_BUILD=ON > /dev/null
cmake --build "$build" --target raysort -j "$(nproc)" > /dev/null

rm -rf "$out"
mkdir -p "$out/lib"
cp "$build/raysort" "$out/raysort.bin"
# Every library the loader resolves, the C library and the loader itself included: the machine's
# own may be older than what this build needs. NVIDIA's OpenCL library comes from that machine.
loader=""
while read -r name arrow path _; do
  if [ "$arrow" = "=>" ] && [ -f "$path" ]; then
    cp -L "$path" "$out/lib/"
  elif [[ "$name" == /*ld-linux* ]]; then
    loader="$name"
  fi
done < <(ldd "$build/raysort")
[ -n "$loader" ] || { echo "device-bundle: no dynamic loader in ldd's output" >&2; exit 1; }
cp -L "$loader" "$out/lib/ld-linux.so"
cat > "$out/raysort" <<'EOF'
#!/bin/sh
# raysort from the bundle (scripts/device-bundle.sh): started by the bundled loader on the bundled
# libraries, then those of RAYSORT_EXTRA_LIBS (NVIDIA's driver folder) and the machine's own.
here="$(dirname "$(readlink -f "$0")")"
exec "$here/lib/ld-linux.so" --library-path "$here/lib${RAYSORT_EXTRA_LIBS:+:$RAYSORT_EXTRA_LIBS}" "$here/raysort.bin" "$@"
EOF
chmod +x "$out/raysort"

if [ -d "$scene_root" ]; then
  tar -C "$scene_root/.." -czf "$out/scenes.tar.gz" $(printf "$(basename "$scene_root")/%s " "${scene_dirs[@]}")
else
  echo "device-bundle: no scenes at $scene_root (RAYSORT_SCENE_ROOT): only procedural scenes will run there" >&2
fi
# The commit the bundle was built from (the device's copy of the tree may have no .git).
{ git -C "$root" rev-parse --short HEAD; git -C "$root" diff --quiet HEAD -- || echo "(with uncommitted changes)"; } \
  | paste -sd' ' > "$out/commit"
"$out/raysort" --version
du -sh "$out"/lib "$out"/raysort.bin "$out"/scenes.tar.gz 2>/dev/null || true
# The device tool sends the checkout's tracked files with the bundle, at most 64 MiB in all
# (docs/gpu-runs.md): say when results/ must be moved out for the call.
tree_mib=$(( ($(git -C "$root" ls-files -z | (cd "$root" && xargs -0 cat 2>/dev/null) | wc -c) + $(du -sk "$out" | cut -f1) * 1024) / 1048576 ))
if [ "$tree_mib" -gt 60 ]; then
  echo "device-bundle: the checkout's tracked files and the bundle come to about $tree_mib MiB, over the device tool's 64:"
  echo "  move results/ out of the checkout for the call (mv results ../results-hold; back after)"
fi
