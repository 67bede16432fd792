#!/usr/bin/env python3
"""What ordering buys as the trace kernel gets faster (issue 46, item 4): per scene, batch and trace
class, the class's own NoSort speed and each encoder's speedup and net speedup over it, from result
sets' cells.csv.

--source model reads the GPU model's columns (run --gpu-model): the class's NoSort speed is rays over
its predicted trace time, the speedup is gpu_model_speedup, and the net speedup charges the sorted
trace with the encode, sort and permute a GPU would run, priced at the profile's DRAM bandwidth
(bandwidth-bound: OVERHEAD_BYTES per ray, below) since the model predicts traces only.
--source pocl reads the measured columns (trace_mrays of the NoSort cell, speedup, net_speedup).

  scripts/class_speedups.py SET [SET ...] --source model|pocl [--svg PLOT] [--profile TOML]
"""
import argparse
import csv
import os
import sys
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# Bytes a GPU moves per ray for an order, each stage at the memory bound: encode reads the ray (32 B)
# and writes a 32-bit key and its index (8 B); an LSD radix sort of 32-bit keys with 8-bit digits
# makes 4 passes, each reading the keys for its histogram (4 B) and reading and writing key and
# index (16 B); the permute reads the index (4 B), reads a ray and writes it (64 B).
OVERHEAD_BYTES = 32 + 8 + 4 * (4 + 16) + 4 + 64


def cells(paths):
    for path in paths:
        with open(os.path.join(path, "cells.csv")) as f:
            yield from csv.DictReader(f)


def rows(paths, source, dram_gbps):
    nosort, out = {}, []
    for c in cells(paths):
        if c["status"] != "ok":
            continue
        key = (c["scene"], c["batch"], c["layout"], c["variant"])
        if c["encoder"] == "nosort":
            if source == "model":
                nosort[key] = int(c["rays"]) / float(c["gpu_model_time_us"])  # MRays/s
            else:
                nosort[key] = float(c["trace_mrays"])
            continue
        if source == "model":
            t_sorted = float(c["gpu_model_time_us"])
            t_nosort = t_sorted * float(c["gpu_model_speedup"])
            overhead_us = int(c["rays"]) * OVERHEAD_BYTES / (dram_gbps * 1e3)
            speedup, net = float(c["gpu_model_speedup"]), t_nosort / (t_sorted + overhead_us)
        else:
            speedup, net = float(c["speedup"]), float(c["net_speedup"])
        out.append((key, c["encoder"], int(c["bits"]), c["access"], speedup, net))
    return nosort, out


