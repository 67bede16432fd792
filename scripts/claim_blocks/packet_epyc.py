"""results/README.md, "Tables 2 and 3 on a CPU that sees coherence", its part on the 2-core AMD EPYC with
the kernels of 139c5a4 (the gathered ray prefetched): the packet class's correlation with the paper's
Tables 2 and 3 at each packet width and access mode, which stand-in holds Table 3 down, and what a
packet's width does to the gains on landscape's shadow rays (paper-1spp-packet-139c5a4,
paper-1spp-access-139c5a4), with scripts/paper_correlation.py."""
import csv
import functools
import os
import re

from paper_correlation import correlations, paper_speedups, scene_correlations

from .prose_early import BAR, _elapsed_s, _noise, _rows, duration
from .sampling import column_label
from .sets import PACKET_EPYC, PACKET_EPYC_ACCESS, PACKET_ROWS, PACKET_TZCNT

FIVE = os.path.join(PACKET_EPYC, "five-scenes")
WIDTHS = os.path.join(PACKET_EPYC, "widths-8-4")
LANDSCAPE_21M = os.path.join(PACKET_EPYC, "landscape-21m")
WIDTH_SHADOW0 = os.path.join(PACKET_EPYC, "width-shadow0")
WIDTHS_AGAIN = os.path.join(PACKET_EPYC, "widths-8-16")
FAST_ROBUST = os.path.join(PACKET_EPYC, "landscape-fast-robust")
PACKET_STEPS = os.path.join(PACKET_EPYC, "packet-steps")  # build/packet_study SCENE 1920x1080 shadow0
ROWS_FIVE = os.path.join(PACKET_ROWS, "five-scenes")
ROWS_LANDSCAPE_21M = os.path.join(PACKET_ROWS, "landscape-21m")
TZCNT_FIVE = os.path.join(PACKET_TZCNT, "five-scenes")
AS_PAPER_SIZE = {"scenes/paper-size/landscape-21m.toml": "landscape"}

# (label, set folders, scene mapping, the classes and access modes to show), in the block's order
ROWS = [
    ("`five-scenes/`", [FIVE], None, [("packet16", "permute")]),
    ("`paper-1spp-access-139c5a4`", [PACKET_EPYC_ACCESS], None,
     [("packet16", "permute"), ("packet16", "gather"), ("wide", "permute"), ("wide", "gather")]),
    ("`widths-8-4/`", [WIDTHS], None, [("packet8", "permute"), ("packet4", "permute")]),
    ("`widths-8-16/`", [WIDTHS_AGAIN], None, [("packet8", "permute"), ("packet16", "permute")]),
    ("`five-scenes/` with `landscape-21m/` as the paper's landscape", [FIVE, LANDSCAPE_21M], AS_PAPER_SIZE,
     [("packet16", "permute")]),
    ("`paper-1spp-packet-a4d24f4`, rays in a row: `five-scenes/`", [ROWS_FIVE], None, [("packet16", "permute")]),
    ("the same with its `landscape-21m/` as the paper's landscape", [ROWS_FIVE, ROWS_LANDSCAPE_21M], AS_PAPER_SIZE,
     [("packet16", "permute")]),
    ("`paper-1spp-packet-4399aef`, one `tzcnt` a lowest bit: `five-scenes/`", [TZCNT_FIVE], None,
     [("packet16", "permute")]),
]


@functools.lru_cache(maxsize=None)
def _correlations(sets, scene_as=None):
    """paper_correlation.correlations of a tuple of set folders (and a scene mapping's items), computed once."""
    return correlations(list(sets), scene_as=dict(scene_as) if scene_as else None)


def _pearson(c):
    text = f"{c['pearson']:.2f} [{c['lo']:.2f}, {c['hi']:.2f}]"
    return f"**{text}**" if c["pearson"] >= BAR else text


