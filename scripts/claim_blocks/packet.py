"""results/README.md, "Tables 2 and 3 on a CPU that sees coherence": the packet class beside single rays
on the paper's 40 cells of each table (paper-1spp-classes-da8579b), and the packet class again after its
robust set-up was vectorised (paper-1spp-packet-06b6e7c), with scripts/paper_correlation.py."""
import csv
import os

from paper_correlation import correlation_table

from .sampling import column_label
from .sets import CLASSES, PACKET_SETUP, PAPER_SPEEDUPS

SCENES = ["sibenik", "breakfast_room", "grey_white_room", "multi-instance-real", "landscape"]
ENCODERS = ["hcc", "mlhcc", "ppc", "twopoint", "grid", "aila", "reis", "origin"]
BATCH = {"2": "bounce1", "3": "shadow0"}


def _cells(set_dir=CLASSES):
    """(layout, scene, batch, encoder) -> row, the ok 32-bit permute cells."""
    with open(os.path.join(set_dir, "cells.csv"), newline="") as f:
        return {(r["layout"], r["scene"], r["batch"], r["encoder"]): r for r in csv.DictReader(f)
                if r["status"] == "ok" and r["access"] == "permute" and r["bits"] == "32"}


def _speedup(r):
    """'1.23', in italic when its 95 % interval contains 1."""
    text = f"{float(r['speedup']):.2f}"
    return f"*{text}*" if float(r["speedup_lo"]) <= 1.0 <= float(r["speedup_hi"]) else text


def correlation_block():
    return "\n".join(correlation_table([CLASSES]))


def setup_correlation_block():
    return "\n".join(correlation_table([PACKET_SETUP]))


def _table(table):
    c = _cells()
    with open(PAPER_SPEEDUPS, newline="") as f:
        paper = {(r["scene"], r["encoder"]): r["paper_speedup"] for r in csv.DictReader(f) if r["table"] == table}
    out = ["| encoder | " + " | ".join(column_label(s) for s in SCENES) + " |", "|---|" + "---|" * len(SCENES)]
    for e in ENCODERS:
        row = [f"{paper[(s, e)]} · {_speedup(c[('packet16', s, BATCH[table], e)])} · "
               f"{_speedup(c[('wide', s, BATCH[table], e)])}" for s in SCENES]
        out.append(f"| {e} | " + " | ".join(row) + " |")
    return "\n".join(out)


def table2_block():
    return _table("2")


def table3_block():
    return _table("3")


def _with_interval(r):
    return f"{float(r['speedup']):.3f} [{float(r['speedup_lo']):.3f}, {float(r['speedup_hi']):.3f}]"


def hcc_breakfast_phrase():
    c = _cells()
    return (f"{_with_interval(c[('packet16', 'breakfast_room', 'bounce1', 'hcc')])} in packets, "
            f"{_with_interval(c[('wide', 'breakfast_room', 'bounce1', 'hcc')])} in single rays")


def setup_hcc_breakfast_phrase():
    hcc = _cells(PACKET_SETUP)[("packet16", "breakfast_room", "bounce1", "hcc")]
    return f"{_with_interval(hcc)} (net {float(hcc['net_speedup']):.3f})"


def shadow_gap_phrase():
    """Table 3 on sibenik and breakfast_room: the packet class's range against the paper's."""
    c = _cells()
    with open(PAPER_SPEEDUPS, newline="") as f:
        paper = [float(r["paper_speedup"]) for r in csv.DictReader(f)
                 if r["table"] == "3" and r["scene"] in ("sibenik", "breakfast_room")]
    ours = [float(c[("packet16", s, "shadow0", e)]["speedup"]) for s in ("sibenik", "breakfast_room") for e in ENCODERS]
    return f"packet16 {min(ours):.2f}-{max(ours):.2f} against {min(paper):.2f}-{max(paper):.2f}"
