"""results/README.md, "The first NVIDIA run" and "What ordering buys as the kernel gets faster": the
figures of the lent H200 (results/gpu-nvidia-h200/): every trace class's speed on the paper's sibenik
and breakfast_room batches (a `raysort trace --layout all` log), what each encoder buys each GPU
class, measured, and what the sort costs beside the trace there."""
import csv
import os
import re
import statistics

from class_speedups import class_trend, profile_dram_gbps, table_lines

from .sets import SHARED_ROUNDS, H200_CLASSES, H200_MODEL, H200_PAPER, H200_SORTBENCH, H200_TRACE_LOG, H200_VALIDATION, PAPER_SPEEDUPS, ROOT

# The GPU-class kernels first, then the CPU classes' narrowest packet and the stream, for the record.
TRACE_COLUMNS = ["wide", "wide8", "binary", "binary-ww", "cwbvh", "packet4", "stream"]
ENCODERS = ["hcc", "mlhcc", "ppc", "twopoint", "origin"]


def trace_arms(path=H200_TRACE_LOG):
    """{(scene, batch): {(class, variant): (MRays/s, speed vs wide fast)}} and the largest mismatch
    count of any arm, from `raysort trace` output."""
    arms, scene, batch, worst = {}, None, None, 0
    for line in open(path):
        m = re.match(r"scene\s+(\S+):", line)
        if m:
            scene = m.group(1)
            continue
        m = re.match(r"(primary|shadow\d|bounce\d)\s+\d+ rays", line)
        if m:
            batch = m.group(1)
            continue
        m = re.match(r"\s+(\S+) (fast|robust)\s+\d+\s+[\d.]+ \[[^]]*\]\s+([\d.]+)\s+(?:([\d.]+) \[[^]]*\]|-)\s+(\d+)$", line)
        if m and scene and batch:
            speed = float(m.group(4)) if m.group(4) else 1.0
            arms.setdefault((scene, batch), {})[(m.group(1), m.group(2))] = (float(m.group(3)), speed)
            worst = max(worst, int(m.group(5)))
    return arms, worst


