#!/usr/bin/env python3
"""Validates the GPU cost model (docs/gpu-model.md) against the paper's RTX 3060 speedups.

  scripts/gpu_model_validate.py RESULT_SET [RESULT_SET...] --out DIR [--profile gpu/profiles/rtx3060.toml]
                                [--access gather|permute] [--baseline pixel|shuffled] [--measured SET]

Reads cells.csv of result sets run with `raysort run --gpu-model rtx3060`, pairs every cell with
its row in results/gpu-model/paper_tables.csv (Tables 2, 3 and 6) and with the NoSort cell of its
batch, and writes DIR/validation.md, DIR/cells.csv and DIR/scatter.svg. The model's one fitted
constant (step_cycles: SM cycles per issued warp step) is refitted here from the counts, on all
cells and leave-one-scene-out (fit on four scenes, predict the fifth), by minimising the mean
absolute error over a log grid. Baselines: the two SIMT ratios, raw and with a leave-one-scene-out
linear calibration (a + b x), and the PoCL gather speedup. With --measured SET (a result set
measured on a GPU, e.g. by scripts/device-check.sh), that set's 32-bit bounce1 and shadow0 speedups
take the place of the paper's Tables 2 and 3: predicted against measured, with step_cycles fitted
to that GPU the same way. Standard library only.
"""
import argparse
import csv
import math
import os
import statistics
import sys
import tomllib

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
COMBINE = "sum"  # bench/gpu_model.cpp's issue + memory; --combine shows the alternatives tried
# The cells' ray access mode (--access): gather loads rays[order[i]], permute consecutive rays. NoSort
# has one cell per batch (its order is the identity: both modes load consecutive rays), kept for both.
ACCESS = "gather"
# NoSort's order, the baseline of every ratio (--baseline): pixel (generation order) or shuffled.
BASELINE = "pixel"
TRUTH = "paper speedup (RTX 3060)"  # what the predictions are checked against (--measured: a GPU's set)
GRID = [round(2 ** (i / 8), 4) for i in range(0, 8 * 11)]  # 1 .. ~1900 cycles per step


def read_cells(dirs):
    """The ok cells of the result sets' cells.csv in the --access mode (and NoSort's) and --baseline order."""
    rows = []
    for d in dirs:
        with open(os.path.join(d, "cells.csv"), newline="") as f:
            rows += [r for r in csv.DictReader(f) if r["status"] == "ok" and (r["access"] == ACCESS or r["encoder"] == "nosort")
                     and r["baseline"] == BASELINE]
    return rows


def load_cells(dirs):
    return [r for r in read_cells(dirs) if r["gpu_model"]]


# Load-to-use latencies for --combine sum+latency, in SM cycles at the RTX 3060's 1.78 GHz: an L2 hit
# about 113 ns and a DRAM access about 270 ns on Ampere (Chips and Cheese, "Measuring GPU Memory
# Latency", 2021, pointer chasing on an RTX 3090: L1 to L2 over 100 ns, VRAM about 270 ns).
L2_LATENCY_CYCLES, DRAM_LATENCY_CYCLES = 200.0, 480.0


def model_time(r, p, k):
    """The predicted time of bench/gpu_model.cpp, gpu_model_time(), with step_cycles = k; --combine
    picks it (sum) or an alternative that was tried against it (results/gpu-model/README.md)."""
    scale = float(r["gpu_warps"]) / float(r["gpu_replayed_warps"])  # a sampled replay stands for all warps
    cycles = p["sms"] * p["clock_ghz"] * 1e9
    # ww: the issued steps of a while-while kernel (GpuCounts::ww_steps) in place of lockstep's
    issue = float(r["gpu_ww_steps" if COMBINE == "ww" else "gpu_warp_steps"]) * k / cycles
    l2_sectors = float(r["gpu_l2_hits"]) + float(r["gpu_l2_misses"])
    memory = float(r["gpu_dram_bytes"]) / (p["dram_gbps"] * 1e9) + l2_sectors * p["sector_bytes"] / (p["l2_gbps"] * 1e9)
    if COMBINE == "max":
        return scale * max(issue, memory)
    if COMBINE == "sum+l1":  # plus the L1's throughput: one line request per SM cycle
        return scale * (issue + memory + (float(r["gpu_l1_hits"]) + float(r["gpu_l1_misses"])) / cycles)
    if COMBINE == "sum+latency":  # plus each step's wait for its slowest read, hidden by the resident warps
        stalls = float(r["gpu_steps_l2"]) * L2_LATENCY_CYCLES + float(r["gpu_steps_dram"]) * DRAM_LATENCY_CYCLES
        return scale * (issue + memory + stalls / cycles / p["resident_warps_per_sm"])
    return scale * (issue + memory)


