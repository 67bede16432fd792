#!/usr/bin/env python3
"""How the figures move from 1 to 8 samples per pixel (issue 22): two result sets of the same
matrix at the two samplings, side by side, as results/README.md lays them out.

  scripts/spp_compare.py ONE_SPP_SET EIGHT_SPP_SET [--access permute] [--bits 32] [--out FILE]

Prints markdown:
  1. per scene and batch: rays, ANC of HCC / TwoPoint / PPC, SIMT lane-efficiency ratio of HCC /
     MLHCC / PPC and the GPU model's HCC speedup, each "1 spp -> 8 spp" (deterministic figures);
  2. the paper's Tables 2 (bounce1) and 3 (shadow0) for every scene of results/gpu-model/
     paper_tables.csv both sets hold: the paper's speedup, the GPU model's 1 -> 8 spp, and PoCL's
     1 -> 8 spp with the 8-spp set's per-round min-max (three timed rounds give no 95 % interval);
  3. per table, the GPU model's mean absolute error and Spearman correlation against the paper at
     each sampling over the cells both sets hold.
  4. with --long, tables 2 and 3 one row per scene and encoder (adds the SIMT lane-efficiency ratio),
     and a per-scene summary of the model's error; with many scenes the wide layout does not fit;
  5. with --key-lengths, the paper's Table 6 (key length on sibenik, bounce1) the same way, over
     every key length both sets hold (the --bits filter does not apply to it).
Cells of the given access mode and key length; NoSort's cell (one per batch) is the baseline.
Standard library only.
"""
import argparse
import csv
import json
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from gpu_model_validate import mae, spearman  # noqa: E402  (one definition of the statistics)


def load(d, access, bits):
    """(scene, batch, encoder) -> the cell's JSON record, for ok cells of one access and key length."""
    out = {}
    for name in sorted(os.listdir(os.path.join(d, "cells"))):
        with open(os.path.join(d, "cells", name)) as f:
            c = json.load(f)
        if c.get("status") != "ok" or c.get("baseline", "pixel") != "pixel" or c.get("top_bits", 0):
            continue
        if c["encoder"] != "nosort" and (c["access"] != access or c["bits"] != bits):
            continue
        out[(c["scene"], c["batch"], c["encoder"])] = c
    return out


def gpu(c):
    g = c.get("gpu_model") or {}
    return g.get("speedup")


def pocl(c):
    s = c.get("speedup") or {}
    return s.get("value")


def round_range(c):
    """Min and max of the per-round NoSort / trace time ratios (the rounds are paired)."""
    s = c.get("samples") or {}
    ratios = [n / t for n, t in zip(s.get("nosort", []), s.get("trace", [])) if t > 0]
    return (min(ratios), max(ratios)) if ratios else None


def pocl_cell(x, y):
    """PoCL speedup 1 spp -> 8 spp, with the 8-spp set's per-round min-max."""
    rr = round_range(y)
    return arrow(pocl(x), pocl(y)) + (f" [{rr[0]:.2f}–{rr[1]:.2f}]" if rr else "")


def arrow(a, b, fmt="{:.2f}"):
    if a is None or b is None:
        return "–"
    return f"{fmt.format(a)} → {fmt.format(b)}"


def long_table(title, rows, at_one, at_eight, with_bits=False):
    """One row per paper cell (scene, encoder[, bits]): the paper's speedup, then 1 spp -> 8 spp of the
    SIMT lane-efficiency ratio, the GPU model and PoCL; then the model's error per scene and overall."""
    out = ["", f"#### {title}", "",
           "| scene | encoder | " + ("bits | " if with_bits else "") + "paper | SIMT lane ratio 1 spp → 8 spp | "
           "GPU model 1 spp → 8 spp | PoCL 1 spp → 8 spp [8-spp rounds min–max] |",
           "|---|---|" + ("---:|" if with_bits else "") + "---:|---:|---:|---:|"]
    for p in rows:
        x, y = at_one(p), at_eight(p)
        out.append(f"| {p['scene']} | {p['encoder']} | " + (f"{p['bits']} | " if with_bits else "") +
                   f"{p['paper_speedup']} | {arrow(x['simt_lane_efficiency_ratio'], y['simt_lane_efficiency_ratio'])} | "
                   f"{arrow(gpu(x), gpu(y))} | {pocl_cell(x, y)} |")
    out += ["", "| GPU model against the paper | cells | MAE 1 spp | MAE 8 spp | Spearman 1 spp | Spearman 8 spp |",
            "|---|---:|---:|---:|---:|---:|"]
    groups = [(s, [p for p in rows if p["scene"] == s]) for s in dict.fromkeys(p["scene"] for p in rows)]
    if len(groups) > 1:
        groups.append(("all", rows))
    for name, ps in groups:
        truth = [float(p["paper_speedup"]) for p in ps]
        stats = []
        for at in (at_one, at_eight):
            pred = [gpu(at(p)) for p in ps]
            ok = all(q is not None for q in pred)
            stats.append((mae(pred, truth) if ok else None, spearman(pred, truth) if ok and len(ps) > 2 else None))
        f = lambda v, fmt: "–" if v is None else fmt.format(v)
        out.append(f"| {name} | {len(ps)} | {f(stats[0][0], '{:.3f}')} | {f(stats[1][0], '{:.3f}')} | "
                   f"{f(stats[0][1], '{:.2f}')} | {f(stats[1][1], '{:.2f}')} |")
    return out


