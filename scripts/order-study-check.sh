#!/usr/bin/env bash
# ctest order_study_oracle: build/order_study runs on a procedural scene and its step-count oracle
# is the best lane efficiency of every order it prints. Sorting by step count minimises the sum of
# each warp's longest trail (consecutive groups of sorted values have the least sum of maxima), so
# no key can beat it on lane efficiency; a row above it means the study or the SIMT model is wrong.
set -euo pipefail
bin="${1:?usage: order-study-check.sh ORDER_STUDY_BIN}"
out=$("$bin" detail-room 96x54 bounce1)
echo "$out"
echo "$out" | awk '
  /lane/ { for (i = 1; i <= NF; ++i) if ($i == "lane") v = $(i + 1) + 0
           if ($0 ~ /oracle: step count/) oracle = v; else if (v > best) { best = v; name = $0 } ; rows++ }
  END {
    if (rows < 10) { print "order-study-check: expected the study rows, got " rows; exit 1 }
    if (best > oracle + 1e-9) { print "order-study-check: a key beats the step-count oracle: " name; exit 1 }
    printf "order-study-check: %d orders, none above the step-count oracle (%.3f)\n", rows, oracle }'