def pearson(x, y):
    mx, my = statistics.fmean(x), statistics.fmean(y)
    sxy = sum((a - mx) * (b - my) for a, b in zip(x, y))
    sxx = math.sqrt(sum((a - mx) ** 2 for a in x))
    syy = math.sqrt(sum((b - my) ** 2 for b in y))
    return sxy / (sxx * syy) if sxx and syy else float("nan")


def ranks(v):
    order = sorted(range(len(v)), key=lambda i: v[i])
    r = [0.0] * len(v)
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and v[order[j + 1]] == v[order[i]]:
            j += 1
        for k in range(i, j + 1):
            r[order[k]] = (i + j) / 2 + 1
        i = j + 1
    return r


def spearman(x, y):
    return pearson(ranks(x), ranks(y))


def mae(x, y):
    return statistics.fmean(abs(a - b) for a, b in zip(x, y))


def linfit(x, y):
    mx, my = statistics.fmean(x), statistics.fmean(y)
    sxx = sum((a - mx) ** 2 for a in x)
    b = sum((a - mx) * (c - my) for a, c in zip(x, y)) / sxx if sxx else 0.0
    return my - b * mx, b


def pair(paper, cells):
    """Paper rows joined with their cell and the NoSort cell of the same batch."""
    by_key = {(c["scene"], c["batch"], c["encoder"], c["bits"]): c for c in cells}
    nosort = {(c["scene"], c["batch"]): c for c in cells if c["encoder"] == "nosort"}
    out = []
    for p in paper:
        c = by_key.get((p["scene"], p["batch"], p["encoder"], p["bits"]))
        n = nosort.get((p["scene"], p["batch"]))
        if c and n:
            out.append({**p, "cell": c, "nosort": n, "paper": float(p["paper_speedup"])})
    return out


def measured_rows(dirs):
    """A GPU-measured result set as rows of the paper's table format: 32-bit bounce1 cells as Table 2,
    shadow0 as Table 3, the measured trace speedup as the truth."""
    tables = {"bounce1": "2", "shadow0": "3"}
    return [{"table": tables[r["batch"]], "batch": r["batch"], "scene": r["scene"], "encoder": r["encoder"],
             "bits": r["bits"], "paper_speedup": r["speedup"]}
            for r in read_cells(dirs)
            if r["batch"] in tables and r["bits"] == "32" and r["encoder"] != "nosort" and r["speedup"]]


def predict(rows, prof, k):
    return [model_time(r["nosort"], prof, k) / model_time(r["cell"], prof, k) for r in rows]


def fit_k(rows, prof):
    return min(GRID, key=lambda k: mae(predict(rows, prof, k), [r["paper"] for r in rows]))


def loso(rows, prof):
    """Leave-one-scene-out: the model's k and the baselines' linear calibrations."""
    scenes = sorted({r["scene"] for r in rows})
    pred = {name: [None] * len(rows) for name in ("model", "lane_cal", "dist_cal")}
    ks = {}
    for s in scenes:
        train = [r for r in rows if r["scene"] != s]
        test = [i for i, r in enumerate(rows) if r["scene"] == s]
        k = fit_k(train, prof)
        ks[s] = k
        for i in test:
            pred["model"][i] = predict([rows[i]], prof, k)[0]
        for name, fn in (("lane_cal", lane_ratio), ("dist_cal", inv_distinct)):
            a, b = linfit([fn(r) for r in train], [r["paper"] for r in train])
            for i in test:
                pred[name][i] = a + b * fn(rows[i])
    return pred, ks


def lane_ratio(r):
    return float(r["cell"]["simt_lane_efficiency_ratio"])


def inv_distinct(r):
    return 1.0 / float(r["cell"]["simt_distinct_per_visit_ratio"])


def pocl(r):
    return float(r["cell"]["speedup"])


def stats_row(name, pred, truth):
    return f"| {name} | {pearson(pred, truth):.2f} | {spearman(pred, truth):.2f} | {mae(pred, truth):.3f} |"