def correlation_block():
    out = ["| set | class | access | Table 2 (bounce1): Pearson [95 %] | Table 3 (shadow0): Pearson [95 %] |",
           "|---|---|---|---|---|"]
    for label, sets, scene_as, arms in ROWS:
        c = _correlations(tuple(sets), tuple(scene_as.items()) if scene_as else None)
        for layout, access in arms:
            out.append(f"| {label} | {layout} | {access} | {_pearson(c[('2', layout, access)])} | "
                       f"{_pearson(c[('3', layout, access)])} |")
    return "\n".join(out)


def by_scene_block():
    """Per stand-in: the packet16 cells' Pearson within the scene and over the other four, both tables, in
    the two sets of the same cells (five-scenes, then the access set's permuted packet16 cells)."""
    five, access = scene_correlations([FIVE]), scene_correlations([PACKET_EPYC_ACCESS])
    out = ["| stand-in | Table 2: within the scene | Table 2: without it | Table 3: within the scene | "
           "Table 3: without it |", "|---|---|---|---|---|"]
    for scene in ["sibenik", "breakfast_room", "grey_white_room", "multi-instance-real", "landscape"]:
        cols = []
        for table in "23":
            a, b = five[(table, "packet16", "permute", scene)], access[(table, "packet16", "permute", scene)]
            cols.append(f"{a[1]:.2f} · {b[1]:.2f}")
            cols.append(f"{a[3]:.2f} · {b[3]:.2f}")
        out.append(f"| {column_label(scene)} | " + " | ".join(cols) + " |")
    return "\n".join(out)


@functools.lru_cache(maxsize=None)
def _cells(set_dir):
    with open(os.path.join(set_dir, "cells.csv"), newline="") as f:
        return {(r["scene"], r["encoder"], r["layout"]): r for r in csv.DictReader(f) if r["status"] == "ok"}


def width_block():
    """shadow0 on landscape and sibenik: each width's speedup over its own NoSort (all in the same rounds),
    the SIMT model's two ratios (32-wide warps over the 4-wide tree), and the paper's speedup."""
    c, paper = _cells(WIDTH_SHADOW0), paper_speedups()
    layouts = ["packet16", "packet8", "packet4", "wide"]
    out = ["| scene | encoder | paper | " + " | ".join(layouts) + " | SIMT lane efficiency ratio | SIMT distinct "
           "nodes per visit ratio |", "|---|---|---:|" + "---|" * len(layouts) + "---:|---:|"]
    for scene in ["landscape", "sibenik"]:
        out.append(f"| {scene} | NoSort, MRays/s | | " + " | ".join(
            f"{float(c[(scene, 'nosort', l)]['trace_mrays']):.1f}" for l in layouts) + " | | |")
        for e in ["hcc", "origin", "reis", "ppc", "aila"]:
            row = []
            for l in layouts:
                r = c[(scene, e, l)]
                row.append(f"{float(r['speedup']):.2f} [{float(r['speedup_lo']):.2f}, {float(r['speedup_hi']):.2f}]")
            r = c[(scene, e, "packet16")]
            simt = f"{float(r['simt_lane_efficiency_ratio']):.2f} | {float(r['simt_distinct_per_visit_ratio']):.2f}"
            out.append(f"| {scene} | {e} | {paper[('3', scene, e)]:.2f} | " + " | ".join(row) + f" | {simt} |")
    return "\n".join(out)


def access_phrase():
    """The access set: what the prefetch did to the gather column's correlation (wide, then packet16)."""
    c = _correlations((PACKET_EPYC_ACCESS,))
    f = lambda t, l, a: f"{c[(t, l, a)]['pearson']:.2f}"  # noqa: E731
    return (f"single rays (`wide`) gathered {f('2', 'wide', 'gather')} and {f('3', 'wide', 'gather')}, permuted "
            f"{f('2', 'wide', 'permute')} and {f('3', 'wide', 'permute')}; packets gathered "
            f"{f('2', 'packet16', 'gather')} and {f('3', 'packet16', 'gather')}, permuted "
            f"{f('2', 'packet16', 'permute')} and {f('3', 'packet16', 'permute')}")


