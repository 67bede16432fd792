"""results/README.md, "What ordering buys as the kernel gets faster" (issue 46) and the CWBVH's DRAM bytes: each trace class's own
NoSort speed beside each encoder's speedup and net speedup, in the GPU model (results/gpu-model/
classes-16c0de1) and measured on PoCL (paper-1spp-stream-23a1a19), with scripts/class_speedups.py."""
from class_speedups import class_trend, profile_dram_gbps, rows, table_lines

import csv
import os

from .sets import CLASSES_BINARY, CLASSES_WIDE8, CWBVH_DRAM, KERNEL_CLASSES_MODEL, STREAM_CLASSES


def model_block():
    return "\n".join(table_lines([KERNEL_CLASSES_MODEL], "model", profile_dram_gbps())[0])


def model_scenes_block():
    """Every GPU class on every paper scene, bounce1 and shadow0, HCC (the DRAM set: wide and cwbvh;
    then wide8; binary and binary-ww)."""
    return "\n".join(table_lines([CWBVH_DRAM, CLASSES_WIDE8, CLASSES_BINARY], "model", profile_dram_gbps())[0])


def cwbvh_gains_phrase():
    """In how many scene-batch pairs the compressed tree's HCC speedup exceeds the 4-wide tree's."""
    nosort, out = rows([CWBVH_DRAM], "model", profile_dram_gbps())
    speed = {(k[0], k[1], k[2]): s for k, enc, _, _, s, _ in out if enc == "hcc"}
    pairs = sorted({(sc, b) for sc, b, _ in speed})
    more = sum(speed[(sc, b, "cwbvh")] > speed[(sc, b, "wide")] for sc, b in pairs)
    return f"in {more} of the {len(pairs)} scene and batch pairs"


def net_trend_phrase():
    """Over every scene-batch pair of the five-class sets: how often the fastest class (its own NoSort)
    has the lowest net speedup, and the slowest the highest."""
    low, high, n = class_trend([CWBVH_DRAM, CLASSES_WIDE8, CLASSES_BINARY], "model", profile_dram_gbps())
    return (f"the fastest class has the lowest net in {low} of the {n} scene and batch pairs, "
            f"the slowest the highest in {high}")


def pocl_block():
    return "\n".join(table_lines([STREAM_CLASSES], "pocl", profile_dram_gbps())[0])


def cwbvh_dram_block():
    """DRAM bytes per ray in the GPU model, cwbvh against wide, per paper scene, batch and order
    (results/gpu-model/cwbvh-dram-9ca3605)."""
    with open(os.path.join(CWBVH_DRAM, "cells.csv"), newline="") as f:
        cells = {(r["scene"], r["batch"], r["encoder"], r["layout"]): r for r in csv.DictReader(f) if r["status"] == "ok"}
    lines = ["| scene | batch | order | wide B/ray | cwbvh B/ray | cwbvh / wide |", "|---|---|---|---:|---:|---:|"]
    for (scene, batch, enc, layout), w in sorted(cells.items()):
        c = cells.get((scene, batch, enc, "cwbvh"))
        if layout != "wide" or c is None:
            continue
        bw, bc = float(w["gpu_dram_bytes"]) / int(w["rays"]), float(c["gpu_dram_bytes"]) / int(c["rays"])
        lines.append(f"| {scene} | {batch} | {enc} | {bw:.1f} | {bc:.1f} | {bc / bw:.3f} |")
    return "\n".join(lines)
