"""results/README.md, "Beyond the paper" (issue 21): hcc-region, hcc-traffic and mlhcc-cost against the
paper's encoders, read from their 1-spp matrices (cells.csv), their sweeps, the order and region
studies' committed outputs (host twins, deterministic) and the paired encode cost (encodebench
--versus hcc). Ratios are computed from the unrounded cells; a table's bold is its row's best."""
import glob
import os
import re
import statistics

from encode_versus_table import read as read_versus

from .appendix import _bold_max, cells
from .sets import (COST_BITS_SWEEP, ENCODE_COST, ENCODE_VERSUS, MLHCC_COST, MLHCC_COST_C8, NEW_ENCODERS,
                   ORDER_STUDY, REGION_CELLS, REGION_STUDY, REGION_SWEEPS, REGION_V2, SWEEPS)

# the order of the matrices' command line (issue 21's eight scenes, then landscape)
SCENES = ["sibenik", "breakfast_room", "grey_white_room", "sponza_dabrovic", "wooden_staircase",
          "japanese_classroom", "jacksboro_terrain", "multi-instance-real", "landscape"]
BATCHES = ["bounce1", "shadow0"]
PAPER = ["hcc", "mlhcc", "ppc", "twopoint"]
OPEN_SCENES = ["jacksboro_terrain", "landscape"]


def _cell(set_dir, scene, batch, encoder):
    return cells(set_dir)[(scene, batch, encoder, 32)]


def lane(set_dir, scene, batch, encoder):
    return float(_cell(set_dir, scene, batch, encoder)["simt_lane_efficiency_ratio"])


def gpu(set_dir, scene, batch, encoder):
    return float(_cell(set_dir, scene, batch, encoder)["gpu_model_speedup"])


def distinct(set_dir, scene, batch, encoder):
    return float(_cell(set_dir, scene, batch, encoder)["simt_distinct_per_visit_ratio"])


def encode_ms(set_dir, scene, batch, encoder):
    return float(_cell(set_dir, scene, batch, encoder)["encode_ms"])


def pct(new, old):
    return f"{(new / old - 1) * 100:+.1f} %"


def _header(first, heads):
    return [f"| {first} | " + " | ".join(heads) + " |", "|---|" + "---:|" * len(heads)]


# --- the first version: new-encoders-1spp-d8b4b22 -------------------------------------------------

NEW = ["hcc-region", "hcc-traffic"]


def _first_version_gain(scene, batch):
    """The better new encoder's lane ratio over the better of HCC and MLHCC."""
    best_new = max(lane(NEW_ENCODERS, scene, batch, e) for e in NEW)
    best_old = max(lane(NEW_ENCODERS, scene, batch, e) for e in ("hcc", "mlhcc"))
    return best_new / best_old - 1


def _first_version_block(batch):
    encs = PAPER + NEW
    out = _header("scene", encs + ["best new vs best of HCC, MLHCC"])
    for s in SCENES:
        bold = _bold_max([lane(NEW_ENCODERS, s, batch, e) for e in encs])
        row = [f"{b} · {gpu(NEW_ENCODERS, s, batch, e):.2f}" for b, e in zip(bold, encs)]
        row.append(f"{_first_version_gain(s, batch) * 100:+.1f} %")
        out.append(f"| {s} | " + " | ".join(row) + " |")
    wins = sum(_first_version_gain(s, batch) > 0 for s in SCENES)
    return "\n".join(out) + f"\n\nbest new beats both on {wins} of {len(SCENES)}"


def first_bounce1_block():
    return _first_version_block("bounce1")


def first_shadow0_block():
    return _first_version_block("shadow0")


def first_encode_block():
    """PoCL encode medians: HCC's, and the two new encoders' with their ratio to it; hcc-traffic's host cut."""
    out = ["| scene | batch | HCC encode | hcc-region encode (× HCC) | hcc-traffic encode (× HCC) | hcc-traffic cut_ms (host) |",
           "|---|---|---:|---:|---:|---:|"]
    for s in SCENES:
        for b in BATCHES:
            hcc = encode_ms(NEW_ENCODERS, s, b, "hcc")
            new = [f"{encode_ms(NEW_ENCODERS, s, b, e):.1f} ({encode_ms(NEW_ENCODERS, s, b, e) / hcc:.2f}×)" for e in NEW]
            cut = float(_cell(NEW_ENCODERS, s, b, "hcc-traffic")["cut_ms"])
            out.append(f"| {s} | {b} | {hcc:.1f} | " + " | ".join(new) + f" | {cut:.0f} |")
    return "\n".join(out)


