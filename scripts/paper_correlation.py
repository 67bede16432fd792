#!/usr/bin/env python3
"""How well a result set's ordering speedups follow the paper's GPU speedups (Tables 2 and 3).

  scripts/paper_correlation.py RESULT_SET [RESULT_SET...] [--bits 32] [--by-scene] [--as SCENE=STAND_IN]

Pairs every ok cell of the sets' cells.csv (bounce1 for Table 2, shadow0 for Table 3, the key
length --bits) with the paper's RTX 3060 speedup of the same scene stand-in and encoder
(results/gpu-model/paper_tables.csv, docs/paper.md "Scenes"), and prints per trace class and ray
access mode: the cells paired, the Pearson correlation of the measured speedup with the paper's
and its 95 % interval (Fisher's z, over the cells), Spearman's rank correlation, and the same two
for the SIMT model's lane-efficiency ratio of those cells (deterministic, for reference). A class
whose cells do not cover a table gets no row for it.

--by-scene adds, per table, class, access mode and scene, the Pearson correlation within the scene (its
eight encoders) and over the other scenes' cells without it: which stand-in holds a correlation down.
--as scores a set's scene as one of the paper's stand-ins (e.g. --as
scenes/paper-size/landscape-21m.toml=landscape: the landscape stand-in at the paper's size is scored
against the paper's landscape column, in place of the sets' own `landscape` cells); repeatable.
Standard library only.
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


def paper_speedups(bits="32"):
    """(table, stand-in scene, encoder) -> the paper's RTX 3060 speedup, Tables 2 and 3 at that key length."""
    with open(PAPER, newline="") as f:
        return {(r["table"], r["scene"], r["encoder"]): float(r["paper_speedup"]) for r in csv.DictReader(f)
                if r["table"] in TABLES and r["bits"] == bits}


def paired_cells(set_dirs, bits="32", scene_as=None):
    """(table, layout, access) -> [(paper, measured, simt ratio, scene, encoder)], every ok cell of the
    sets that pairs with a paper cell; scene_as maps a set's scene name to the stand-in it is scored as,
    and the cells of the stand-in it replaces are left out."""
    paper = paper_speedups(bits)
    scene_as = scene_as or {}
    replaced = set(scene_as.values()) - set(scene_as)
    cells = {}
    for d in set_dirs:
        path = os.path.join(d, "cells.csv")
        if not os.path.exists(path):
            sys.exit(f"paper_correlation: {path} is missing: give result set folders (raysort run --out DIR)")
        with open(path, newline="") as f:
            for r in csv.DictReader(f):
                if r["status"] != "ok" or r["bits"] != bits or r["baseline"] != "pixel":
                    continue
                if r["scene"] in replaced:
                    continue  # another scene stands in for this paper column (--as)
                scene = scene_as.get(r["scene"], r["scene"])
                for table, batch in TABLES.items():
                    key = (table, scene, r["encoder"])
                    if r["batch"] == batch and key in paper and r["speedup"]:
                        cells.setdefault((table, r["layout"], r["access"]), []).append(
                            (paper[key], float(r["speedup"]), float(r["simt_lane_efficiency_ratio"]), scene,
                             r["encoder"]))
    if not cells:
        sys.exit("paper_correlation: no cell of the sets pairs with the paper's Tables 2 and 3 "
                 f"(bounce1 / shadow0 at {bits} bits on the paper's scene stand-ins)")
    return cells


def correlations(set_dirs, bits="32", scene_as=None):
    """(table, layout, access) -> {cells, scenes, pearson, lo, hi, spearman, simt_pearson, simt_spearman}:
    the measured speedups' and the SIMT ratios' correlation with the paper's, over the paired cells."""
    out = {}
    for key, rows in paired_cells(set_dirs, bits, scene_as).items():
        p, m, s = [r[0] for r in rows], [r[1] for r in rows], [r[2] for r in rows]
        r = pearson(p, m)
        lo, hi = fisher_interval(r, len(rows))
        out[key] = {"cells": len(rows), "scenes": len({x[3] for x in rows}), "pearson": r, "lo": lo, "hi": hi,
                    "spearman": spearman(p, m), "simt_pearson": pearson(p, s), "simt_spearman": spearman(p, s)}
    return out


def correlation_table(set_dirs, bits="32", scene_as=None):
    """The markdown table (lines) of main's output; scripts/claims.py quotes it too."""
    lines = ["| table | class | access | cells | Pearson [95 %] | Spearman | SIMT ratio: Pearson | Spearman |",
             "|---|---|---|---:|---|---:|---:|---:|"]
    for (table, layout, access), c in sorted(correlations(set_dirs, bits, scene_as).items()):
        lines.append(f"| {table} ({TABLES[table]}) | {layout} | {access} | {c['cells']} ({c['scenes']} scenes) | "
                     f"{c['pearson']:.2f} [{c['lo']:.2f}, {c['hi']:.2f}] | {c['spearman']:.2f} | "
                     f"{c['simt_pearson']:.2f} | {c['simt_spearman']:.2f} |")
    return lines


def scene_correlations(set_dirs, bits="32", scene_as=None):
    """(table, layout, access, scene) -> (cells in the scene, Pearson within them, cells of the other scenes,
    Pearson over those: the correlation without the scene); nan where fewer than three cells."""
    def r(rows):
        return pearson([x[0] for x in rows], [x[1] for x in rows]) if len(rows) > 2 else float("nan")

    out = {}
    for (table, layout, access), rows in paired_cells(set_dirs, bits, scene_as).items():
        for scene in {x[3] for x in rows}:
            inside = [x for x in rows if x[3] == scene]
            rest = [x for x in rows if x[3] != scene]
            out[(table, layout, access, scene)] = (len(inside), r(inside), len(rest), r(rest))
    return out


def by_scene_table(set_dirs, bits="32", scene_as=None):
    """scene_correlations as markdown lines (--by-scene)."""
    lines = ["| table | class | access | scene | cells | Pearson within the scene | without it: cells, Pearson |",
             "|---|---|---|---|---:|---:|---|"]
    for (table, layout, access, scene), (n_in, within, n_out, without) in sorted(
            scene_correlations(set_dirs, bits, scene_as).items()):
        lines.append(f"| {table} ({TABLES[table]}) | {layout} | {access} | {scene} | {n_in} | {within:.2f} | "
                     f"{n_out}, {without:.2f} |")
    return lines


def _scene_as(pairs):
    """--as SCENE=STAND_IN values as a dict."""
    out = {}
    for p in pairs:
        scene, sep, stand_in = p.rpartition("=")
        if not sep or not scene or not stand_in:
            sys.exit(f"paper_correlation: --as {p!r}: give SCENE=STAND_IN, e.g. "
                     "scenes/paper-size/landscape-21m.toml=landscape")
        out[scene] = stand_in
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("sets", nargs="+")
    ap.add_argument("--bits", default="32")
    ap.add_argument("--by-scene", action="store_true", help="also each scene's own and leave-it-out correlation")
    ap.add_argument("--as", dest="scene_as", action="append", default=[], metavar="SCENE=STAND_IN",
                    help="score a set's scene as one of the paper's stand-ins (repeatable)")
    args = ap.parse_args()
    scene_as = _scene_as(args.scene_as)
    print("\n".join(correlation_table(args.sets, args.bits, scene_as)))
    if args.by_scene:
        print()
        print("\n".join(by_scene_table(args.sets, args.bits, scene_as)))

if __name__ == "__main__":
    main()
