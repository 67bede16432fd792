#!/usr/bin/env python3
"""How well a result set's ordering speedups follow the paper's GPU speedups (Tables 2 and 3).

  scripts/paper_correlation.py RESULT_SET [RESULT_SET...] [--bits 32] [--markdown]

Pairs every ok cell of the sets' cells.csv (bounce1 for Table 2, shadow0 for Table 3, the key
length --bits) with the paper's RTX 3060 speedup of the same scene stand-in and encoder
(results/gpu-model/paper_tables.csv, docs/paper.md "Scenes"), and prints per trace class and ray
access mode: the cells paired, the Pearson correlation of the measured speedup with the paper's
and its 95 % interval (Fisher's z, over the cells), Spearman's rank correlation, and the same two
for the SIMT model's lane-efficiency ratio of those cells (deterministic, for reference). A class
whose cells do not cover a table gets no row for it. Standard library only.
"""
import argparse
import csv
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gpu_model_validate import pearson, spearman  # noqa: E402  (one definition of each)

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PAPER = os.path.join(ROOT, "results", "gpu-model", "paper_tables.csv")
TABLES = {"2": "bounce1", "3": "shadow0"}


def fisher_interval(r, n):
    """The 95 % interval of a Pearson correlation over n pairs (Fisher's z transform)."""
    if n <= 3 or not -1.0 < r < 1.0:
        return float("nan"), float("nan")
    z, se = math.atanh(r), 1.0 / math.sqrt(n - 3)
    return math.tanh(z - 1.96 * se), math.tanh(z + 1.96 * se)


def correlation_table(set_dirs, bits="32"):
    """The markdown table (lines) of main's output; scripts/claims.py quotes it too."""
    paper = {}
    with open(PAPER, newline="") as f:
        for r in csv.DictReader(f):
            if r["table"] in TABLES and r["bits"] == bits:
                paper[(r["table"], r["scene"], r["encoder"])] = float(r["paper_speedup"])

    cells = {}  # (table, layout, access) -> [(paper, measured, simt ratio, scene, encoder)]
    for d in set_dirs:
        path = os.path.join(d, "cells.csv")
        if not os.path.exists(path):
            sys.exit(f"paper_correlation: {path} is missing: give result set folders (raysort run --out DIR)")
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                if r["status"] != "ok" or r["bits"] != bits or r["baseline"] != "pixel":
                    continue
                for table, batch in TABLES.items():
                    key = (table, r["scene"], r["encoder"])
                    if r["batch"] == batch and key in paper and r["speedup"]:
                        cells.setdefault((table, r["layout"], r["access"]), []).append(
                            (paper[key], float(r["speedup"]), float(r["simt_lane_efficiency_ratio"]), r["scene"],
                             r["encoder"]))
    if not cells:
        sys.exit("paper_correlation: no cell of the sets pairs with the paper's Tables 2 and 3 "
                 f"(bounce1 / shadow0 at {bits} bits on the paper's scene stand-ins)")

    lines = ["| table | class | access | cells | Pearson [95 %] | Spearman | SIMT ratio: Pearson | Spearman |",
             "|---|---|---|---:|---|---:|---:|---:|"]
    for (table, layout, access), rows in sorted(cells.items()):
        p = [r[0] for r in rows]
        m = [r[1] for r in rows]
        s = [r[2] for r in rows]
        r = pearson(p, m)
        lo, hi = fisher_interval(r, len(rows))
        scenes = len({x[3] for x in rows})
        lines.append(f"| {table} ({TABLES[table]}) | {layout} | {access} | {len(rows)} ({scenes} scenes) | "
              f"{r:.2f} [{lo:.2f}, {hi:.2f}] | {spearman(p, m):.2f} | {pearson(p, s):.2f} | {spearman(p, s):.2f} |")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sets", nargs="+")
    ap.add_argument("--bits", default="32")
    args = ap.parse_args()
    print("\n".join(correlation_table(args.sets, args.bits)))

if __name__ == "__main__":
    main()
