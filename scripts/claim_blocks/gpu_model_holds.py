"""results/gpu-model/README.md, "What holds, and what does not" (issue 20's three bars and where the
model fails): the figures it quotes, each read from the committed validations (results/gpu-model/
cells.csv and its binary/, schedules/ and shuffled/ variants, written by scripts/gpu_model_validate.py)
or the committed sets, with the readers and statistics of gpu_model_rest.py, gpu_model.py and
gpu_model_scoring.py, so that a figure quoted here and in a table above is the same computation."""
import csv
import os
import statistics

import gpu_model_validate as validate

from . import gpu_model, gpu_model_rest as rest, gpu_model_scoring as scoring, paper_tex
from .sets import (GPU_MODEL_SHUFFLED, GPU_SHUFFLED_SET, GPU_VALIDATION_BINARY, GPU_VALIDATION_WIDE, ONE_SPP,
                   PAPER_COLUMN)

# The encoders as the paper names them ("Aila_Compact" -> Aila, "HCC (Ours)" -> HCC).
PAPER_NAME = {enc: label.split(" (")[0].replace("_Compact", "") for label, enc in paper_tex.ROWS.items()}
# The validation variants whose per-cell predictions are committed, for "the best variant measured".
VARIANTS = [("the wide trails", GPU_VALIDATION_WIDE), ("the binary trails", GPU_VALIDATION_BINARY)]


def _signed(v, fmt="{:+.2f}"):
    return fmt.format(v).replace("-", "−")


def _mean_signed(folder, table, name="predicted_profile"):
    rs = rest.rows(folder, table)
    return statistics.fmean(p - t for p, t in zip(rest.column(rs, name), rest.truth(rs)))


def _cell(folder, table, scene, encoder):
    return next(r for r in rest.rows(folder, table) if r["scene"] == scene and r["encoder"] == encoder)


def spearman_phrase():
    """Issue 20's ranking bar: the wide validation's leave-one-scene-out Spearman (the Table 2 table's)."""
    return f"leave-one-scene-out Spearman is {rest.scores(GPU_VALIDATION_WIDE, '2', 'predicted_loso')[1]:.2f}"


def mae_phrase():
    return f"leave-one-scene-out MAE is {rest.scores(GPU_VALIDATION_WIDE, '2', 'predicted_loso')[2]:.3f}"


def best_variant_phrase():
    """The smallest Table 2 leave-one-scene-out MAE over the trails and schedules whose cells are committed."""
    label, folder = min(VARIANTS + rest.SCHEDULES[1:], key=lambda v: rest.scores(v[1], "2", "predicted_loso")[2])
    return f"{rest.scores(folder, '2', 'predicted_loso')[2]:.3f}, on {label}"


def other_schedules_phrase():
    """The other schedules (the static one is the binary validation itself), in gpu_model_rest's order."""
    return " and ".join(f"{rest.scores(folder, '2', 'predicted_loso')[2]:.3f} ({label.split(',')[0]})"
                        for label, folder in rest.SCHEDULES[1:])


def largest_errors_phrase(count=3):
    """The binary trails' largest leave-one-scene-out errors on Table 2, the paper's speedup in brackets."""
    rs = sorted(rest.rows(GPU_VALIDATION_BINARY, "2"),
                key=lambda r: -abs(float(r["predicted_loso"]) - float(r["paper_speedup"])))[:count]
    one_encoder = len({r["encoder"] for r in rs}) == 1
    parts = []
    for i, r in enumerate(rs):
        where = r["scene"] if one_encoder else f"{PAPER_NAME[r['encoder']]} on {r['scene']}"
        paper = f"{'the paper has ' if i == 0 else ''}{float(r['paper_speedup']):.2f}"
        parts.append(f"{_signed(float(r['predicted_loso']) - float(r['paper_speedup']))} on {where} ({paper})")
    head = f"on {PAPER_NAME[rs[0]['encoder']]}: " if one_encoder else ""
    return head + ", ".join(parts[:-1]) + " and " + parts[-1]


def _sibenik(encoder, column):
    return float(_cell(GPU_VALIDATION_BINARY, "2", "sibenik", encoder)[column])


def sibenik_lane_phrase():
    """PPC and TwoPoint on sibenik (the paper's own scene), binary trails: the lane-efficiency ratio."""
    ppc, twopoint = (f"{_sibenik(e, 'simt_lane_efficiency_ratio'):.3f}" for e in ("ppc", "twopoint"))
    return f"the same SIMT lane-efficiency ratio ({ppc})" if ppc == twopoint else \
        f"SIMT lane-efficiency ratios of {ppc} and {twopoint}"


def sibenik_distinct_phrase():
    """The distinct-nodes-per-visit ratio over NoSort's: the larger, the more nodes a warp fetches."""
    ppc, twopoint = (_sibenik(e, "simt_distinct_per_visit_ratio") for e in ("ppc", "twopoint"))
    return f"the {'worse' if ppc > twopoint else 'better'} of the two ({ppc:.2f} against {twopoint:.2f})"


def simt_mae_phrase():
    """The SIMT ratios' Table 2 MAE, raw and calibrated leave-one-scene-out (the Table 2 table's rows)."""
    rs = gpu_model._rows("2")
    truth = [float(r["paper_speedup"]) for r in rs]
    raw = [validate.mae([f(r) for r in rs], truth) for f in (gpu_model.lane, gpu_model.inv_distinct)]
    cal = [validate.mae(gpu_model._loso_calibrated(rs, f), truth) for f in (gpu_model.lane, gpu_model.inv_distinct)]
    return f"raw ({raw[0]:.3f}, {raw[1]:.3f}) and calibrated ({cal[0]:.3f}, {cal[1]:.3f})"


