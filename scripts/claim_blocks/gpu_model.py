"""results/gpu-model/README.md: the GPU model and the SIMT baselines against the paper's Tables 2, 3
and 6, recomputed from the committed per-cell predictions (results/gpu-model/cells.csv, written by
scripts/gpu_model_validate.py from the two runs the README names) with that script's statistics."""
import csv
import os

from gpu_model_validate import linfit, mae, pearson, spearman

from .sets import ROOT

CELLS = os.path.join(ROOT, "results", "gpu-model", "cells.csv")


def _rows(table):
    with open(CELLS, newline="") as f:
        return [r for r in csv.DictReader(f) if r["table"] == table]


def _num(v, fmt):
    return fmt.format(v).replace("-", "−")


def _row(label, pred, truth, bold=False):
    cells = [_num(pearson(pred, truth), "{:.2f}"), _num(spearman(pred, truth), "{:.2f}"), _num(mae(pred, truth), "{:.3f}")]
    if bold:
        label, cells = f"**{label}**", [f"**{c}**" for c in cells]
    return f"| {label} | " + " | ".join(cells) + " |"


def _loso_calibrated(rows, x):
    """Leave-one-scene-out linear calibration a + b·x of a SIMT ratio (gpu_model_validate.loso's)."""
    out = [None] * len(rows)
    for s in {r["scene"] for r in rows}:
        train = [r for r in rows if r["scene"] != s]
        a, b = linfit([x(r) for r in train], [float(r["paper_speedup"]) for r in train])
        for i, r in enumerate(rows):
            if r["scene"] == s:
                out[i] = a + b * x(r)
    return out


lane = lambda r: float(r["simt_lane_efficiency_ratio"])  # noqa: E731
inv_distinct = lambda r: 1.0 / float(r["simt_distinct_per_visit_ratio"])  # noqa: E731


def _table(table, profile_label, loso_label, bold_profile):
    rows = _rows(table)
    truth = [float(r["paper_speedup"]) for r in rows]
    col = lambda name: [float(r[name]) for r in rows]  # noqa: E731
    out = ["| predictor | Pearson | Spearman | MAE (speedup) |", "|---|---:|---:|---:|",
           _row(profile_label, col("predicted_profile"), truth, bold_profile)]
    if loso_label:
        out.append(_row(loso_label, col("predicted_loso"), truth, not bold_profile))
    out += [_row("SIMT lane-efficiency ratio, raw", [lane(r) for r in rows], truth),
            _row("SIMT 1 / distinct-nodes ratio, raw", [inv_distinct(r) for r in rows], truth)]
    if loso_label:
        out += [_row("SIMT lane-efficiency ratio, leave-one-scene-out linear calibration" +
                     (" (a + b·x)" if table == "2" else ""), _loso_calibrated(rows, lane), truth),
                _row("SIMT 1 / distinct-nodes ratio, leave-one-scene-out linear calibration",
                     _loso_calibrated(rows, inv_distinct), truth),
                _row("PoCL gather speedup (this machine's CPU; one round, beside another run)",
                     col("pocl_gather_speedup"), truth)]
    return "\n".join(out)


def table2_block():
    return _table("2", "GPU model, profile constant (step_cycles = 32, fitted on these 40 cells: in-sample)",
                  "GPU model, leave-one-scene-out (step_cycles fitted on 4 scenes, 5th predicted)", False)


def table3_block():
    return _table("3", "GPU model, Table 2's constant (no fit on Table 3)",
                  "GPU model, leave-one-scene-out fit on Table 3 (the fit runs to the grid's top: issue only)", True)


def table6_block():
    return _table("6", "GPU model, Table 2's constant (in-sample on its four 32-bit cells, Table 2's)", None, False)


def table2_loso_per_scene_phrase():
    rows = _rows("2")
    return ", ".join(f"{s} {mae([float(r['predicted_loso']) for r in rows if r['scene'] == s], [float(r['paper_speedup']) for r in rows if r['scene'] == s]):.3f}"
                     for s in sorted({r["scene"] for r in rows}))