def table_report(title, rows, prof):
    truth = [r["paper"] for r in rows]
    k_all = fit_k(rows, prof)
    loso_pred, ks = loso(rows, prof)
    lines = [f"### {title} ({len(rows)} cells)", "",
             "| predictor | Pearson | Spearman | MAE (speedup) |", "|---|---:|---:|---:|",
             stats_row(f"GPU model, profile constant (step_cycles = {prof['step_cycles']:g})",
                       predict(rows, prof, prof["step_cycles"]), truth),
             stats_row(f"GPU model, step_cycles fitted on all cells ({k_all:g}; in-sample)",
                       predict(rows, prof, k_all), truth),
             stats_row("**GPU model, leave-one-scene-out fit**", loso_pred["model"], truth),
             stats_row("SIMT lane-efficiency ratio, raw", [lane_ratio(r) for r in rows], truth),
             stats_row("SIMT 1 / distinct-nodes ratio, raw", [inv_distinct(r) for r in rows], truth),
             stats_row("SIMT lane-efficiency ratio, leave-one-scene-out linear calibration", loso_pred["lane_cal"], truth),
             stats_row("SIMT 1 / distinct-nodes ratio, leave-one-scene-out linear calibration", loso_pred["dist_cal"], truth),
             stats_row(f"PoCL {ACCESS} speedup (this machine's CPU)", [pocl(r) for r in rows], truth),
             "", "Leave-one-scene-out, per held-out scene: MAE " + ", ".join(
                 f"{s} {mae([q for q, r in zip(loso_pred['model'], rows) if r['scene'] == s], [r['paper'] for r in rows if r['scene'] == s]):.3f}"
                 for s in sorted(ks)),
             "", "Leave-one-scene-out step_cycles per held-out scene: " +
             ", ".join(f"{s} {k:g}" for s, k in ks.items()), ""]
    return lines, loso_pred["model"], k_all


