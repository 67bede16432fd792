#!/usr/bin/env bash
# ctest read_rays_python: the Python reader (scripts/read_rays.py) reads a batch that
# `raysort rays --export --hits` wrote, and finds in it what raysort printed: the batch name, the
# ray count, the scene's SHA-256, and the FNV-1a hashes of the rays and of the hits (docs/rays-format.md).
# Exit 77 (ctest: skipped) without python3, except under CI=true (exit 1).
set -euo pipefail
bin="${1:?usage: read-rays-check.sh RAYSORT_BIN}"
if ! command -v python3 > /dev/null; then
  msg="read-rays-check: python3 is not installed (apt-get install python3)"
  if [ "${CI:-}" = "true" ]; then echo "$msg" >&2; exit 1; fi
  echo "$msg; skipped"
  exit 77
fi
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
"$bin" rays --scene cornell --resolution 48x27 --batch bounce1 --hits --export "$dir/cornell-bounce1.rays" | tee "$dir/out.txt"
python3 - "$dir/cornell-bounce1.rays" "$dir/out.txt" << 'PY'
import re, struct, sys
sys.path.insert(0, "scripts")
from read_rays import read_rays

def fnv1a(data):
    h = 0xcbf29ce484222325
    for byte in data:
        h = ((h ^ byte) * 0x100000001b3) & 0xFFFFFFFFFFFFFFFF
    return f"{h:016x}"

b = read_rays(sys.argv[1])
out = open(sys.argv[2]).read()
printed = re.search(r"batch +(\S+): (\d+) rays .*rays hash (\w+), hits hash (\w+)", out)
scene = re.search(r"scene sha256 (\w+)", out).group(1)
found = (b["batch"], str(len(b["rays"])), fnv1a(b"".join(struct.pack("<8f", *r) for r in b["rays"])),
         fnv1a(b"".join(struct.pack("<fI", *h) for h in b["hits"])))
if found != printed.groups() or b["scene_sha256"] != scene or not b["command"].startswith("raysort rays"):
    sys.exit(f"read-rays-check: the reader found {found} scene {b['scene_sha256']}, raysort printed {printed.groups()} scene {scene}")
print(f"read-rays-check: the Python reader agrees: {found[0]}, {found[1]} rays, rays hash {found[2]}, hits hash {found[3]}")
PY