def simt_spearman_phrase():
    rs = gpu_model._rows("2")
    ratio = validate.spearman([gpu_model.inv_distinct(r) for r in rs], [float(r["paper_speedup"]) for r in rs])
    return f"Spearman {rest.scores(GPU_VALIDATION_WIDE, '2', 'predicted_loso')[1]:.2f} against {ratio:.2f}"


def table3_error_phrase():
    """Table 3 at Table 2's constant and refitted leave-one-scene-out: MAE and mean signed error spans."""
    names = ("predicted_profile", "predicted_loso")
    maes = [rest.scores(GPU_VALIDATION_WIDE, "3", n)[2] for n in names]
    signed = [_mean_signed(GPU_VALIDATION_WIDE, "3", n) for n in names]
    return (f"an MAE of {min(maes):.2f} to {max(maes):.2f} and a mean error of {_signed(min(signed), '{:.2f}')} "
            f"to {_signed(max(signed), '{:.2f}')}")


def table3_paper_phrase():
    """The paper's largest Table 3 speedups on Sibenik and Breakfast, and the model's (Table 2's constant)
    on those cells."""
    rs, parts, predicted = rest.rows(GPU_VALIDATION_WIDE, "3"), [], []
    for scene in ("sibenik", "breakfast_room"):
        cells = [r for r in rs if r["scene"] == scene]
        top = max(float(r["paper_speedup"]) for r in cells)
        at_top = [r for r in cells if float(r["paper_speedup"]) == top]
        parts.append(f"{top:.2f}x on {PAPER_COLUMN[scene]} ({', '.join(PAPER_NAME[r['encoder']] for r in at_top)})")
        predicted += [float(r["predicted_profile"]) for r in at_top]
    return f"up to {' and '.join(parts)}; the model predicts {min(predicted):.1f} to {max(predicted):.1f}x"


def any_hit_phrase():
    """Table 3 before d8e67d0's any-hit change (the committed 1-spp set, replayed at the profile's
    constant) against after it (cells.csv), both scored against cells.csv's paper speedups."""
    prof, after = scoring.profile(), {(r["scene"], r["encoder"]): r for r in rest.rows(GPU_VALIDATION_WIDE, "3")}
    rows = scoring.scored("3", PAPER_COLUMN, scoring.model_cells(ONE_SPP))
    before = validate.predict(rows, prof, prof["step_cycles"])
    now = [float(after[(r["scene"], r["encoder"])]["predicted_profile"]) for r in rows]
    truth = [float(after[(r["scene"], r["encoder"])]["paper_speedup"]) for r in rows]
    changed = sum(round(b, 4) != n for b, n in zip(before, now))
    stats = [("Pearson", validate.pearson, "{:.2f}"), ("Spearman", validate.spearman, "{:.2f}"), ("MAE", validate.mae, "{:.3f}")]
    moved = [name for name, f, fmt in stats if fmt.format(f(before, truth)) != fmt.format(f(now, truth))]
    verdict = ("Pearson, Spearman and MAE unchanged at the precision above" if not moved
               else f"{', '.join(moved)} changed at the precision above")
    return (f"by at most {max(abs(b - n) for b, n in zip(before, now)):.3f} ({changed} of {len(rows)} cells changed "
            f"in the fourth decimal; {verdict})")


def shuffled_phrase():
    """The model against the shuffled baseline (Table 2's constant) beside the pixel baseline's signed error."""
    shuffled = {t: rest.scores(GPU_MODEL_SHUFFLED, t, "predicted_profile") for t in ("3", "2")}
    signed = {t: _mean_signed(GPU_MODEL_SHUFFLED, t) for t in ("3", "2")}
    pixel = [_mean_signed(GPU_VALIDATION_WIDE, t) for t in ("3", "2")]
    return (f"mean signed error {_signed(signed['3'])} on Table 3 and {_signed(signed['2'])} on Table 2 (MAE "
            f"{shuffled['3'][2]:.3f} and {shuffled['2'][2]:.3f}, Spearman {shuffled['3'][1]:.2f} and "
            f"{shuffled['2'][1]:.2f}), against {_signed(pixel[0], '{:.2f}')} and {_signed(pixel[1], '{:.2f}')} "
            "with the pixel order")


def shuffled_origin_phrase():
    rs = [r for t in ("2", "3") for r in rest.rows(GPU_MODEL_SHUFFLED, t) if r["encoder"] == "origin"]
    p, t = rest.column(rs, "predicted_profile"), rest.truth(rs)
    return f"{min(p):.2f}–{max(p):.2f} against the paper's {min(t):.2f}–{max(t):.2f}"


def shuffled_cells_phrase():
    """The shuffled-baseline run's cell count (its committed cells.csv, one row a cell)."""
    with open(os.path.join(GPU_SHUFFLED_SET, "cells.csv"), newline="") as f:
        return f"{sum(1 for _ in csv.DictReader(f))} cells"


def _against(scene, encoder):
    r = _cell(GPU_VALIDATION_WIDE, "2", scene, encoder)
    return f"{float(r['predicted_loso']):.2f} against {float(r['paper_speedup']):.2f}"


def ppc_under_phrase():
    """PPC on the Living-room and Sibenik stand-ins (wide, leave-one-scene-out), the paper's after."""
    return f"{_against('grey_white_room', 'ppc')}, and {_against('sibenik', 'ppc')}"


def multi_instance_over_phrase():
    return f"{_against('multi-instance-real', 'ppc')}, and {_against('multi-instance-real', 'aila')}"