def svg_scatter(path, series):
    """series: [(label, colour, [(truth, predicted)])]: predicted vs paper (or measured) speedup, y = x dashed."""
    w, h, m = 520, 520, 60
    lo, hi = 0.6, 2.4
    sx = lambda v: m + (v - lo) / (hi - lo) * (w - 2 * m)
    sy = lambda v: h - m - (v - lo) / (hi - lo) * (h - 2 * m)
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12">',
           f'<rect width="{w}" height="{h}" fill="white"/>',
           f'<line x1="{sx(lo)}" y1="{sy(lo)}" x2="{sx(hi)}" y2="{sy(hi)}" stroke="#999" stroke-dasharray="4"/>']
    for t in [0.6 + 0.2 * i for i in range(10)]:
        out.append(f'<text x="{sx(t) - 10:.0f}" y="{h - m + 18}">{t:.1f}</text>')
        out.append(f'<text x="{m - 35}" y="{sy(t) + 4:.0f}">{t:.1f}</text>')
    out.append(f'<rect x="{m}" y="{m}" width="{w - 2 * m}" height="{h - 2 * m}" fill="none" stroke="black"/>')
    out.append(f'<text x="{w / 2 - 60}" y="{h - 20}">{TRUTH}</text>')
    out.append(f'<text x="15" y="{h / 2 + 60}" transform="rotate(-90 15 {h / 2 + 60})">predicted speedup (LOSO)</text>')
    for i, (label, colour, pts) in enumerate(series):
        for p, q in pts:
            out.append(f'<circle cx="{sx(min(max(p, lo), hi)):.1f}" cy="{sy(min(max(q, lo), hi)):.1f}" r="4" '
                       f'fill="{colour}" fill-opacity="0.7"/>')
        out.append(f'<circle cx="{m + 15}" cy="{m + 15 + 18 * i}" r="4" fill="{colour}"/>')
        out.append(f'<text x="{m + 25}" y="{m + 19 + 18 * i}">{label}</text>')
    out.append("</svg>")
    with open(path, "w") as f:
        f.write("\n".join(out) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("sets", nargs="+")
    ap.add_argument("--out", required=True)
    ap.add_argument("--profile", default=os.path.join(ROOT, "gpu/profiles/rtx3060.toml"))
    ap.add_argument("--paper", default=os.path.join(ROOT, "results/gpu-model/paper_tables.csv"))
    ap.add_argument("--combine", choices=("sum", "max", "sum+l1", "sum+latency", "ww"), default="sum",
                    help="issue and memory time: sum (the model's, default); alternatives tried against it: max (a "
                         "roofline), sum+l1 (plus L1 requests at one per cycle), sum+latency (plus L2/DRAM stalls; "
                         "needs the gpu_steps_l2/gpu_steps_dram columns), ww (the sum with a while-while kernel's issued steps, "
                         "gpu_ww_steps, in place of lockstep's)")
    ap.add_argument("--access", choices=("gather", "permute"), default="gather",
                    help="which access mode's cells to read (the 8-spp paper sets ran both; earlier ones one)")
    ap.add_argument("--baseline", choices=("pixel", "shuffled"), default="pixel",
                    help="which baseline order's cells to read (run --baseline): the paper does not say its NoSort order")
    ap.add_argument("--measured", nargs="+", metavar="SET",
                    help="check against the speedups of result sets measured on a GPU instead of the paper's tables")
    a = ap.parse_args()
    global COMBINE, ACCESS, BASELINE, TRUTH
    COMBINE = a.combine
    ACCESS = a.access
    BASELINE = a.baseline
    with open(a.profile, "rb") as f:
        prof = tomllib.load(f)
    if a.measured:
        paper = measured_rows(a.measured)
        TRUTH = f"measured speedup ({', '.join(os.path.basename(os.path.normpath(d)) for d in a.measured)})"
    else:
        with open(a.paper, newline="") as f:
            paper = list(csv.DictReader(f))
    cells = load_cells(a.sets)
    for c in cells:  # cells.csv has the replayed warps; the total is the ray count in warps of 32
        c["gpu_warps"] = str((int(c["rays"]) + 31) // 32)
    os.makedirs(a.out, exist_ok=True)
    report = [f"# GPU model ({prof['name']}) against the {TRUTH} (generated by scripts/gpu_model_validate.py)", ""]
    series, per_cell = [], []
    for table, title, colour in (("2", "Table 2: secondary rays (bounce1), 32-bit keys", "#1f77b4"),
                                 ("3", "Table 3: primary shadow rays (shadow0), 32-bit keys", "#d62728"),
                                 ("6", "Table 6: key lengths 16/32/64 on sibenik, bounce1", "#2ca02c")):
        rows = pair([p for p in paper if p["table"] == table], cells)
        if len(rows) < 3:
            report += [f"### {title}", "", f"{len(rows)} cells paired: not enough to report.", ""]
            continue
        if len({r["scene"] for r in rows}) > 1:
            lines, pred, k_all = table_report(title, rows, prof)
        else:  # one scene: no leave-one-scene-out; the profile's constant predicts
            pred = predict(rows, prof, prof["step_cycles"])
            truth = [r["paper"] for r in rows]
            lines = [f"### {title} ({len(rows)} cells, one scene: the profile's constant, no fit)", "",
                     "| predictor | Pearson | Spearman | MAE (speedup) |", "|---|---:|---:|---:|",
                     stats_row("GPU model (profile constant)", pred, truth),
                     stats_row("SIMT lane-efficiency ratio, raw", [lane_ratio(r) for r in rows], truth),
                     stats_row("SIMT 1 / distinct-nodes ratio, raw", [inv_distinct(r) for r in rows], truth), ""]
        report += lines
        series.append((f"Table {table}", colour, [(r["paper"], q) for r, q in zip(rows, pred)]))
        for r, q in zip(rows, pred):
            per_cell.append([table, r["scene"], r["encoder"], r["bits"], r["paper"], round(q, 4),
                             round(predict([r], prof, prof["step_cycles"])[0], 4), r["cell"]["simt_lane_efficiency_ratio"],
                             r["cell"]["simt_distinct_per_visit_ratio"], r["cell"]["speedup"]])
    with open(os.path.join(a.out, "cells.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["table", "scene", "encoder", "bits", "paper_speedup", "predicted_loso", "predicted_profile",
                    "simt_lane_efficiency_ratio", "simt_distinct_per_visit_ratio", f"pocl_{ACCESS}_speedup"])
        w.writerows(per_cell)
    svg_scatter(os.path.join(a.out, "scatter.svg"), series)
    with open(os.path.join(a.out, "validation.md"), "w") as f:
        f.write("\n".join(report) + "\n")
    print("\n".join(report))


if __name__ == "__main__":
    sys.exit(main())