def runs_phrase():
    """Each run of the sets: cells, wall clock (run.log's WALL line) and A/A calibration."""
    parts = []
    for d in [FIVE, PACKET_EPYC_ACCESS, WIDTHS, WIDTHS_AGAIN, LANDSCAPE_21M, WIDTH_SHADOW0]:
        n, wall = _noise(d), duration(_elapsed_s(os.path.join(d, "run.log")))
        parts.append(f"`{os.path.basename(d)}` {len(_rows(d))} cells in {wall} "
                     f"(A/A {n['aa_containing_one']} of {n['aa_intervals']})")
    return "; ".join(parts)


def fast_robust_phrase():
    """landscape shadow0: the fast variant's speedups beside the robust one's, packets of 16 and of 8."""
    c = {(r["variant"], r["layout"], r["encoder"]): r for r in _rows(FAST_ROBUST) if r["status"] == "ok"}
    f = lambda v, l, e: f"{float(c[(v, l, e)]['speedup']):.2f}"  # noqa: E731
    return "; ".join(f"{e}: packet16 {f('fast', 'packet16', e)} fast, {f('robust', 'packet16', e)} robust, packet8 "
                     f"{f('fast', 'packet8', e)} and {f('robust', 'packet8', e)}" for e in ["hcc", "origin", "reis"])


def wide_gather_phrase():
    """The access set's single rays gathered: Pearson with Table 2, then Table 3 (paper-cfebb2c's section)."""
    c = _correlations((PACKET_EPYC_ACCESS,))
    return f"{c[('2', 'wide', 'gather')]['pearson']:.2f} and {c[('3', 'wide', 'gather')]['pearson']:.2f}"


def width_verdict_phrase():
    """Per packet width, its Pearson with Table 2 and Table 3 in every run of the five scenes (ROWS' sets)."""
    runs = {}
    for label, sets, scene_as, arms in ROWS:
        if scene_as:
            continue
        c = _correlations(tuple(sets))
        for layout, access in arms:
            if layout.startswith("packet") and access == "permute":
                runs.setdefault(layout, []).append(
                    (c[("2", layout, access)]["pearson"], c[("3", layout, access)]["pearson"]))
    return "; ".join(f"{layout} " + ", ".join(f"{a:.2f}" for a, _ in r) + " and " + ", ".join(f"{b:.2f}" for _, b in r)
                     for layout, r in sorted(runs.items(), key=lambda kv: -int(kv[0][6:])))


def _packet_steps(scene):
    """packet_study's output for the scene's shadow0: (order, width) -> (steps per packet, lanes per step)."""
    with open(os.path.join(PACKET_STEPS, f"{scene}-shadow0.txt")) as f:
        return {(m.group(1), int(m.group(2))): (float(m.group(3)), float(m.group(4)))
                for m in re.finditer(r"^  (\S+)\s+packet(\d+)\s+steps\s+([\d.]+)\s+leaf steps\s+[\d.]+\s+lanes per step"
                                     r"\s+([\d.]+)", f.read(), re.M)}


def steps_block():
    """What an order saves a packet in steps (NoSort's steps per packet over the order's, packet_study's host
    count) beside what it buys in time (width-shadow0's measured speedup), packets of 16 and 8, shadow0."""
    c = _cells(WIDTH_SHADOW0)
    out = ["| scene | encoder | packet16: fewer steps | packet16: faster | packet16: lanes per step | "
           "packet8: fewer steps | packet8: faster |", "|---|---|---:|---:|---|---:|---:|"]
    for scene in ["landscape", "sibenik"]:
        steps = _packet_steps(scene)
        for e in ["hcc", "origin", "reis", "ppc", "aila"]:
            cols = []
            for w in (16, 8):
                cols.append(f"{steps[('nosort', w)][0] / steps[(e, w)][0]:.2f}")
                cols.append(f"{float(c[(scene, e, f'packet{w}')]['speedup']):.2f}")
                if w == 16:
                    cols.append(f"{steps[('nosort', 16)][1]:.2f} → {steps[(e, 16)][1]:.2f}")
            out.append(f"| {scene} | {e} | " + " | ".join(cols) + " |")
    return "\n".join(out)
