"""results/README.md, "Table by table": the 1-spp sets of the paper's Table 4 (limited viewport),
Table 8 (HCC_DIR), the bounces figure and the two hyperparameter sweeps, read from their cells.csv."""
import csv
import os

from . import paper_tex
from .sets import BOUNCES, HCC_DIR, SWEEPS, SWEEPS_MORE, VIEWPORT

ENCODERS = ["hcc", "mlhcc", "grid", "twopoint", "aila", "reis", "origin", "ppc"]


def cells(set_dir):
    """(scene, batch, encoder, bits) -> row, for the ok permute cells and NoSort's (bits 0)."""
    with open(os.path.join(set_dir, "cells.csv"), newline="") as f:
        return {(r["scene"], r["batch"], r["encoder"], int(r["bits"])): r for r in csv.DictReader(f)
                if r["status"] == "ok" and r["baseline"] == "pixel" and (r["access"] == "permute" or r["encoder"] == "nosort")}


def _printed(table):
    return {(r["row"], r["column"]): r for r in paper_tex.printed() if r["table"] == table}


def _bold_max(values, fmt="{:.3f}"):
    best = max(values)
    return [f"**{fmt.format(v)}**" if v == best and values.count(best) == 1 else fmt.format(v) for v in values]


# Table 4's stand-ins: scene -> the paper's column (None: no paper column)
VIEWPORT_SCENES = [("breakfast_room_limited", "Breakfast"), ("grey_white_room_limited", "Living room"),
                   ("sibenik_limited", "Sibenik"), ("japanese_classroom_limited", None),
                   ("wooden_staircase_limited", None)]


def viewport_block():
    """SIMT lane-efficiency ratio per encoder and scene, best per column in bold, paper speedup in brackets."""
    c, paper = cells(VIEWPORT), _printed("4")
    heads = [f"{col} ({s[:-len('_limited')]})" if col and col.lower() != s.split('_')[0] else
             (col or f"{s[:-len('_limited')]} (no paper column)") for s, col in VIEWPORT_SCENES]
    ratio = {(s, e): float(c[(s, "bounce1", e, 32)]["simt_lane_efficiency_ratio"]) for s, _ in VIEWPORT_SCENES
             for e in ENCODERS}
    shown = {}
    for s, _ in VIEWPORT_SCENES:
        for e, text in zip(ENCODERS, _bold_max([ratio[(s, e)] for e in ENCODERS])):
            shown[(s, e)] = text
    out = ["| encoder | " + " | ".join(heads) + " |", "|---|" + "---:|" * len(heads)]
    for e in ENCODERS:
        row = []
        for s, col in VIEWPORT_SCENES:
            p = paper.get(("mlhcc32" if e == "mlhcc" else e, col)) if col else None
            row.append(shown[(s, e)] + (f" ({p['printed_speedup']})" if p else ""))
        out.append(f"| {e} | " + " | ".join(row) + " |")
    return "\n".join(out)


# Table 8's stand-ins: scene -> the paper's row (None: no paper row)
HCC_DIR_SCENES = [("breakfast_room", "Breakfast"), ("grey_white_room", "Living room"), ("sibenik", "Sibenik"),
                  ("sponza_dabrovic", None), ("landscape", "Vokselia")]


def hcc_dir_block():
    """SIMT lane-efficiency ratio of HCC 32, HCC_DIR and HCC 31 bits, paper MRays/s in brackets."""
    c, paper = cells(HCC_DIR), _printed("8")
    arms = [("hcc", 32, "HCC"), ("hcc-dir", 32, "HCC_DIR"), ("hcc", 31, "HCC_31bit")]
    out = ["| scene | HCC 32 bits | HCC_DIR (31 cut bits + 1 direction bit) | HCC 31 bits |", "|---|---:|---:|---:|"]
    for s, col in HCC_DIR_SCENES:
        vals = _bold_max([float(c[(s, "bounce1", e, b)]["simt_lane_efficiency_ratio"]) for e, b, _ in arms])
        if col:
            vals = [f"{v} ({paper[(col, head)]['value']})" for v, (_, _, head) in zip(vals, arms)]
        label = f"{s} ({col}" + (" stand-in: the paper's Table 8 has no landscape row)" if s == "landscape" else ")") \
            if col else s
        out.append(f"| {label} | " + " | ".join(vals) + " |")
    return "\n".join(out)


def _speedup_range(set_dir):
    sp = [float(r["speedup"]) for k, r in cells(set_dir).items() if k[2] != "nosort" and r["speedup"]]
    return f"{min(sp):.2f}–{max(sp):.2f}"


def hcc_dir_pocl_phrase():
    return _speedup_range(HCC_DIR)


def bounces_pocl_phrase():
    return _speedup_range(BOUNCES)


