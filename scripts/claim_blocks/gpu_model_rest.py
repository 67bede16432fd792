"""results/gpu-model/README.md from "The same on the binary BVH" to "Cost": the validation on the binary
trails, at 8 spp and under the other schedules, recomputed from each variant's committed per-cell
predictions (<folder>/cells.csv, written by scripts/gpu_model_validate.py) and the step_cycles its
report (<folder>/validation.md) lists per held-out scene."""
import csv
import os
import re
import statistics

from gpu_model_validate import mae, pearson, spearman

from . import gpu_model_scoring as scoring
from .gpu_model import _loso_calibrated, inv_distinct
from .sets import (GPU_SCHEDULE_DYNAMIC, GPU_SCHEDULE_REFILL, GPU_VALIDATION_8SPP, GPU_VALIDATION_BINARY,
                   GPU_VALIDATION_WIDE, ONE_SPP, PAPER_COLUMN)

import gpu_model_validate as validate  # noqa: E402


def rows(folder, table):
    with open(os.path.join(folder, "cells.csv"), newline="") as f:
        return [r for r in csv.DictReader(f) if r["table"] == table]


def truth(rs):
    return [float(r["paper_speedup"]) for r in rs]


def column(rs, name):
    return [float(r[name]) for r in rs]


def scores(folder, table, name):
    """Pearson, Spearman, MAE of one prediction column against the paper."""
    rs = rows(folder, table)
    p, t = column(rs, name), truth(rs)
    return pearson(p, t), spearman(p, t), mae(p, t)


def loso_steps(folder, table):
    """The step_cycles the leave-one-scene-out fit chose per held-out scene (validation.md lists them)."""
    with open(os.path.join(folder, "validation.md")) as f:
        lines = [l for l in f if l.startswith("Leave-one-scene-out step_cycles per held-out scene:")]
    line = lines[{"2": 0, "3": 1}[table]]
    return [float(v) for v in re.findall(r" ([\d.]+)(?:,|$)", line.strip())]


def steps_span(folder, table, fmt="{:.1f}"):
    k = loso_steps(folder, table)
    return f"{fmt.format(min(k))}–{fmt.format(max(k))}"


def _cells(s, bold_mae=False):
    p, sp, m = s
    return f"{p:.2f} | {sp:.2f} | " + (f"**{m:.3f}**" if bold_mae else f"{m:.3f}")


def binary_block():
    binary = scores(GPU_VALIDATION_BINARY, "2", "predicted_loso")
    wide = scores(GPU_VALIDATION_WIDE, "2", "predicted_loso")
    rs = rows(GPU_VALIDATION_BINARY, "2")
    cal = _loso_calibrated(rs, inv_distinct)
    cal_s = (pearson(cal, truth(rs)), spearman(cal, truth(rs)), mae(cal, truth(rs)))
    best = min(binary[2], wide[2], cal_s[2])
    return "\n".join([
        "| Table 2 (bounce1, 40 cells) | Pearson | Spearman | MAE |", "|---|---:|---:|---:|",
        f"| GPU model, binary trails, leave-one-scene-out (step_cycles refitted: {steps_span(GPU_VALIDATION_BINARY, '2')}) | "
        f"{_cells(binary, binary[2] == best)} |",
        f"| GPU model, wide trails, leave-one-scene-out (above) | {_cells(wide, wide[2] == best)} |",
        f"| SIMT 1 / distinct-nodes ratio, binary, leave-one-scene-out calibration | {_cells(cal_s, cal_s[2] == best)} |"])


def per_scene(folder, table="2", name="predicted_loso"):
    rs = rows(folder, table)
    return ", ".join(f"{s} {mae(column([r for r in rs if r['scene'] == s], name), truth([r for r in rs if r['scene'] == s])):.3f}"
                     for s in sorted({r["scene"] for r in rs}))


def binary_scenes_phrase():
    return per_scene(GPU_VALIDATION_BINARY)


def binary_spearman_phrase():
    return f"Spearman {scores(GPU_VALIDATION_BINARY, '2', 'predicted_loso')[1]:.2f}"


def binary_other_tables_phrase():
    t3 = scores(GPU_VALIDATION_BINARY, "3", "predicted_loso")
    return (f"Table 3 is unchanged in substance (MAE {t3[2]:.3f}, Spearman {t3[1]:.2f}), Table 6 gets MAE "
            f"{scores(GPU_VALIDATION_BINARY, '6', 'predicted_profile')[2]:.3f} "
            f"({scores(GPU_VALIDATION_WIDE, '6', 'predicted_profile')[2]:.3f} wide)")