def _knob_block(prefix, encoder, values, first_head, heads):
    """A sweep of sweeps-d8b4b22 beside HCC (from the matrix): lane ratio, the row's best in bold with
    its gain over HCC."""
    sets = {v: cells(os.path.join(SWEEPS, f"{prefix}-{v}")) for v in values}
    scenes = sorted({k[0] for k in sets[values[0]]})
    out = _header("scene", [first_head] + heads)
    for s in scenes:
        hcc = lane(NEW_ENCODERS, s, "bounce1", "hcc")
        vals = [hcc] + [float(sets[v][(s, "bounce1", encoder, 32)]["simt_lane_efficiency_ratio"]) for v in values]
        shown = _bold_max(vals)
        best = vals.index(max(vals))
        if best > 0:
            shown[best] += f" ({pct(vals[best], hcc)})"
        out.append(f"| {s} | " + " | ".join(shown) + " |")
    return "\n".join(out)


def region_knob_block():
    return _knob_block("region", "hcc-region", ["1", "2", "3", "4", "5"], "HCC",
                       ["hcc-region r = 1", "r = 2", "r = 3", "r = 4", "r = 5"])


def traffic_knob_block():
    return _knob_block("traffic", "hcc-traffic", ["0.25", "0.5", "0.75", "1.0"], "HCC (β = 0)",
                       ["hcc-traffic β = 0.25", "β = 0.5", "β = 0.75", "β = 1"])


# --- the order study: results/order-study/bounce1-960x540.txt --------------------------------------

def study(path=ORDER_STUDY):
    """{scene: {row label: (lane, distinct, ANC)}} from order_study's or region_study's output."""
    rows, scene = {}, None
    for line in open(path):
        m = re.match(r"(\S+) bounce1 at ", line)
        if m:
            scene = m.group(1)
            rows[scene] = {}
            continue
        m = re.match(r"\s+(.+?)\s+lane ([\d.]+)\s+distinct nodes ([\d.]+)\s+ANC\s+([\d.]+)$", line)
        if m and scene:
            rows[scene][m.group(1)] = tuple(float(m.group(i)) for i in (2, 3, 4))
    return rows


ORACLE_COLUMNS = [("HCC/32", "hcc/32"), ("MLHCC/32", "mlhcc/32"), ("MLHCC/64", "mlhcc/64"), ("PPC/32", "ppc/32"),
                  ("rep.·l·TwoPoint₁₁ (32)", "representative | l | twopoint/11"),
                  ("MLHCC/32‖TwoPoint/32 (64)", "mlhcc/32 | twopoint/32 (64 bits)"),
                  ("oracle: HCC/32 then steps", "oracle: hcc/32, then step count"),
                  ("oracle: steps", "oracle: step count")]


def oracle_block():
    rows = study()
    out = _header("scene", [h for h, _ in ORACLE_COLUMNS])
    for s in SCENES:
        out.append(f"| {s} | " + " | ".join(f"{rows[s][label][0]:.3f}" for _, label in ORACLE_COLUMNS) + " |")
    return "\n".join(out)


COST_STUDY_COLUMNS = [  # (head, row label, with the distinct-nodes ratio)
    ("MLHCC/32 split 24 \\| 8", "mlhcc/32 split 24 | 8", False), ("split 8 \\| 24", "mlhcc/32 split 8 | 24", False),
    ("HCC/32 \\| est (64 bits), previous frame", "prev-frame cost table: hcc/32 | est", False),
    ("the same, this frame's table (oracle)", "oracle cost table: hcc/32 | est", False),
    ("MLHCC/24 \\| est/8", "prev-frame cost table: mlhcc/24 | est/8", False),
    ("**mlhcc-cost/32, C = 4** (16 \\| 12 \\| 4)", "mlhcc-cost/32 (16 | 12 | 4)", True),
    ("C = 8 (16 \\| 8 \\| 8)", "mlhcc-cost/32 (16 | 8 | 8)", True),
    ("C = 12 (16 \\| 4 \\| 12)", "mlhcc-cost/32 (16 | 4 | 12)", True),
    ("MLHCC/32 \\| PPC/32 (64 bits)", "mlhcc/32 | ppc/32 (64 bits)", False)]


