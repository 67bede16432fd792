#!/usr/bin/env python3
"""Our sorted trace with its whole overhead against Embree's fastest path on the NoSort order.

  scripts/net_vs_embree.py RESULT_SET [RESULT_SET...]

Reads the cell files of result sets run with `raysort run --embree-paths ...` (docs/measurement.md,
"Embree on sorted orders"). For every ok sorted cell it pairs, round by round, the time of Embree's
fastest path in NoSort order (the path with the lowest median of the cell's `embree:<path>:nosort`
samples) with our encode + sort + permute + trace of the same round, and prints Embree's time over
ours: the Hodges-Lehmann estimate of the per-round ratio (on logarithms) with its 95 % interval from
the exact signed-rank distribution, as the protocol's own paired estimates (docs/measurement.md).
Above 1: the sorted trace, overhead included, beats Embree's best path on the unsorted rays (issue
40's stretch figure). Standard library only.
"""
import glob
import json
import math
import os
import statistics
import sys


def signed_rank_critical(n, alpha=0.05):
    """The largest k with P(W+ <= k) <= alpha / 2 for n pairs (exact; -1 when none)."""
    counts = [1]  # counts[s]: subsets of 1..i whose ranks sum to s
    for i in range(1, n + 1):
        nxt = counts + [0] * i
        for s, c in enumerate(counts):
            nxt[s + i] += c
        counts = nxt
    total, acc, k = 2 ** n, 0, -1
    for s, c in enumerate(counts):
        acc += c
        if acc / total > alpha / 2:
            break
        k = s
    return k


def hodges_lehmann(x):
    """Estimate and 95 % interval of the centre of x from its Walsh averages."""
    n = len(x)
    walsh = sorted((x[i] + x[j]) / 2 for i in range(n) for j in range(i, n))
    k = signed_rank_critical(n)
    est = statistics.median(walsh)
    if k < 0:
        return est, walsh[0], walsh[-1]
    return est, walsh[k], walsh[len(walsh) - 1 - k]


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    rows = []
    for d in sys.argv[1:]:
        files = sorted(glob.glob(os.path.join(d, "cells", "*.json")))
        if not files:
            sys.exit(f"net_vs_embree: {d} holds no cell files (cells/*.json): give result set folders")
        for f in files:
            c = json.load(open(f))
            s = c.get("samples", {})
            if c.get("status") != "ok" or c.get("encoder") == "nosort" or "encode" not in s:
                continue
            paths = {k.split(":")[1]: v for k, v in s.items() if k.startswith("embree:") and k.endswith(":nosort")}
            if not paths:
                continue
            best = min(paths, key=lambda p: statistics.median(paths[p]))
            ours = [a + b + p + t for a, b, p, t in zip(s["encode"], s["sort"], s.get("permute", [0] * len(s["trace"])),
                                                         s["trace"])]
            logs = [math.log(e / o) for e, o in zip(paths[best], ours)]
            est, lo, hi = hodges_lehmann(logs)
            rows.append((c["scene"], c["batch"], c["encoder"], c["layout"], c["access"], best, len(logs),
                         math.exp(est), math.exp(lo), math.exp(hi)))
    print("| scene, batch | encoder | class | access | Embree's best NoSort path | Embree / ours (encode + sort + permute + trace) |")
    print("|---|---|---|---|---|---|")
    for r in sorted(rows):
        print(f"| {r[0]} {r[1]} | {r[2]} | {r[3]} | {r[4]} | `{r[5]}` | {r[7]:.3f} [{r[8]:.3f}, {r[9]:.3f}] "
              f"({r[6]} rounds) |")


if __name__ == "__main__":
    main()