def living_room_phrase():
    """The Living-room stand-in: the model's (wide, leave-one-scene-out) range against the paper's."""
    rs = [r for r in rows(GPU_VALIDATION_WIDE, "2") if r["scene"] == "grey_white_room"]
    p, t = column(rs, "predicted_loso"), truth(rs)
    under = all(a < b for a, b in zip(p, t))
    return (("under-predicts for every encoder" if under else "under-predicts for most encoders") +
            f" ({min(p):.2f}–{max(p):.2f} against {min(t):.2f}–{max(t):.2f})")


def eight_spp_block():
    f = GPU_VALIDATION_8SPP
    return "\n".join([
        "| | Pearson | Spearman | MAE |", "|---|---:|---:|---:|",
        f"| Table 2, profile constant | {_cells(scores(f, '2', 'predicted_profile'))} |",
        f"| Table 2, leave-one-scene-out (step_cycles refitted: {steps_span(f, '2', '{:.2g}')}) | "
        f"{_cells(scores(f, '2', 'predicted_loso'))} |",
        f"| Table 3, profile constant | {_cells(scores(f, '3', 'predicted_profile'))} |",
        f"| Table 3, leave-one-scene-out | {_cells(scores(f, '3', 'predicted_loso'))} |",
        f"| Table 6, profile constant | {_cells(scores(f, '6', 'predicted_profile'))} |"])


def one_spp_companion_phrase():
    """The committed 1-spp set replayed at the profile's constant and leave-one-scene-out, Table 2."""
    prof = scoring.profile()
    t2 = scoring.scored("2", PAPER_COLUMN, scoring.model_cells(ONE_SPP))
    loso, _ = validate.loso(t2, prof)
    t = [r["paper"] for r in t2]
    return (f"Table 2 profile-constant MAE {mae(validate.predict(t2, prof, prof['step_cycles']), t):.3f}, "
            f"leave-one-scene-out {mae(loso['model'], t):.3f}")


def eight_spp_refit_phrase():
    return f"the refit swings from {steps_span(GPU_VALIDATION_8SPP, '2', '{:.2g}').replace('–', ' to ')} cycles per step"


def eight_spp_over_phrase():
    """Scenes where the 8-spp model (profile constant) over-predicts Table 2 on average."""
    rs = rows(GPU_VALIDATION_8SPP, "2")
    scenes = sorted({r["scene"] for r in rs})
    over = sum(statistics.fmean(float(r["predicted_profile"]) - float(r["paper_speedup"]) for r in rs if r["scene"] == s) > 0
               for s in scenes)
    words = {1: "one", 2: "two", 3: "three", 4: "four", 5: "five"}
    return f"on {words.get(over, over)} of {words.get(len(scenes), len(scenes))} scenes"


def eight_spp_shadow_phrase():
    return (f"Spearman {scores(GPU_VALIDATION_8SPP, '3', 'predicted_profile')[1]:.2f} against "
            f"{scores(GPU_VALIDATION_WIDE, '3', 'predicted_profile')[1]:.2f}")


SCHEDULES = [("static warps in waves (the default; [binary/](binary/validation.md))", GPU_VALIDATION_BINARY),
             ("warp refill, threshold 1", GPU_SCHEDULE_REFILL),
             ("dynamic fetch, threshold 20", GPU_SCHEDULE_DYNAMIC)]


def schedules_block():
    out = ["| schedule (binary trails) | Table 2, leave-one-scene-out: Pearson · Spearman · MAE | Table 3, "
           "leave-one-scene-out | Table 6, profile constant: MAE |", "|---|---:|---:|---:|"]
    best = min(scores(f, "2", "predicted_loso")[2] for _, f in SCHEDULES)
    for label, f in SCHEDULES:
        p, s, m = scores(f, "2", "predicted_loso")
        p3, s3, m3 = scores(f, "3", "predicted_loso")
        mtext = f"**{m:.3f}**" if m == best else f"{m:.3f}"
        out.append(f"| {label} | {p:.2f} · {s:.2f} · {mtext} | {p3:.2f} · {s3:.2f} · {m3:.3f} | "
                   f"{scores(f, '6', 'predicted_profile')[2]:.3f} |")
    return "\n".join(out)