def cost_study_block():
    rows = study()
    out = _header("scene", ["best of HCC/32, MLHCC/32 (lane · distinct)"] + [h for h, _, _ in COST_STUDY_COLUMNS])
    for s in SCENES:
        r = rows[s]
        best = max((r["hcc/32"], r["mlhcc/32"]), key=lambda v: v[0])
        shown = [f"{best[0]:.3f} · {best[1]:.2f}"]
        for head, label, with_distinct in COST_STUDY_COLUMNS:
            text = f"{r[label][0]:.3f}" + (f" · {r[label][1]:.2f}" if with_distinct else "")
            shown.append(f"**{text}**" if head.startswith("**") else text)
        out.append(f"| {s} | " + " | ".join(shown) + " |")
    return "\n".join(out)


# --- mlhcc-cost: mlhcc-cost-1spp-f82d974 (C = 4) and -fbcf847 (C = 8) -------------------------------

def _cost_arm(encoder, column):
    """The set and encoder of a column of the mlhcc-cost tables: C = 8 is fbcf847's mlhcc-cost."""
    return (MLHCC_COST_C8, "mlhcc-cost") if column == "C = 8" else (MLHCC_COST, encoder)


def _mlhcc_cost_block(batch):
    columns = PAPER + ["mlhcc-cost", "C = 8"]
    heads = PAPER + ["**mlhcc-cost** (C = 4)", "C = 8", "C = 4 vs best of HCC, MLHCC: lane · GPU model"]
    out = _header("scene", heads)
    for s in SCENES:
        arms = [_cost_arm(c, c) for c in columns]
        bold = _bold_max([lane(d, s, batch, e) for d, e in arms])
        row = [f"{b} · {distinct(d, s, batch, e):.2f} · {gpu(d, s, batch, e):.2f}" for b, (d, e) in zip(bold, arms)]
        lane_gain = pct(lane(MLHCC_COST, s, batch, "mlhcc-cost"), max(lane(MLHCC_COST, s, batch, e) for e in ("hcc", "mlhcc")))
        gpu_gain = pct(gpu(MLHCC_COST, s, batch, "mlhcc-cost"), max(gpu(MLHCC_COST, s, batch, e) for e in ("hcc", "mlhcc")))
        out.append(f"| {s} | " + " | ".join(row) + f" | {lane_gain} · {gpu_gain} |")
    return "\n".join(out)


def mlhcc_cost_bounce1_block():
    return _mlhcc_cost_block("bounce1")


def mlhcc_cost_shadow0_block():
    return _mlhcc_cost_block("shadow0")


def mlhcc_cost_encode_block():
    out = ["| scene | batch | HCC | MLHCC | mlhcc-cost (× HCC, × MLHCC) | cut_ms (host) |", "|---|---|---:|---:|---:|---:|"]
    for s in SCENES:
        for b in BATCHES:
            hcc, mlhcc, cost = (encode_ms(MLHCC_COST, s, b, e) for e in ("hcc", "mlhcc", "mlhcc-cost"))
            cut = float(_cell(MLHCC_COST, s, b, "mlhcc-cost")["cut_ms"])
            out.append(f"| {s} | {b} | {hcc:.1f} | {mlhcc:.1f} | {cost:.1f} ({cost / hcc:.2f}×, {cost / mlhcc:.2f}×) | {cut:.0f} |")
    return "\n".join(out)


def cost_bits_block():
    """sweeps-fbcf847: mlhcc-cost at C = 4, 8, 12 beside MLHCC (the matrix); the row's best C in bold."""
    values = ["4", "8", "12"]
    sets = {v: os.path.join(COST_BITS_SWEEP, f"cost-{v}") for v in values}
    fmt = lambda d, s, e, text: f"{text} · {distinct(d, s, 'bounce1', e):.2f} · {gpu(d, s, 'bounce1', e):.2f}"
    out = _header("scene", ["MLHCC", "C = 4 (16 \\| 12 \\| 4)", "C = 8 (16 \\| 8 \\| 8)", "C = 12 (16 \\| 4 \\| 12)"])
    for s in SCENES:
        mlhcc = fmt(MLHCC_COST, s, "mlhcc", f"{lane(MLHCC_COST, s, 'bounce1', 'mlhcc'):.3f}")
        bold = _bold_max([lane(sets[v], s, "bounce1", "mlhcc-cost") for v in values])
        out.append(f"| {s} | {mlhcc} | " + " | ".join(fmt(sets[v], s, "mlhcc-cost", b) for v, b in zip(values, bold)) + " |")
    return "\n".join(out)