def trace_classes_block():
    arms, _ = trace_arms()
    lines = ["| scene | batch | " + " | ".join(TRACE_COLUMNS) + " |", "|---|---|" + "---:|" * len(TRACE_COLUMNS)]
    for (scene, batch), a in arms.items():
        cells = [f"{a[(c, 'fast')][0]:.0f} ({a[(c, 'fast')][1]:.2f})" for c in TRACE_COLUMNS]
        lines.append(f"| {scene} | {batch} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def trace_classes_phrase():
    """The fastest class per batch, and the mismatches of every arm against its host twin."""
    arms, worst = trace_arms()
    best = {}
    for key, a in arms.items():
        cls = max((v[0], c) for (c, var), v in a.items() if var == "fast")[1]
        best[cls] = best.get(cls, 0) + 1
    n_arms = sum(len(a) for a in arms.values())
    tops = ", ".join(f"{c} in {n}" for c, n in sorted(best.items(), key=lambda kv: -kv[1]))
    return (f"the fastest class (fast variant) is {tops} of the {len(arms)} batches; {n_arms} arms, "
            f"largest mismatch count against the host twin {worst}")


def classes_block():
    return "\n".join(table_lines(H200_CLASSES, "pocl", profile_dram_gbps(), ENCODERS)[0])


def classes_trend_phrase():
    """Over the scene-batch pairs: how often HCC's speedup is lowest on the fastest class and highest on
    the slowest (each class's own NoSort speed, measured)."""
    low, high, n = class_trend(H200_CLASSES, "pocl", profile_dram_gbps(), figure="speedup")
    return (f"HCC's speedup is lowest on the fastest class in {low} of the {n} scene and batch pairs, "
            f"highest on the slowest in {high}")


def _validation_cells():
    with open(os.path.join(H200_VALIDATION, "cells.csv"), newline="") as f:
        return [r for r in csv.DictReader(f) if r["status"] == "ok"]


def overhead_phrase():
    """The sort against the NoSort trace in the validation matrix, and the net speedups it leaves."""
    cells = [r for r in _validation_cells() if r["encoder"] != "nosort"]
    ratio = [float(r["sort_ms"]) / float(r["nosort_trace_ms"]) for r in cells]
    net = [float(r["net_speedup"]) for r in cells]
    speed = [float(r["speedup"]) for r in cells]
    return (f"the sort takes {statistics.median(ratio):.2f}x the NoSort trace's time (median of {len(cells)} cells, "
            f"{min(ratio):.2f}-{max(ratio):.2f}); speedups {min(speed):.2f}-{max(speed):.2f}, "
            f"net speedups {min(net):.2f}-{max(net):.2f}")


def validation_block():
    """Measured speedup per encoder on the validation matrix (gather, 32-bit keys)."""
    cells = _validation_cells()
    encoders = ["hcc", "mlhcc", "grid", "twopoint", "aila", "reis", "origin", "ppc"]
    by = {(r["scene"], r["batch"], r["encoder"]): r for r in cells}
    lines = ["| scene | batch | NoSort MRays/s | " + " | ".join(encoders) + " |",
             "|---|---|---:|" + "---:|" * len(encoders)]
    for sc, b in sorted({(r["scene"], r["batch"]) for r in cells}):
        ns = by[(sc, b, "nosort")]
        vals = [f"{float(by[(sc, b, e)]['speedup']):.2f}" if (sc, b, e) in by else "" for e in encoders]
        lines.append(f"| {sc} | {b} | {float(ns['trace_mrays']):.0f} | " + " | ".join(vals) + " |")
    return "\n".join(lines)


def model_block():
    """The GPU model's h200 profile, as shipped (step_cycles 32, fitted on the paper's RTX 3060 Table 2,
    never on this GPU), against the speedups measured on the H200; beside it the SIMT ratio, the
    paper's own RTX 3060 speedups of the same cells, and the PoCL speedups of the model run."""
    import tomllib

    import gpu_model_validate as v

    with open(os.path.join(ROOT, "gpu", "profiles", "h200.toml"), "rb") as f:
        prof = tomllib.load(f)
    cells = v.load_cells([H200_MODEL])
    for c in cells:
        c["gpu_warps"] = str((int(c["rays"]) + 31) // 32)
    measured = v.measured_rows([H200_VALIDATION])
    with open(PAPER_SPEEDUPS, newline="") as f:
        paper = {(p["table"], p["scene"], p["encoder"], p["bits"]): float(p["paper_speedup"]) for p in csv.DictReader(f)}
    lines = ["| batch | cells | predictor | Pearson | Spearman | MAE (speedup) |", "|---|---:|---|---:|---:|---:|"]
    for table, batch in (("2", "bounce1"), ("3", "shadow0")):
        rows = v.pair([m for m in measured if m["table"] == table], cells)
        truth = [r["paper"] for r in rows]
        preds = [(f"GPU model, h200 profile as shipped (step_cycles {prof['step_cycles']}, no fit)",
                  v.predict(rows, prof, prof["step_cycles"])),
                 ("SIMT lane-efficiency ratio, raw", [v.lane_ratio(r) for r in rows]),
                 ("PoCL gather speedup (the model run, 1 rep, Xeon)", [v.pocl(r) for r in rows])]
        both = [(paper[(table, r["scene"], r["encoder"], r["bits"])], r["paper"]) for r in rows
                if (table, r["scene"], r["encoder"], r["bits"]) in paper]
        for name, pred in preds:
            lines.append(f"| {batch} | {len(rows)} | {name} | {v.pearson(pred, truth):.2f} | "
                         f"{v.spearman(pred, truth):.2f} | {v.mae(pred, truth):.3f} |")
        if len(both) >= 3:
            x, y = [b[0] for b in both], [b[1] for b in both]
            lines.append(f"| {batch} | {len(both)} | the paper's RTX 3060 speedup of the same cell (stand-in scenes) | "
                         f"{v.pearson(x, y):.2f} | {v.spearman(x, y):.2f} | {v.mae(x, y):.3f} |")
    return "\n".join(lines)


def sortbench_phrase():
    """`raysort sortbench` on the H200 (sortbench-12e32f2.md): our sort at 2 M and 16 M random 32-bit
    keys against the copy bound and Boost.Compute."""
    rows = {}
    for line in open(H200_SORTBENCH):
        cols = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cols) > 12 and cols[0].isdigit() and cols[1] == "32" and cols[2] == "random":
            rows[int(cols[0])] = cols
    small, large = rows[min(rows)], rows[max(rows)]
    return (f"{int(small[0]) / 1e6:.1f} M pairs of random 32-bit keys in {small[5]} ms, {float(small[4]):.0f} Mkeys/s, "
            f"{small[7]} of the copy bound, {float(small[14]):.1f}x Boost.Compute's speed; at "
            f"{int(large[0]) / 1e6:.1f} M pairs Boost.Compute is {1 / float(large[14]):.1f}x faster")


def validation_summary_phrase():
    """Cells, and NoSort A/A intervals containing 1, of the validation matrix."""
    cells = _validation_cells()
    aa = [r for r in cells if r["encoder"] == "nosort"]
    inside = sum(float(r["aa_lo"]) <= 1.0 <= float(r["aa_hi"]) for r in aa)
    return f"{len(cells)} cells, A/A {inside} of {len(aa)}"


def table6_block():
    """The paper's Table 6 (key lengths on Sibenik, secondary rays) measured on the H200 (the paper preset on
    sibenik and breakfast_room, gather), beside the paper's RTX 3060 speedups, and their Pearson."""
    import gpu_model_validate as v

    with open(os.path.join(H200_PAPER, "cells.csv"), newline="") as f:
        cells = {(r["encoder"], r["bits"]): r for r in csv.DictReader(f)
                 if r["status"] == "ok" and r["scene"] == "sibenik" and r["batch"] == "bounce1" and r["access"] == "gather"}
    with open(PAPER_SPEEDUPS, newline="") as f:
        paper = {(p["encoder"], p["bits"]): float(p["paper_speedup"]) for p in csv.DictReader(f) if p["table"] == "6"}
    encoders = sorted({e for e, _ in paper}, key=["hcc", "mlhcc", "twopoint", "ppc"].index)
    lines = ["| encoder | 16 bits: H200 (paper) | 32 bits | 64 bits | H200 ANC 16 / 32 / 64 |", "|---|---:|---:|---:|---:|"]
    ours, theirs = [], []
    for e in encoders:
        row = []
        for bits in ("16", "32", "64"):
            s = float(cells[(e, bits)]["speedup"])
            ours.append(s), theirs.append(paper[(e, bits)])
            row.append(f"{s:.2f} ({paper[(e, bits)]:.2f})")
        anc = " / ".join(f"{float(cells[(e, b)]['anc']):.2f}" for b in ("16", "32", "64"))
        lines.append(f"| {e} | " + " | ".join(row) + f" | {anc} |")
    lines.append(f"\nPearson of the {len(ours)} cells, H200 against the paper: {v.pearson(ours, theirs):.2f}, "
                 f"Spearman {v.spearman(ours, theirs):.2f}")
    return "\n".join(lines)


def same_orders_phrase():
    """Device independence at the paper's scale: the H200's sibenik cells of the paper preset against the same
    preset's cells on the Xeon (PoCL; the shared-rounds set of be9b74a): order hash and ANC per cell."""
    def cells(path):
        with open(os.path.join(path, "cells.csv"), newline="") as f:
            return {(r["scene"], r["batch"], r["encoder"], r["bits"], r["access"]): r for r in csv.DictReader(f)
                    if r["status"] == "ok" and r["encoder"] != "nosort"}
    gpu, cpu = cells(H200_PAPER), cells(os.path.join(SHARED_ROUNDS, "shared-be9b74a"))
    common = [k for k in gpu if k in cpu]
    same = sum(gpu[k]["order_hash"] == cpu[k]["order_hash"] and gpu[k]["anc"] == cpu[k]["anc"] for k in common)
    return f"{same} of the {len(common)} sibenik cells"