def refill_phrase():
    moved = abs(scores(GPU_SCHEDULE_REFILL, "2", "predicted_loso")[2] - scores(GPU_VALIDATION_BINARY, "2", "predicted_loso")[2])
    return (f"moves Table 2's leave-one-scene-out MAE by {moved:.3f}, and the refitted step_cycles stay within "
            f"{steps_span(GPU_SCHEDULE_REFILL, '2')}")


def _profile_prediction(folder, scene, encoder):
    return next(float(r["predicted_profile"]) for r in rows(folder, "2") if r["scene"] == scene and r["encoder"] == encoder)


def dynamic_hcc_phrase():
    paper = next(float(r["paper_speedup"]) for r in rows(GPU_SCHEDULE_DYNAMIC, "2")
                 if r["scene"] == "breakfast_room" and r["encoder"] == "hcc")
    return (f"predicts {_profile_prediction(GPU_SCHEDULE_DYNAMIC, 'breakfast_room', 'hcc'):.2f} for HCC on Breakfast, "
            f"where the paper measured {paper:.2f} (static warps: "
            f"{_profile_prediction(GPU_VALIDATION_BINARY, 'breakfast_room', 'hcc'):.2f})")


def dynamic_landscape_phrase():
    rs = [r for r in rows(GPU_SCHEDULE_DYNAMIC, "2") if r["scene"] == "landscape"]
    slower = [float(r["predicted_profile"]) for r in rs if float(r["predicted_profile"]) < 1]
    best = max(rs, key=lambda r: float(r["predicted_profile"]))["encoder"]
    return (f"{len(slower)} of {len(rs)} sorted orders come out slower than NoSort ({min(slower):.2f}–{max(slower):.2f}), "
            f"and {best.capitalize()} comes out best")


def dynamic_refit_phrase():
    return f"swing from {steps_span(GPU_SCHEDULE_DYNAMIC, '2', '{:.0f}').replace('–', ' to ')}"


def in_sample_fit(folder, table="2"):
    """The step_cycles fitted on all of a table's cells, as validation.md prints it."""
    with open(os.path.join(folder, "validation.md")) as f:
        text = f.read()
    section = text.split(f"### Table {table}:")[1]
    return float(re.search(r"step_cycles fitted on all cells \(([\d.]+); in-sample\)", section).group(1))


def occupancy_phrase():
    """The committed occupancy (the profile's resident warps) on the binary trails: its fit and scores;
    validation.md prints the in-sample row, cells.csv holds the leave-one-scene-out predictions."""
    with open(os.path.join(GPU_VALIDATION_BINARY, "validation.md")) as f:
        section = f.read().split("### Table 2:")[1]
    k, in_mae = re.search(r"step_cycles fitted on all cells \(([\d.]+); in-sample\) \| [\d.]+ \| [\d.]+ \| ([\d.]+) \|",
                          section).groups()
    p, s, m = scores(GPU_VALIDATION_BINARY, "2", "predicted_loso")
    return (f"at the profiles' {scoring.profile()['resident_warps_per_sm']} warps the binary validation fits step_cycles = "
            f"{float(k):.1f} on all 40 cells (in-sample MAE {in_mae}) and scores {p:.2f} · {s:.2f} · {m:.3f} "
            f"(Pearson · Spearman · MAE) leave-one-scene-out")


def time_formula_block():
    """The model's own formula (issue + memory) on both layouts: the one row whose runs are committed."""
    w, b = scores(GPU_VALIDATION_WIDE, "2", "predicted_loso"), scores(GPU_VALIDATION_BINARY, "2", "predicted_loso")
    t3 = [scores(f, "3", "predicted_loso")[2] for f in (GPU_VALIDATION_WIDE, GPU_VALIDATION_BINARY)]
    return "\n".join([
        "| time = | wide: Table 2 LOSO Pearson · Spearman · MAE | binary: Table 2 LOSO | Table 3 LOSO MAE (wide, binary) |",
        "|---|---:|---:|---:|",
        f"| issue + memory (the model) | {w[0]:.2f} · {w[1]:.2f} · {w[2]:.3f} | {b[0]:.2f} · {b[1]:.2f} · {b[2]:.3f} | "
        f"{t3[0]:.3f}, {t3[1]:.3f} |"])
