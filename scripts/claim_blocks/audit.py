"""results/README.md, "Open questions of the audit (issue 43)": Sibenik's PPC against TwoPoint by key
length, batch, trace layout and PPC's walking order, and TwoPoint's ANC by key length, read from the
two sets of results/<device>/audit-issue43-5382d1e/ (its README.md gives their commands)."""
import csv
import os

from spp_compare import gpu, load

from . import paper_tex
from .sets import AUDIT_ORDER, AUDIT_TWOPOINT_BITS, AUDIT_TWOPOINT_VARIANTS, EIGHT_SPP, ONE_SPP

# The rows of the walking-order table: encoder name in the set -> its label.
ORDER_ROWS = [("hcc", "hcc"), ("twopoint", "twopoint"), ("ppc", "ppc (left child first: the built-in)"),
              ("file:ppc_nearest_first", "ppc, nearest child first (file encoder)")]
BITS = (16, 32, 64)


def cells(set_dir):
    """(layout, batch, encoder, bits) -> row of cells.csv, ok cells on Sibenik."""
    with open(os.path.join(set_dir, "cells.csv"), newline="") as f:
        return {(r["layout"], r["batch"], r["encoder"], int(r["bits"])): r for r in csv.DictReader(f)
                if r["status"] == "ok" and r["scene"] == "sibenik" and r["encoder"] != "nosort"}


def _paper_speedups():
    """encoder -> the paper's Sibenik speedup at 16 / 32 / 64 bits (Table 6 over Table 2's NoSort)."""
    rows = paper_tex.printed()
    printed = {(r["row"], r["column"]): float(r["value"]) for r in rows if r["table"] == "6"}
    nosort = next(float(r["value"]) for r in rows if (r["table"], r["row"], r["column"]) == ("2", "nosort", "Sibenik"))
    return {enc: " / ".join(f"{printed[(enc, str(b))] / nosort:.2f}" for b in BITS) for enc in ("hcc", "twopoint", "ppc")}


def _figure(row, field, fmt):
    v = row.get(field, "")
    return fmt.format(float(v)) if v not in ("", None) else "–"


def order_block():
    """SIMT lane-efficiency ratio and GPU-model speedup, 16 / 32 / 64 bits, by layout and batch."""
    paper = _paper_speedups()
    out = ["| layout | batch | encoder | SIMT lane ratio 16 / 32 / 64 | GPU model 16 / 32 / 64 | ANC 16 / 32 / 64 | paper (Table 6) |",
           "|---|---|---|---|---|---|---|"]
    c = cells(AUDIT_ORDER)
    for layout, label_layout in (("wide", "wide (default)"), ("binary", "binary")):
        for batch in ("bounce1", "shadow0"):
            for enc, label in ORDER_ROWS:
                rows = [c[(layout, batch, enc, b)] for b in BITS]
                lane = " / ".join(_figure(r, "simt_lane_efficiency_ratio", "{:.3f}") for r in rows)
                model = " / ".join(_figure(r, "gpu_model_speedup", "{:.2f}") for r in rows)
                anc = " / ".join(_figure(r, "anc", "{:.2f}") for r in rows)
                p = paper.get(enc, "–") if batch == "bounce1" else "–"
                out.append(f"| {label_layout} | {batch} | {label} | {lane} | {model} | {anc} | {p} |")
    return "\n".join(out)


def twopoint_bits_block():
    """TwoPoint's ANC and SIMT lane-efficiency ratio on Sibenik bounce1 (1 spp) at every key length of its
    set, and the two variants at the lengths they stand for."""
    c = cells(AUDIT_TWOPOINT_BITS)
    c.update(cells(AUDIT_TWOPOINT_VARIANTS))
    bits = sorted({b for (_, _, enc, b) in c if enc == "twopoint"})
    out = ["| key: ANC · SIMT lane ratio | " + " | ".join(f"{b} bits" for b in bits) + " |", "|---|" + "---:|" * len(bits)]
    for enc, label, only in (("twopoint", "TwoPoint (top bits of its 64-bit code)", bits),
                             ("file:twopoint_cap32", "TwoPoint cut to 32 bits (file encoder)", (32, 64)),
                             ("file:twopoint_low16", "low 16 bits of TwoPoint's 32-bit key (file encoder)", (16,))):
        row = [f"{_figure(c[('wide', 'bounce1', enc, b)], 'anc', '{:.2f}')} · "
               f"{_figure(c[('wide', 'bounce1', enc, b)], 'simt_lane_efficiency_ratio', '{:.3f}')}" if b in only else ""
               for b in bits]
        out.append(f"| {label} | " + " | ".join(row) + " |")
    return "\n".join(out)


def batch_block():
    """PPC against TwoPoint on Sibenik at 1 and 8 spp (the paper preset's sets), both batches, 32 and 64 bits."""
    out = ["| batch | bits | SIMT lane ratio: PPC · TwoPoint, 1 spp → 8 spp | GPU model: PPC · TwoPoint, 1 spp → 8 spp |",
           "|---|---:|---|---|"]
    for batch in ("bounce1", "shadow0"):
        for bits in (32, 64):
            one, eight = load(ONE_SPP, "permute", bits), load(EIGHT_SPP, "permute", bits)
            cell = {(s, e): c[("sibenik", batch, e)] for s, c in (("1", one), ("8", eight)) for e in ("ppc", "twopoint")
                    if ("sibenik", batch, e) in c}
            if len(cell) < 4:
                continue
            lane = " → ".join(f"{cell[(s, 'ppc')]['simt_lane_efficiency_ratio']:.3f} · "
                              f"{cell[(s, 'twopoint')]['simt_lane_efficiency_ratio']:.3f}" for s in ("1", "8"))
            model = " → ".join(f"{gpu(cell[(s, 'ppc')]):.2f} · {gpu(cell[(s, 'twopoint')]):.2f}" for s in ("1", "8"))
            out.append(f"| {batch} | {bits} | {lane} | {model} |")
    return "\n".join(out)
