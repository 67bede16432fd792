#!/usr/bin/env bash
# ctest region_study_runs: build/region_study runs on a procedural scene and prints all its rows
# (HCC, MLHCC, PPC, then four region codes for each r = 2 ... 6). The study itself checks that its
# halved-cell HAD keys are hcc-region's keys without statistics, and fails (exit 2) if they differ.
set -euo pipefail
bin="${1:?usage: region-study-check.sh REGION_STUDY_BIN}"
out=$("$bin" detail-room 96x54 bounce1)
echo "$out"
rows=$(echo "$out" | grep -c ' lane ' || true)
if [ "$rows" -ne 23 ]; then echo "region-study-check: expected 23 rows, got $rows"; exit 1; fi
echo "region-study-check: 23 rows"