# --- hcc-region, second version: the region study, region-v2-1spp-7547e16 and sweeps-7547e16 -------

REGION_STUDY_COLUMNS = [("halved + HAD (first version)", "halved + HAD"), ("halved + traffic", "halved + traffic"),
                        ("median + HAD", "median + HAD"), ("**median + traffic** (hcc-region)", "median + traffic (hcc-region)")]


def region_study_block():
    """tools/region_study at r = 4 (its committed output): each rule of the second version alone."""
    rows = study(REGION_STUDY)
    out = _header("scene", ["HCC", "MLHCC"] + [h for h, _ in REGION_STUDY_COLUMNS] + ["vs HCC"])
    for s in SCENES:
        r = rows[s]
        vals = [r["hcc/32"][0], r["mlhcc/32"][0]] + [r[f"r = 4: {label}"][0] for _, label in REGION_STUDY_COLUMNS]
        out.append(f"| {s} | " + " | ".join(f"{v:.3f}" for v in vals) + f" | {pct(vals[-1], vals[0])} |")
    return "\n".join(out)


V2 = ["hcc-region", "hcc-traffic", "mlhcc-cost"]


def _best_new_v2(scene, batch):
    """The new encoder of the best lane ratio, with its lane and GPU-model gain over the better of HCC, MLHCC."""
    best = max(V2, key=lambda e: lane(REGION_V2, scene, batch, e))
    old = lambda f: max(f(REGION_V2, scene, batch, e) for e in ("hcc", "mlhcc"))
    return best, pct(lane(REGION_V2, scene, batch, best), old(lane)), pct(gpu(REGION_V2, scene, batch, best), old(gpu))


def _region_v2_block(batch):
    encs = PAPER + V2
    out = _header("scene", encs + ["hcc-region vs HCC", "best new vs best of HCC, MLHCC (lane · GPU model)"])
    for s in SCENES:
        bold = _bold_max([lane(REGION_V2, s, batch, e) for e in encs])
        row = [f"{b} · {gpu(REGION_V2, s, batch, e):.2f}" for b, e in zip(bold, encs)]
        row.append(pct(lane(REGION_V2, s, batch, "hcc-region"), lane(REGION_V2, s, batch, "hcc")))
        best, lane_gain, gpu_gain = _best_new_v2(s, batch)
        row.append(f"{best}: {lane_gain} · {gpu_gain}")
        out.append(f"| {s} | " + " | ".join(row) + " |")
    return "\n".join(out)


def region_v2_bounce1_block():
    return _region_v2_block("bounce1")


def region_v2_shadow0_block():
    return _region_v2_block("shadow0")


V2_ENCODE = ["mlhcc", "hcc-region", "hcc-traffic", "mlhcc-cost"]


