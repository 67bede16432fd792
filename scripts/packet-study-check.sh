#!/usr/bin/env bash
# ctest packet_study_counts: build/packet_study runs on a procedural scene, for closest-hit and
# any-hit rays; the study itself fails where its step hook disagrees with the kernels' visit counts,
# and here every row must exist with at most as many active lanes per step as the packet has lanes.
set -euo pipefail
bin="${1:?usage: packet-study-check.sh PACKET_STUDY_BIN}"
for batch in bounce1 shadow0; do
  out=$("$bin" detail-room 96x54 "$batch")
  echo "$out"
  echo "$out" | awk -v batch="$batch" '
    /packet(16|8|4) / { for (i = 1; i <= NF; ++i) { if ($i ~ /^packet[0-9]+$/) w = substr($i, 7) + 0
                                                   if ($i == "step") lanes = $(i + 1) + 0 }
                        if (lanes > w || lanes <= 0) { print "packet-study-check: " batch ": lanes per step out of range: " $0; exit 1 }
                        rows++ }
    END { if (rows != 18) { print "packet-study-check: " batch ": expected 18 rows (6 orders x 3 widths), got " rows; exit 1 }
          printf "packet-study-check: %s: %d rows, lanes per step within each width\n", batch, rows }'
done