def batch_table(one, eight):
    """Per scene and batch both sets hold: rays, ANC and SIMT lane ratios of a few encoders and the GPU
    model's HCC speedup, each "1 spp -> 8 spp" (markdown lines; scripts/claims.py quotes it too)."""
    batches = sorted({(s, b) for (s, b, e) in eight if e == "nosort" and (s, b, "nosort") in one})
    lines = ["| scene, batch | rays 1 spp → 8 spp | HCC ANC | TwoPoint ANC | PPC ANC | HCC SIMT lane ratio | "
             "MLHCC lane ratio | PPC lane ratio | HCC GPU model |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for s, b in batches:
        o, e = (lambda enc: one.get((s, b, enc))), (lambda enc: eight.get((s, b, enc)))
        def pair(enc, f, fmt="{:.2f}"):
            x, y = o(enc), e(enc)
            return arrow(f(x) if x else None, f(y) if y else None, fmt)
        rays = f"{o('nosort')['rays'] / 1e6:.2f} M → {e('nosort')['rays'] / 1e6:.2f} M"
        lines.append(f"| {s} {b} | {rays} | {pair('hcc', lambda c: c['anc'])} | {pair('twopoint', lambda c: c['anc'])} | "
                     f"{pair('ppc', lambda c: c['anc'])} | {pair('hcc', lambda c: c['simt_lane_efficiency_ratio'])} | "
                     f"{pair('mlhcc', lambda c: c['simt_lane_efficiency_ratio'])} | "
                     f"{pair('ppc', lambda c: c['simt_lane_efficiency_ratio'])} | {pair('hcc', gpu)} |")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("one")
    ap.add_argument("eight")
    ap.add_argument("--access", default="permute", choices=("gather", "permute"))
    ap.add_argument("--bits", type=int, default=32)
    ap.add_argument("--paper", default=os.path.join(ROOT, "results/gpu-model/paper_tables.csv"))
    ap.add_argument("--out")
    ap.add_argument("--long", action="store_true", help="tables 2 and 3 one row per scene and encoder")
    ap.add_argument("--key-lengths", action="store_true", help="add the paper's Table 6 (sibenik, 16/32/64 bits)")
    a = ap.parse_args()
    one, eight = load(a.one, a.access, a.bits), load(a.eight, a.access, a.bits)
    lines = [f"Cells: {a.access}, {a.bits}-bit keys; `{os.path.basename(os.path.normpath(a.one))}` (1 spp) → "
             f"`{os.path.basename(os.path.normpath(a.eight))}` (8 spp).", ""] + batch_table(one, eight)
    with open(a.paper, newline="") as f:
        paper_rows = list(csv.DictReader(f))
    paper = [r for r in paper_rows if r["table"] in ("2", "3") and int(r["bits"]) == a.bits]
    for table, batch, title in (("2", "bounce1", "Secondary rays (bounce1) — paper Table 2"),
                                ("3", "shadow0", "Primary shadow rays (shadow0) — paper Table 3")):
        rows = [p for p in paper if p["table"] == table
                and (p["scene"], batch, p["encoder"]) in one and (p["scene"], batch, p["encoder"]) in eight]
        if not rows:
            continue
        scenes = sorted({p["scene"] for p in rows})
        if a.long:
            lines += long_table(title, rows, lambda p: one[(p["scene"], batch, p["encoder"])],
                                lambda p: eight[(p["scene"], batch, p["encoder"])])
            continue
        lines += ["", f"#### {title}", "",
                  "| encoder | " + " | ".join(f"{s}: paper | GPU model 1 spp → 8 spp | PoCL 1 spp → 8 spp [8-spp rounds min–max]"
                                              for s in scenes) + " |",
                  "|---|" + "---:|---:|---:|" * len(scenes)]
        for enc in dict.fromkeys(p["encoder"] for p in rows):
            cells = []
            for s in scenes:
                p = next((p for p in rows if p["scene"] == s and p["encoder"] == enc), None)
                if not p:
                    cells += ["–", "–", "–"]
                    continue
                x, y = one[(s, batch, enc)], eight[(s, batch, enc)]
                cells += [p["paper_speedup"], arrow(gpu(x), gpu(y)), pocl_cell(x, y)]
            lines.append(f"| {enc} | " + " | ".join(cells) + " |")
        truth = [float(p["paper_speedup"]) for p in rows]
        for label, cells in (("1 spp", one), ("8 spp", eight)):
            pred = [gpu(cells[(p["scene"], batch, p["encoder"])]) for p in rows]
            if any(q is None for q in pred):
                continue
            err = mae(pred, truth)
            lines.append("")
            lines.append(f"GPU model against the paper at {label}, {len(rows)} cells: MAE {err:.3f}, "
                         f"Spearman {spearman(pred, truth):.2f}.")
    if a.key_lengths:
        table6 = [r for r in paper_rows if r["table"] == "6"]
        by_bits = {b: (load(a.one, a.access, b), load(a.eight, a.access, b)) for b in sorted({int(r["bits"]) for r in table6})}
        rows = [p for p in table6 if all((p["scene"], p["batch"], e) in by_bits[int(p["bits"])][i]
                                         for i in (0, 1) for e in (p["encoder"], "nosort"))]
        if rows:
            key = lambda p, i: by_bits[int(p["bits"])][i][(p["scene"], p["batch"], p["encoder"])]
            lines += long_table("Key length on sibenik (bounce1) — paper Table 6", rows,
                                lambda p: key(p, 0), lambda p: key(p, 1), with_bits=True)
    text = "\n".join(lines) + "\n"
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    sys.stdout.write(text)


if __name__ == "__main__":
    sys.exit(main())