def region_v2_encode_block():
    out = ["| scene | batch | HCC ms | MLHCC | hcc-region | hcc-traffic | mlhcc-cost | hcc-region cut_ms | mlhcc-cost cut_ms |",
           "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for s in SCENES:
        for b in BATCHES:
            hcc = encode_ms(REGION_V2, s, b, "hcc")
            ratios = [f"{encode_ms(REGION_V2, s, b, e) / hcc:.2f}×" for e in V2_ENCODE]
            cuts = [f"{float(_cell(REGION_V2, s, b, e)['cut_ms']):.0f}" for e in ("hcc-region", "mlhcc-cost")]
            out.append(f"| {s} | {b} | {hcc:.1f} | " + " | ".join(ratios + cuts) + " |")
    return "\n".join(out)


def _region_sweep_block(arms, heads, anc):
    """sweeps-7547e16 beside HCC (region-v2's matrix): lane ratio (ANC) · GPU model, the row's best arm
    in bold, and the arms' mean lane ratio over the nine scenes."""
    out = _header("scene", ["HCC"] + heads)
    text = lambda d, e, s, shown: (f"{shown} ({float(_cell(d, s, 'bounce1', e)['anc']):.2f})" if anc else shown) + \
        f" · {gpu(d, s, 'bounce1', e):.2f}"
    for s in SCENES:
        hcc = text(REGION_V2, "hcc", s, f"{lane(REGION_V2, s, 'bounce1', 'hcc'):.3f}")
        bold = _bold_max([lane(d, s, "bounce1", "hcc-region") for d in arms])
        out.append(f"| {s} | {hcc} | " + " | ".join(text(d, "hcc-region", s, b) for d, b in zip(arms, bold)) + " |")
    means = [statistics.mean(lane(d, s, "bounce1", "hcc-region") for s in SCENES) for d in arms]
    out.append("| mean lane ratio | | " + " | ".join(f"{m:.3f}" for m in means) + " |")
    return "\n".join(out)


def region_bits_block():
    bits = ["2", "3", "4", "5", "6"]
    return _region_sweep_block([os.path.join(REGION_SWEEPS, f"region-{r}") for r in bits], [f"r = {r}" for r in bits], True)


BLEND = [("blend-0", "β = 0"), ("blend-0.25", "0.25"), ("region-4", "0.5 (default)"), ("blend-0.75", "0.75"), ("blend-1", "1")]


def blend_block():
    return _region_sweep_block([os.path.join(REGION_SWEEPS, d) for d, _ in BLEND], [h for _, h in BLEND], False)


# --- the third kernel: region-cells-1spp-0a53899 (run 1), encode-cost-1spp-fa55adf (run 2) ----------

THIRD_RUNS = [REGION_CELLS, ENCODE_COST]
THIRD_ENCODERS = ["hcc-region", "mlhcc", "mlhcc-cost", "hcc-traffic"]


def third_ratios(encoder, run):
    """encoder's PoCL encode median over HCC's, per (scene, batch), in one run."""
    return [encode_ms(run, s, b, encoder) / encode_ms(run, s, b, "hcc") for s in SCENES for b in BATCHES]


def third_encode_block():
    out = ["| scene | batch | HCC ms | hcc-region | MLHCC | mlhcc-cost | hcc-traffic |", "|---|---|---:|---:|---:|---:|---:|"]
    for s in SCENES:
        for b in BATCHES:
            hcc = " · ".join(f"{encode_ms(r, s, b, 'hcc'):.1f}" for r in THIRD_RUNS)
            ratios = [" · ".join(f"{encode_ms(r, s, b, e) / encode_ms(r, s, b, 'hcc'):.2f}" for r in THIRD_RUNS)
                      for e in THIRD_ENCODERS]
            out.append(f"| {s} | {b} | {hcc} | " + " | ".join(ratios) + " |")
    medians = [" · ".join(f"{statistics.median(third_ratios(e, r)):.2f}" for r in THIRD_RUNS) for e in THIRD_ENCODERS]
    region = third_ratios("hcc-region", REGION_CELLS) + third_ratios("hcc-region", ENCODE_COST)
    medians[0] = f"**{medians[0]}** ({min(region):.2f}–{max(region):.2f})"
    out.append("| **median** (range) | | | " + " | ".join(medians) + " |")
    return "\n".join(out)


# --- the paired encode cost: encode-versus-hcc-b53a04f (encodebench --versus hcc) ------------------

VERSUS = [("hcc-traffic", "hcc-traffic"), ("hcc-region", "**hcc-region**"), ("mlhcc", "MLHCC (the paper's)"),
          ("mlhcc-cost", "mlhcc-cost")]
BAR = 1.5  # issue 21's encode bar: within 1.5× HCC


def versus_rows(encoder, run):
    """Each batch's paired ratio to HCC with its interval, {name: (x, lo, hi)}, from one run's files."""
    rows = {}
    for path in sorted(glob.glob(os.path.join(ENCODE_VERSUS, run, "*.txt"))):
        r = read_versus(path)[1][encoder]
        rows[os.path.basename(path)[:-4]] = (r["x"], r["lo"], r["hi"])
    return rows


def versus_block():
    out = ["| encoder | × HCC, run 1: median (range of 18) | run 2 | batches whose interval lies wholly under 1.5× (runs 1, 2) | wholly over |",
           "|---|---:|---:|---:|---:|"]
    for encoder, label in VERSUS:
        runs = [versus_rows(encoder, run).values() for run in ("run1", "run2")]
        med = [f"{statistics.median(x for x, _, _ in r):.3f}" for r in runs]
        if label.startswith("**"):
            med = [f"**{m}**" for m in med]
        shown = [f"{m} ({min(x for x, _, _ in r):.3f}–{max(x for x, _, _ in r):.3f})" for m, r in zip(med, runs)]
        under = ", ".join(str(sum(hi < BAR for _, _, hi in r)) for r in runs)
        over = ", ".join(str(sum(lo > BAR for _, lo, _ in r)) for r in runs)
        out.append(f"| {label} | " + " | ".join(shown) + f" | {under} | {over} |")
    return "\n".join(out)