def svg(path, points, encoders):
    """points: [(nosort MRays/s, speedup, net, encoder, class)]: speedup (filled) and net (hollow)."""
    colours = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf"]
    w, h, m = 640, 440, 60
    xs = [p[0] for p in points]
    x_lo, x_hi = 0.0, max(xs) * 1.1
    y_lo, y_hi = min(0.6, min(min(p[1], p[2]) for p in points) - 0.05), max(max(p[1], p[2]) for p in points) + 0.1
    sx = lambda v: m + (v - x_lo) / (x_hi - x_lo) * (w - 2 * m)
    sy = lambda v: h - m - (v - y_lo) / (y_hi - y_lo) * (h - 2 * m)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<rect x="{m}" y="{m}" width="{w - 2 * m}" height="{h - 2 * m}" fill="none" stroke="black"/>',
           f'<line x1="{m}" y1="{sy(1.0):.1f}" x2="{w - m}" y2="{sy(1.0):.1f}" stroke="#999" stroke-dasharray="4"/>']
    for i in range(6):
        xv, yv = x_lo + i * (x_hi - x_lo) / 5, y_lo + i * (y_hi - y_lo) / 5
        out.append(f'<text x="{sx(xv) - 12:.0f}" y="{h - m + 18}">{xv:.0f}</text>')
        out.append(f'<text x="{m - 40}" y="{sy(yv) + 4:.0f}">{yv:.2f}</text>')
    out.append(f'<text x="{w / 2 - 110}" y="{h - 15}">the class\'s own NoSort speed (MRays/s)</text>')
    out.append(f'<text x="15" y="{h / 2 + 120}" transform="rotate(-90 15 {h / 2 + 120})">speedup (filled), net (hollow)</text>')
    for x, s, n, enc, cls in points:
        col = colours[encoders.index(enc) % len(colours)]
        out.append(f'<circle cx="{sx(x):.1f}" cy="{sy(s):.1f}" r="4" fill="{col}"><title>{cls} {enc} {s:.3f}</title></circle>')
        out.append(f'<circle cx="{sx(x):.1f}" cy="{sy(n):.1f}" r="4" fill="none" stroke="{col}"/>')
    for i, enc in enumerate(encoders):
        out.append(f'<circle cx="{m + 15}" cy="{m + 15 + 18 * i}" r="4" fill="{colours[i % len(colours)]}"/>')
        out.append(f'<text x="{m + 25}" y="{m + 19 + 18 * i}">{enc}</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def table_lines(paths, source, dram_gbps, encoders=None):
    """The markdown table, one row per scene, batch and class (fastest NoSort first), and the plot's
    points [(nosort MRays/s, speedup, net, encoder, class)]; encoders: the columns (default every
    encoder of the sets)."""
    nosort, out = rows(paths, source, dram_gbps)
    encoders = encoders or sorted({r[1] for r in out})
    groups = sorted({r[0] for r in out}, key=lambda k: (k[0], k[1], -nosort.get(k, 0.0)))
    lines = ["| scene | batch | class | NoSort MRays/s | " + " | ".join(f"{e} speedup / net" for e in encoders) + " |",
             "|---|---|---|---:|" + "---|" * len(encoders)]
    points = []
    for k in groups:
        if k not in nosort:
            continue
        by_enc = {r[1]: r for r in out if r[0] == k}
        cells_text = []
        for e in encoders:
            r = by_enc.get(e)
            cells_text.append(f"{r[4]:.3f} / {r[5]:.3f}" if r else "")
            if r:
                points.append((nosort[k], r[4], r[5], e, k[2]))
        lines.append(f"| {k[0]} | {k[1]} | {k[2]} | {nosort[k]:.1f} | " + " | ".join(cells_text) + " |")
    return lines, points, encoders


def class_trend(paths, source, dram_gbps, encoder="hcc", figure="net"):
    """Over the sets' scene and batch pairs: in how many the fastest class (its own NoSort speed) has the
    encoder's lowest `figure` ("speedup" or "net"), in how many the slowest has the highest, and the pairs."""
    nosort, out = rows(paths, source, dram_gbps)
    pick = 4 if figure == "speedup" else 5
    pairs = sorted({(k[0], k[1]) for k, *_ in out})
    low = high = 0
    for sc, b in pairs:
        cls = sorted((nosort[r[0]], r[pick]) for r in out if r[0][0] == sc and r[0][1] == b and r[1] == encoder)
        low += cls[-1][1] == min(v for _, v in cls)
        high += cls[0][1] == max(v for _, v in cls)
    return low, high, len(pairs)


def profile_dram_gbps(path=os.path.join(ROOT, "gpu/profiles/rtx3060.toml")):
    with open(path, "rb") as f:
        return tomllib.load(f)["dram_gbps"]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sets", nargs="+")
    ap.add_argument("--source", choices=("model", "pocl"), required=True)
    ap.add_argument("--profile", default=os.path.join(ROOT, "gpu/profiles/rtx3060.toml"))
    ap.add_argument("--svg", help="write the plot of speedup and net against the class's NoSort speed here")
    a = ap.parse_args()
    lines, points, encoders = table_lines(a.sets, a.source, profile_dram_gbps(a.profile))
    print("\n".join(lines))
    if a.svg and points:
        svg(a.svg, points, encoders)
    return 0


if __name__ == "__main__":
    sys.exit(main())