def bounces_block():
    """Rays, NoSort's lane efficiency and three encoders' (ratio) at every bounce of Breakfast."""
    c = cells(BOUNCES)
    batches = sorted({k[1] for k in c})
    n = lambda b: c[("breakfast_room", b, "nosort", 0)]
    e = lambda b, enc: c[("breakfast_room", b, enc, 32)]
    lane = lambda r: f"{float(r['simt_lane_efficiency']):.3f}"
    best = {b: max(ENCODERS, key=lambda enc: float(e(b, enc)["simt_lane_efficiency_ratio"])) for b in batches}
    mlhcc_label = "MLHCC (ratio; the best code at every bounce)" if all(v == "mlhcc" for v in best.values()) \
        else "MLHCC (ratio)"
    out = ["| | " + " | ".join(batches) + " |", "|---|" + "---:|" * len(batches),
           "| rays (Russian roulette from bounce 3) | " + " | ".join(f"{int(n(b)['rays']):,}" for b in batches) + " |",
           "| NoSort lane efficiency | " + " | ".join(lane(n(b)) for b in batches) + " |"]
    for enc, label in (("hcc", "HCC lane efficiency (ratio)"), ("mlhcc", mlhcc_label), ("ppc", "PPC (ratio)")):
        out.append(f"| {label} | " + " | ".join(
            f"{lane(e(b, enc))} ({float(e(b, enc)['simt_lane_efficiency_ratio']):.2f})" for b in batches) + " |")
    return "\n".join(out)


SWEEP_SCENES = ["breakfast_room", "sibenik", "landscape", "grey_white_room", "multi-instance-real"]


def _sweep(prefix, encoder, values, paper_value, head, roots=(SWEEPS,)):
    """SIMT lane-efficiency ratio per scene and swept value; the row's best in bold. Several roots:
    their sets' cells together (each scene in one root)."""
    sets = {v: {} for v in values}
    for root in roots:
        for v in values:
            sets[v].update(cells(os.path.join(root, f"{prefix}-{v}")))
    scenes = sorted({k[0] for k in sets[values[0]]}, key=SWEEP_SCENES.index)
    heads = [f"{head} = {values[0]}"] + [f"{v} (paper)" if v == paper_value else v for v in values[1:]]
    out = ["| scene | " + " | ".join(heads).replace(".0 ", " ").replace("= 1.0", "= 1") + " |",
           "|---|" + "---:|" * len(values)]
    for s in scenes:
        vals = _bold_max([float(sets[v][(s, "bounce1", encoder, 32)]["simt_lane_efficiency_ratio"]) for v in values])
        out.append(f"| {s} | " + " | ".join(vals) + " |")
    return "\n".join(out).replace("| 1.0 |", "| 1 |")


def lambda_block():
    return _sweep("lambda", "hcc", ["0.1", "0.125", "0.25", "0.5", "1.0"], "0.125", "λ", (SWEEPS, SWEEPS_MORE))


def lambda_spread_phrase():
    """How much λ moves HCC's lane ratio: the widest spread over 0.1-0.5 on any scene, and λ = 1 against
    the paper's 0.125, over the five scenes."""
    values = ["0.1", "0.125", "0.25", "0.5", "1.0"]
    sets = {v: {} for v in values}
    for root in (SWEEPS, SWEEPS_MORE):
        for v in values:
            sets[v].update(cells(os.path.join(root, f"lambda-{v}")))
    # the ratios as the table prints them (three decimals), so the phrase reads off the table
    ratio = lambda v, s: round(float(sets[v][(s, "bounce1", "hcc", 32)]["simt_lane_efficiency_ratio"]), 3)
    scenes = sorted({k[0] for k in sets["0.1"]})
    spread = max(max(ratio(v, s) for v in values[:4]) - min(ratio(v, s) for v in values[:4]) for s in scenes)
    gain = [ratio("1.0", s) - ratio("0.125", s) for s in scenes]
    return (f"within {spread:.3f} on each of the {len(scenes)} scenes between 0.1 and 0.5; λ = 1 against the paper's "
            f"0.125: {min(gain):+.3f} to {max(gain):+.3f}")


def twopoint_block():
    return _sweep("twopoint", "twopoint", ["0.1", "0.25", "0.5", "0.75", "1.0"], "0.25", "L")


def _sweep_scenes():
    """The scenes the committed λ sweep holds, in the order its command gave them."""
    return ",".join(sorted({k[0] for k in cells(os.path.join(SWEEPS, "lambda-0.125"))},
                           key=["sibenik", "breakfast_room", "landscape"].index))


def sweep_lambda_command_phrase():
    return f"`raysort run --preset paper-1spp --scenes {_sweep_scenes()} --batches bounce1 --encoders hcc --bits 32 --lambda λ`"


def sweep_commands_block():
    """docs/paper.md: the commands of the committed sweeps (sweeps-d8b4b22), scenes as the sets hold them."""
    return "\n".join([
        "```sh",
        "for l in 0.1 0.125 0.25 0.5 1.0; do",
        f"  raysort run --preset paper-1spp --scenes {_sweep_scenes()} \\",
        "      --batches bounce1 --encoders hcc --bits 32 --lambda $l --out sets/lambda-$l",
        "done",
        "raysort sweep sets/lambda-* --out sweep-lambda.md",
        "# TwoPoint: --encoders twopoint --twopoint-length D for D in 0.1 0.25 0.5 0.75 1.0",
        "```"])
