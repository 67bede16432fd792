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


# --- phrases: figures quoted in the prose ---------------------------------------------------------

def signed(x, digits=1):
    """A signed percentage as the prose prints it (a real minus sign)."""
    return f"{x:+.{digits}f}".replace("-", "−")


def span(values, digits=1, signs=True):
    """'lo to hi' of percentages (signed) or 'lo–hi' of plain numbers."""
    lo, hi = min(values), max(values)
    if f"{lo:.{digits}f}" == f"{hi:.{digits}f}":
        return signed(lo, digits) if signs else f"{lo:.{digits}f}"
    return f"{signed(lo, digits)} to {signed(hi, digits)}" if signs else f"{lo:.{digits}f}–{hi:.{digits}f}"


def run_facts(set_dir, rss=True):
    """'N cells, M min S s, peak RSS G GiB' from a set's cells.csv and its /usr/bin/time run-time.txt."""
    with open(os.path.join(set_dir, "cells.csv")) as f:
        n = sum(1 for _ in f) - 1
    text = open(os.path.join(set_dir, "run-time.txt")).read()
    minutes, seconds = re.search(r"wall clock\) time \(h:mm:ss or m:ss\): (\d+):([\d.]+)", text).groups()
    kib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", text).group(1))
    out = f"{n} cells, {int(minutes)} min {int(float(seconds))} s"
    return out + (f", peak RSS {kib / 1024 ** 2:.1f} GiB" if rss else "")


def gains(f, scenes=SCENES):
    """{scene: percentage} of a per-scene ratio function."""
    return {s: (f(s) - 1) * 100 for s in scenes}


def tally(g):
    """'wins W of N (+a to +b %), ties T, loses L (...)' of per-scene gains; a loss names its scenes when
    there are at most three."""
    wins = [v for v in g.values() if v > 0]
    losses = sorted((v, s) for s, v in g.items() if v < 0)
    parts = [f"wins {len(wins)} of {len(g)}" + (f" ({span(wins)} %)" if wins else "")]
    ties = sum(v == 0 for v in g.values())
    if ties:
        parts.append(f"ties {ties}")
    if losses and len(losses) <= 3:
        parts.append(f"loses {len(losses)} (" + ", ".join(f"{signed(v)} % on {s}" for v, s in losses) + ")")
    elif losses:
        parts.append(f"loses {len(losses)} ({span([v for v, _ in losses])} %, worst on {losses[0][1]})")
    return ", ".join(parts)


# the first version (new-encoders-1spp-d8b4b22)

def first_set_phrase():
    return run_facts(NEW_ENCODERS)


def first_verdict_bounce1_phrase():
    g = {s: _first_version_gain(s, "bounce1") * 100 for s in SCENES}
    wins = sorted(((v, s) for s, v in g.items() if v >= 0), reverse=True)
    big = sorted((v, s) for s, v in g.items() if v < -2)
    return (f"beats both in {len(wins)} of {len(g)} (" + ", ".join(f"{s} {signed(v)} %" for v, s in wins) +
            f"), and loses by more than 2 % in {len(big)} (" + ", ".join(f"{s} {signed(v)} %" for v, s in big) + ")")


def first_verdict_shadow0_phrase():
    g = [_first_version_gain(s, "shadow0") * 100 for s in SCENES]
    return f"beats both in {sum(v > 0 for v in g)} of {len(g)}, by at most {max(g):.1f} %"


def _knob_best(prefix, encoder, values, scene):
    """(best value, its lane ratio) of a sweeps-d8b4b22 knob on a scene."""
    return max(((v, lane(os.path.join(SWEEPS, f"{prefix}-{v}"), scene, "bounce1", encoder)) for v in values),
               key=lambda t: t[1])


def first_region_open_phrase():
    at3 = [signed(pct_of(NEW_ENCODERS, s, "hcc-region")) for s in OPEN_SCENES]
    best = [_knob_best("region", "hcc-region", ["1", "2", "3", "4", "5"], s) for s in OPEN_SCENES]
    at_best = [f"{signed((v / lane(NEW_ENCODERS, s, 'bounce1', 'hcc') - 1) * 100)} % (r = {r})"
               for s, (r, v) in zip(OPEN_SCENES, best)]
    return (f"{at3[0]} % on {OPEN_SCENES[0]} and {at3[1]} % on {OPEN_SCENES[1]} at the default r = 3, "
            f"at best {at_best[0]} and {at_best[1]}")


def pct_of(set_dir, scene, encoder, batch="bounce1", base="hcc"):
    return (lane(set_dir, scene, batch, encoder) / lane(set_dir, scene, batch, base) - 1) * 100


def first_region_breakfast_phrase():
    return f"breakfast_room {signed(pct_of(NEW_ENCODERS, 'breakfast_room', 'hcc-region'))} %"


def _first_encode_ratios(encoder):
    return [encode_ms(NEW_ENCODERS, s, b, encoder) / encode_ms(NEW_ENCODERS, s, b, "hcc") for s in SCENES for b in BATCHES]


def first_traffic_encode_phrase():
    return f"{span(_first_encode_ratios('hcc-traffic'), signs=False)}×"


def first_region_encode_phrase():
    r = _first_encode_ratios("hcc-region")
    return f"{span(r, signs=False)}× HCC, median {statistics.median(r):.1f}×"


def first_cut_phrase():
    cut = {(s, b): float(_cell(NEW_ENCODERS, s, b, "hcc-traffic")["cut_ms"]) for s in SCENES for b in BATCHES}
    times = [cut[k] / encode_ms(NEW_ENCODERS, *k, "hcc-traffic") for k in cut]
    return f"{span([c / 1000 for c in cut.values()], signs=False)} s per batch here (`cut_ms`), {span(times, 0, False)}× its encode"


def traffic_best_phrase():
    """The scenes where some β > 0 beats HCC (β = 0), with the best gain."""
    out = []
    for s in sorted({k[0] for k in cells(os.path.join(SWEEPS, "traffic-0.5"))}):
        beta, v = _knob_best("traffic", "hcc-traffic", ["0.25", "0.5", "0.75", "1.0"], s)
        gain = (v / lane(NEW_ENCODERS, s, "bounce1", "hcc") - 1) * 100
        if gain > 0:
            out.append((gain, s))
    return ", ".join(f"{s} {signed(g)} %" for g, s in sorted(out, reverse=True))


# the order study (results/order-study/bounce1-960x540.txt)

def _study_gains(label, base=("hcc/32",), rows=None):
    rows = rows or study()
    return {s: (rows[s][label][0] / max(rows[s][b][0] for b in base) - 1) * 100 for s in SCENES}


def oracle_anc_phrase():
    return span([study()[s]["hcc/32"][2] for s in SCENES], signs=False)


STEPS = "oracle: hcc/32, then step count"


def oracle_steps_phrase():
    r = study()
    return " and ".join(f"from {r[s]['hcc/32'][0]:.2f} to {r[s][STEPS][0]:.2f} on {s}" for s in ("sibenik", "breakfast_room"))


def oracle_steps_distinct_phrase():
    r = study()["sibenik"]
    return f"{r[STEPS][1]:.2f} against HCC's {r['hcc/32'][1]:.2f} on sibenik"


def oracle_steps_alone_phrase():
    r = study()["sibenik"]["oracle: step count"]
    return f"{r[0]:.3f} on sibenik, distinct-node ratio {r[1]:.2f}"


def oracle_popcount_phrase():
    label = "hcc/32, then popcount of hcc/64"
    r = study()
    return (f"{span(_study_gains(label).values())} % over HCC (sibenik {r['sibenik'][label][0]:.3f}, "
            f"breakfast_room {r['breakfast_room'][label][0]:.3f})")


def oracle_mean_steps_phrase():
    label = "hcc/32, then origin cell's mean steps"
    return f"{span(_study_gains(label).values())} %"


def oracle_exit_phrase():
    label, r = "hcc/32, then scene-box exit distance", study()
    worse = sum(r[s][label][1] > r[s]["hcc/32"][1] for s in SCENES)
    return (f"{span(_study_gains(label).values())} % while making the distinct-node ratio worse in {worse} of "
            f"{len(SCENES)} scenes ({r['jacksboro_terrain'][label][1]:.1f} on jacksboro_terrain)")


def oracle_short_phrase():
    label = "hcc/32 over 0.25 of the extent"
    g = sorted((v, s) for s, v in _study_gains(label).items())
    worst = ", ".join(f"{signed(v)} % on {s}" for v, s in g[:3])
    return f"{worst}; at best {signed(g[-1][0])} %"


def oracle_hit_phrase():
    return f"{span(_study_gains('oracle: hcc/32 up to the hit').values())} %"


def ml_tp_phrase():
    return tally(_study_gains("mlhcc/32 | twopoint/32 (64 bits)", ("hcc/32", "mlhcc/32")))


def ml_tp_64_phrase():
    return tally(_study_gains("mlhcc/32 | twopoint/32 (64 bits)", ("mlhcc/64",)))


def ml_tp_encode_phrase():
    """MLHCC's plus TwoPoint's encode over HCC's, bounce1, in the first matrix."""
    r = [(encode_ms(NEW_ENCODERS, s, "bounce1", "mlhcc") + encode_ms(NEW_ENCODERS, s, "bounce1", "twopoint")) /
         encode_ms(NEW_ENCODERS, s, "bounce1", "hcc") for s in SCENES]
    return f"{span(r, signs=False)}×"


def _study_tally(label, base):
    return lambda: tally(_study_gains(label, base))


fold_phrase = _study_tally("representative | l | twopoint/11", ("mlhcc/32",))
hcc24_tp8_phrase = _study_tally("hcc/24 | twopoint/8 (32 bits)", ("hcc/32", "mlhcc/32"))
ml24_tp8_phrase = _study_tally("mlhcc/24 | twopoint/8 (32 bits)", ("hcc/32", "mlhcc/32"))
hcc32_tp32_phrase = _study_tally("hcc/32 | twopoint/32 (64 bits)", ("hcc/32", "mlhcc/32"))
entered_first_phrase = _study_tally("mlhcc/32, representative entered first", ("mlhcc/32",))
lowest_had_phrase = _study_tally("mlhcc/32, representative of lowest HAD", ("mlhcc/32",))
busiest_phrase = _study_tally("mlhcc/32, busiest representative", ("mlhcc/32",))


# mlhcc-cost: the order study's rows, then mlhcc-cost-1spp-f82d974 (C = 4) and -fbcf847 (C = 8)

ISSUE_SCENES = SCENES[:8]  # issue 21's eight scenes; landscape is the ninth
PREV, ORACLE_TABLE = "prev-frame cost table: hcc/32 | est", "oracle cost table: hcc/32 | est"
COST_ROWS = {"4": "mlhcc-cost/32 (16 | 12 | 4)", "8": "mlhcc-cost/32 (16 | 8 | 8)", "12": "mlhcc-cost/32 (16 | 4 | 12)"}


def cost_prev_frame_phrase():
    r = study()
    below = {s: (1 - r[s][PREV][0] / r[s][ORACLE_TABLE][0]) * 100 for s in SCENES}
    kept = [(r[s][PREV][0] - r[s]["hcc/32"][0]) / (r[s][ORACLE_TABLE][0] - r[s]["hcc/32"][0]) * 100 for s in SCENES]
    return (f"{span(below.values(), signs=False)} % below the oracle table's ({max(below, key=below.get)} the most), "
            f"and it keeps {span(kept, 0, False)} %")


def cost_split_phrase():
    b = study()["breakfast_room"]
    return f"keeps {b['mlhcc/32 split 24 | 8'][0]:.3f} with 24 | 8 but drops to {b['mlhcc/32 split 8 | 24'][0]:.3f} with 8 | 24"


def _cost_vs_best(label, scene):
    return _study_gains(label, ("hcc/32", "mlhcc/32"))[scene]


def cost_ml24_phrase():
    label = "prev-frame cost table: mlhcc/24 | est/8"
    return f"loses {-_cost_vs_best(label, 'breakfast_room'):.1f} % there ({study()['breakfast_room'][label][0]:.3f})"


def cost_c4_c8_phrase():
    loss = [f"{-_cost_vs_best(COST_ROWS[c], 'breakfast_room'):.1f} %" for c in ("4", "8")]
    wins = [sum(_cost_vs_best(COST_ROWS[c], s) > 0 for s in SCENES if s != "breakfast_room") for c in ("4", "8")]
    return f"loses {loss[0]} or {loss[1]} and wins in {wins[0]} and {wins[1]} of the other eight scenes"


def cost_c12_phrase():
    return f"lose {-_cost_vs_best(COST_ROWS['12'], 'breakfast_room'):.1f} % on breakfast_room"


def cost_distinct_phrase():
    r = study()["jacksboro_terrain"]
    moved = max(r[COST_ROWS[c]][0] for c in COST_ROWS) / min(r[COST_ROWS[c]][0] for c in COST_ROWS) - 1
    return (f"from MLHCC's {r['mlhcc/32'][1]:.2f} to " + ", ".join(f"{r[COST_ROWS[c]][1]:.2f} (C = {c})" for c in COST_ROWS) +
            f" on jacksboro_terrain, for a lane ratio that moves by {moved * 100:.1f} %")


def cost_ml_ppc_phrase():
    ppc = _set_encode_ratios(MLHCC_COST, "ppc")
    return (f"against MLHCC/64 it {tally(_study_gains('mlhcc/32 | ppc/32 (64 bits)', ('mlhcc/64',)))}), but costs PPC's "
            f"encode, {span(ppc, 0, False)}× HCC's on PoCL (both batches of the matrix below")


def mlhcc_cost_set_phrase():
    return run_facts(MLHCC_COST)


def mlhcc_cost_c8_set_phrase():
    return run_facts(MLHCC_COST_C8)


DETERMINISTIC = ["simt_lane_efficiency_ratio", "simt_distinct_per_visit_ratio", "anc"]


def same_cells_phrase():
    """The paper's encoders' (and NoSort's) cells whose lane, distinct-node ratios and ANC are the same
    string in both mlhcc-cost sets and in new-encoders-1spp-d8b4b22; and how far their GPU model moved."""
    sets = [cells(d) for d in (MLHCC_COST, MLHCC_COST_C8, NEW_ENCODERS)]
    keys = [k for k in sets[0] if k[2] in PAPER + ["nosort"]]
    same = sum(all(s[k][c] == sets[0][k][c] for s in sets for c in DETERMINISTIC) for k in keys)
    moved = max(abs(float(sets[0][k]["gpu_model_speedup"]) - float(sets[2][k]["gpu_model_speedup"])) for k in keys)
    return f"{same} of their {len(keys)} cells; their GPU-model speedups differ from that older set by at most {moved:.4f}"


def _cost_gains(batch, f, scenes=SCENES, d=MLHCC_COST):
    return gains(lambda s: f(d, s, batch, "mlhcc-cost") / max(f(MLHCC_COST, s, batch, e) for e in ("hcc", "mlhcc")), scenes)


def mlhcc_cost_bounce1_phrase():
    return (f"on the lane ratio it {tally(_cost_gains('bounce1', lane))}; on the GPU model it "
            f"{tally(_cost_gains('bounce1', gpu))}")


def mlhcc_cost_c8_phrase():
    c4, c8 = _cost_gains("bounce1", lane), _cost_gains("bounce1", lane, d=MLHCC_COST_C8)
    larger = sum(c8[s] > c4[s] for s in SCENES)
    below = [s for s in SCENES if gpu(MLHCC_COST_C8, s, "bounce1", "mlhcc-cost") < gpu(MLHCC_COST, s, "bounce1", "mlhcc")]
    j = "jacksboro_terrain"
    return (f"larger in {larger} scenes (up to {signed(max(c8.values()))} %), but the GPU model puts it below MLHCC in "
            f"{len(below)} ({j} {gpu(MLHCC_COST_C8, j, 'bounce1', 'mlhcc-cost'):.2f} against "
            f"{gpu(MLHCC_COST, j, 'bounce1', 'mlhcc'):.2f})")


def mlhcc_cost_shadow0_phrase():
    ppc_best = sum(max(PAPER + ["mlhcc-cost"], key=lambda e: lane(MLHCC_COST, s, "shadow0", e)) == "ppc" for s in SCENES)
    sib = [gpu(d, "sibenik", "shadow0", "mlhcc-cost") for d in (MLHCC_COST_C8, MLHCC_COST)]
    return (f"on the lane ratio it {tally(_cost_gains('shadow0', lane))}; on the GPU model it "
            f"{tally(_cost_gains('shadow0', gpu))}; C = 8 is the better width there (sibenik {sib[0]:.2f} against "
            f"{sib[1]:.2f}); PPC has the best lane ratio in {ppc_best} scenes")


def mlhcc_cost_encode_drift_phrase():
    r = [encode_ms(MLHCC_COST, s, b, e) / encode_ms(NEW_ENCODERS, s, b, e) for s in SCENES for b in BATCHES for e in PAPER]
    return f"{span(r, 2, False)}×"


def _sweep_minutes(root, dirs):
    """'M min S s to M min S s' of the sweep sets' run-time.txt (either /usr/bin/time or 'elapsed Ns')."""
    secs = []
    for d in dirs:
        text = open(os.path.join(root, d, "run-time.txt")).read()
        m = re.search(r"m:ss\): (\d+):([\d.]+)", text)
        secs.append(int(m.group(1)) * 60 + int(float(m.group(2))) if m else int(re.search(r"elapsed (\d+)s", text).group(1)))
    return " to ".join(f"{t // 60} min {t % 60} s" for t in (min(secs), max(secs)))


def cost_bits_phrase():
    sets = {c: os.path.join(COST_BITS_SWEEP, f"cost-{c}") for c in ("4", "8", "12")}
    best8 = sum(max(sets, key=lambda c: lane(sets[c], s, "bounce1", "mlhcc-cost")) == "8" for s in SCENES)
    gpu4 = sum(gpu(sets["4"], s, "bounce1", "mlhcc-cost") > gpu(MLHCC_COST, s, "bounce1", "mlhcc") for s in SCENES)
    loss12 = 1 - lane(sets["12"], "breakfast_room", "bounce1", "mlhcc-cost") / lane(MLHCC_COST, "breakfast_room", "bounce1", "mlhcc")
    return (f"Eight cost bits give the best lane ratio in {best8} scenes, but four keep the distinct nodes close to "
            f"MLHCC's and beat MLHCC on the GPU model in {gpu4}; twelve leave the low-level cut four nodes and lose "
            f"{loss12 * 100:.1f} % on breakfast_room")


def cost_bits_time_phrase():
    return _sweep_minutes(COST_BITS_SWEEP, ["cost-4", "cost-8", "cost-12"]) + " a set"


def cost_verdict_lane_phrase():
    g, land = _cost_gains("bounce1", lane, ISSUE_SCENES), _cost_gains("bounce1", lane)["landscape"]
    return f"{tally(g)}; landscape, the ninth, {signed(land)} %"


def cost_verdict_gpu_phrase():
    return tally(_cost_gains("bounce1", gpu, ISSUE_SCENES))


def first_region_open_short_phrase():
    return " and ".join(f"{signed(pct_of(NEW_ENCODERS, s, 'hcc-region'))} %" for s in OPEN_SCENES)


def cost_open_phrase():
    parts, over = [], []
    for s in OPEN_SCENES:
        c, h, m = (lane(MLHCC_COST, s, "bounce1", e) for e in ("mlhcc-cost", "hcc", "mlhcc"))
        parts.append(f"{signed((c / h - 1) * 100)} % on {s} ({c:.3f} against {h:.3f})")
        over.append(f"{signed((c / m - 1) * 100)} %")
    return " and ".join(parts) + f", of which {' and '.join(over)} over MLHCC"


def _set_encode_ratios(set_dir, encoder, base="hcc"):
    return [encode_ms(set_dir, s, b, encoder) / encode_ms(set_dir, s, b, base) for s in SCENES for b in BATCHES]


def cost_verdict_encode_phrase():
    c, m = _set_encode_ratios(MLHCC_COST, "mlhcc-cost"), _set_encode_ratios(MLHCC_COST, "mlhcc")
    cm = _set_encode_ratios(MLHCC_COST, "mlhcc-cost", "mlhcc")
    return (f"{span(c, signs=False)}× HCC's kernel time here, median {statistics.median(c):.1f}× (MLHCC itself is "
            f"{span(m, signs=False)}× HCC in the same set, median {statistics.median(m):.1f}×, so a two-level key cannot meet "
            f"this bar on PoCL); mlhcc-cost is a median {statistics.median(cm):.1f}× MLHCC")


def cost_verdict_cut_phrase():
    cut = [float(_cell(MLHCC_COST, s, b, "mlhcc-cost")["cut_ms"]) / 1000 for s in SCENES for b in BATCHES]
    return f"{span(cut, signs=False)} s"


# hcc-region, second version: the region study, region-v2-1spp-7547e16, sweeps-7547e16

def _rs(scene, label):
    return study(REGION_STUDY)[scene][label if "/" in label else f"r = 4: {label}"][0]


def region_study_traffic_phrase():
    up = sum(_rs(s, "halved + traffic") > _rs(s, "halved + HAD") for s in SCENES)
    return f"lifts {up} of {len(SCENES)} scenes: " + ", ".join(
        f"{s} from {_rs(s, 'halved + HAD'):.3f} to {_rs(s, 'halved + traffic'):.3f}" for s in ("breakfast_room", "jacksboro_terrain"))


def region_study_median_phrase():
    g = {s: (_rs(s, "median + traffic (hcc-region)") / _rs(s, "halved + traffic") - 1) * 100 for s in SCENES}
    shown = ", ".join(f"{s} {_rs(s, 'median + traffic (hcc-region)'):.3f} ({signed(g[s])} %)"
                      for s in ("breakfast_room", "jacksboro_terrain", "landscape"))
    flat = [s for s in SCENES if abs(g[s]) < 0.3]
    return (f"add up to {max(g.values()):.1f} % on top of it: {shown}. On {', '.join(flat[:-1])} and {flat[-1]} they "
            f"change less than 0.3 %")


def region_study_median_had_phrase():
    return tally({s: (_rs(s, "median + HAD") / _rs(s, "halved + HAD") - 1) * 100 for s in SCENES})


def region_study_grey_phrase():
    return f"{_rs('grey_white_room', 'hcc/32'):.3f} here, {lane(REGION_V2, 'grey_white_room', 'bounce1', 'hcc'):.3f} below"


def region_v2_set_phrase():
    return run_facts(REGION_V2)


def region_v2_moved_phrase():
    """The cells region-v2 shares with new-encoders-1spp-d8b4b22 whose GPU-model speedup moved."""
    old, new = cells(NEW_ENCODERS), cells(REGION_V2)
    moved = [(k, abs(float(new[k]["gpu_model_speedup"]) - float(old[k]["gpu_model_speedup"]))) for k in old
             if k[2] != "hcc-region" and new[k]["gpu_model_speedup"] != old[k]["gpu_model_speedup"]]
    batches = " and ".join(sorted({k[1] for k, _ in moved}))
    return f"{len(moved)} {batches} GPU-model speedups of that older set moved, by at most {max(d for _, d in moved):.4f}"


def _v2_gains(batch, encoder, f=lane, scenes=ISSUE_SCENES):
    return gains(lambda s: f(REGION_V2, s, batch, encoder) / max(f(REGION_V2, s, batch, e) for e in ("hcc", "mlhcc")), scenes)


def region_v2_bounce1_phrase():
    land = _v2_gains("bounce1", "hcc-region", scenes=["landscape"])["landscape"]
    return (f"hcc-region {tally(_v2_gains('bounce1', 'hcc-region'))} of the issue's scenes; landscape, the ninth, "
            f"{signed(land)} %. mlhcc-cost {tally(_v2_gains('bounce1', 'mlhcc-cost'))}")


def region_v2_landscape_phrase():
    g = lambda e: gpu(REGION_V2, "landscape", "bounce1", e)
    d = lambda e: distinct(REGION_V2, "landscape", "bounce1", e)
    return (f"{g('hcc-region'):.2f} against PPC's {g('ppc'):.2f} and HCC's {g('hcc'):.2f}. Its distinct-nodes ratio there is "
            f"{d('hcc-region'):.2f}, against HCC's {d('hcc'):.2f} and PPC's {d('ppc'):.2f}")


def region_v2_shadow0_phrase():
    return tally(_v2_gains("shadow0", "hcc-region"))


def v2_encode(encoder, base="hcc"):
    return _set_encode_ratios(REGION_V2, encoder, base)


def region_v2_encode_phrase():
    r = v2_encode("hcc-region")
    return (f"hcc-traffic runs HCC's kernel (median {statistics.median(v2_encode('hcc-traffic')):.2f}× HCC). hcc-region "
            f"costs {span(r, signs=False)}× HCC, median {statistics.median(r):.2f}×, against "
            f"{statistics.median(_first_encode_ratios('hcc-region')):.1f}× for the first version in its own set")


def region_v2_encode_others_phrase():
    cut = lambda e: span([float(_cell(REGION_V2, s, b, e)["cut_ms"]) / 1000 for s in SCENES for b in BATCHES], signs=False)
    return (f"MLHCC is a median {statistics.median(v2_encode('mlhcc')):.2f}× HCC in the same rows. mlhcc-cost is a median "
            f"{statistics.median(v2_encode('mlhcc-cost')):.2f}×. The previous frame's statistics cost a host traversal: "
            f"{cut('hcc-region')} s per batch for hcc-region (it counts the traffic of each region's rays) and "
            f"{cut('mlhcc-cost')} s for mlhcc-cost")


def _region_bits(r, scene):
    return lane(os.path.join(REGION_SWEEPS, f"region-{r}"), scene, "bounce1", "hcc-region")


def region_bits_phrase():
    over = lambda r, s: (_region_bits(r, s) / lane(REGION_V2, s, "bounce1", "hcc") - 1) * 100
    first = next(r for r in "23456" if all(over(r, s) >= 10 for s in OPEN_SCENES))
    before = str(int(first) - 1)
    return (f"r = {first} is the smallest region count at which both open scenes pass +10 % over HCC (r = {before}: "
            + " and ".join(f"{signed(over(before, s))} %" for s in OPEN_SCENES) + ")")


def region_bits_more_phrase():
    return f"jacksboro_terrain {_region_bits('6', 'jacksboro_terrain'):.3f} at r = 6"


def _blend(name, scene, f=lane):
    return f(os.path.join(REGION_SWEEPS, name), scene, "bounce1", "hcc-region")


def blend_zero_phrase():
    off = max(abs(_blend("blend-0", s) - lane(REGION_V2, s, "bounce1", "hcc")) for s in SCENES)
    return f"to within {off:.3f} in every scene (" + ", ".join(f"{s} {_blend('blend-0', s):.3f}" for s in OPEN_SCENES) + ")"


def blend_zero_gpu_phrase():
    return f"landscape {_blend('blend-0', 'landscape', gpu):.2f} against {gpu(REGION_V2, 'landscape', 'bounce1', 'hcc'):.2f}"


def blend_quarter_phrase():
    return " and ".join(f"{signed((_blend('blend-0.25', s) / lane(REGION_V2, s, 'bounce1', 'hcc') - 1) * 100)} %" for s in OPEN_SCENES)


def blend_more_phrase():
    b0, b1 = _blend("blend-0", "breakfast_room"), _blend("blend-1", "breakfast_room")
    return (f"up to β = 0.75 (" + ", ".join(f"{_blend('blend-0.75', s):.3f}" for s in OPEN_SCENES) + "), while Breakfast "
            f"falls from {b0:.3f} at β = 0 to {b1:.3f} at β = 1 ({signed((b1 / b0 - 1) * 100)} %)")


def blend_mean_phrase():
    mean = lambda d: statistics.mean(_blend(d, s) for s in SCENES)
    return f"{mean('region-4'):.3f}, against {mean('blend-0.25'):.3f} at 0.25 and {mean('blend-0.75'):.3f} at 0.75"


def v2_verdict_bar1_phrase():
    lane_g, gpu_g = _v2_gains("bounce1", "mlhcc-cost"), _v2_gains("bounce1", "mlhcc-cost", gpu)
    region = _v2_gains("bounce1", "hcc-region")
    return (f"on the lane-efficiency ratio it {tally(lane_g)}; on the GPU model it {tally(gpu_g)}. hcc-region "
            f"{tally(region)}")


def v2_verdict_open_phrase():
    parts = [f"{signed(pct_of(REGION_V2, s, 'hcc-region'))} % on {s} ({lane(REGION_V2, s, 'bounce1', 'hcc-region'):.3f} "
             f"against {lane(REGION_V2, s, 'bounce1', 'hcc'):.3f})" for s in OPEN_SCENES]
    g = [(gpu(REGION_V2, s, "bounce1", "hcc-region"), gpu(REGION_V2, s, "bounce1", "hcc")) for s in OPEN_SCENES]
    return (" and ".join(parts) + ". On the GPU model the gain is " + " and ".join(f"{signed((a / b - 1) * 100, 0)} %" for a, b in g)
            + " (" + ", ".join(f"{a:.2f} against {b:.2f}" for a, b in g) + ")")


def v2_verdict_encode_phrase():
    m = lambda e: statistics.median(v2_encode(e))
    return f"hcc-region is {m('hcc-region'):.2f}× and mlhcc-cost {m('mlhcc-cost'):.2f}× (medians), and MLHCC itself is {m('mlhcc'):.2f}×"


# the third kernel: region-cells-1spp-0a53899 (run 1) and encode-cost-1spp-fa55adf (run 2)

def region_cells_set_phrase():
    return run_facts(REGION_CELLS)


def encode_cost_set_phrase():
    return run_facts(ENCODE_COST, rss=False)


SAME_KEYS = ["anc", "simt_lane_efficiency_ratio", "simt_distinct_per_visit_ratio", "gpu_model_speedup", "gpu_warp_steps",
             "gpu_idle_lanes", "gpu_l1_hits", "gpu_l1_misses", "gpu_l2_hits", "gpu_l2_misses", "gpu_dram_bytes",
             "gpu_replayed_warps", "keys_hash", "order_hash"]


def third_same_phrase():
    """How many cells of each third-kernel run have region-v2's deterministic columns, string for string."""
    v2 = cells(REGION_V2)
    counts = []
    for run in THIRD_RUNS:
        c = cells(run)
        counts.append(f"{sum(all(c[k][f] == v2[k][f] for f in SAME_KEYS) for k in c)} of {len(c)} cells")
    return " and ".join(counts)


def _third_region():
    return [third_ratios("hcc-region", r) for r in THIRD_RUNS]


def third_median_phrase():
    return f"{statistics.median(_third_region()[0] + _third_region()[1]):.2f}× HCC"


def third_runs_phrase():
    r1, r2 = _third_region()
    under = lambda r: sum(x <= BAR for x in r)
    second = v2_encode("hcc-region")
    return (f"the median of the {len(r1) + len(r2)} rows of both runs. Run 1 has a median of {statistics.median(r1):.2f}×, "
            f"with {under(r1)} of its {len(r1)} rows at or under 1.5×; run 2 has {statistics.median(r2):.2f}×, with "
            f"{under(r2)} of {len(r2)}. The range is {span(r1 + r2, 2, False)}×, where the second kernel cost "
            f"{statistics.median(second):.2f}× ({span(second, 2, False)}×)")


def third_others_phrase():
    m = lambda e: [f"{statistics.median(third_ratios(e, r)):.2f}×" for r in THIRD_RUNS]
    rows = [(s, b) for s in SCENES for b in BATCHES]
    worst, (scene, batch) = max(zip(third_ratios("mlhcc", ENCODE_COST), rows))
    return (f"MLHCC {m('mlhcc')[0]} against {m('mlhcc')[1]}, and mlhcc-cost {m('mlhcc-cost')[0]} against "
            f"{m('mlhcc-cost')[1]}. MLHCC's {worst:.2f}× on {scene}'s {batch}")


def third_traffic_phrase():
    return " and ".join(f"{statistics.median(third_ratios('hcc-traffic', r)):.2f}×" for r in THIRD_RUNS)


def third_verdict_phrase():
    both = _third_region()[0] + _third_region()[1]
    above = sum(x > BAR for x in both)
    return f"its median is {statistics.median(both):.2f}×, and {above} of the {len(both)} rows are above"


# the paired encode cost: encode-versus-hcc-b53a04f

def _versus_all(encoder):
    return [versus_rows(encoder, run) for run in ("run1", "run2")]


def versus_median_phrase():
    return f"{statistics.median(x for x, _, _ in versus_rows('hcc-region', 'run1').values()):.2f}×"


def versus_region_phrase():
    runs = _versus_all("hcc-region")
    rows = [v for r in runs for v in r.values()]
    under, over = sum(hi < BAR for _, _, hi in rows), sum(lo > BAR for _, lo, _ in rows)
    name, (x, lo, hi) = max(runs[0].items(), key=lambda kv: kv[1][0])
    x2, lo2, hi2 = runs[1][name]
    scene, batch = name.rsplit("-", 1)
    return (f"{under} of the {len(rows)} rows. The other {len(rows) - under - over} contain 1.5, and {over or 'none'} lies wholly "
            f"over it. Its largest point estimate is {x:.3f} ({scene}, {batch}, run 1: [{lo:.3f}, {hi:.3f}]; run 2 gives "
            f"{x2:.3f} [{lo2:.3f}, {hi2:.3f}] for the same batch)")


def versus_moves_phrase():
    move = lambda e: max(abs(a[0] - _versus_all(e)[1][k][0]) for k, a in _versus_all(e)[0].items())
    return (f"{move('hcc-region'):.3f} for hcc-region, {move('hcc-traffic'):.3f} for hcc-traffic, {move('mlhcc'):.3f} for "
            f"MLHCC and {move('mlhcc-cost'):.3f} for mlhcc-cost")


def versus_mlhcc_phrase():
    xs = [x for r in _versus_all("mlhcc") for x, _, _ in r.values()]
    return f"{span(xs, 2, False)}×"


def blend_time_phrase():
    return _sweep_minutes(REGION_SWEEPS, [d for d, _ in BLEND if d.startswith("blend")])


# the verdict on issue 21: the three bars, each new encoder (region-v2-1spp-7547e16, encode-versus-hcc-b53a04f)

def _bar_bounce1(encoder):
    g = _v2_gains("bounce1", encoder)
    wins, (worst, scene) = sum(v > 0 for v in g.values()), min((v, s) for s, v in g.items())
    met = wins >= 6 and worst > -2
    return f"{'**yes**' if met else 'no'}: {wins} of {len(g)}, worst {signed(worst)} % ({scene})"


def _bar_open(encoder):
    g = {s: pct_of(REGION_V2, s, encoder) for s in OPEN_SCENES}
    shown = ", ".join(f"{signed(v)} % ({s})" for s, v in g.items())
    if encoder == "mlhcc-cost":
        return f"not a region code, but {shown}"
    return f"{'**yes**' if all(v >= 10 for v in g.values()) else 'no'}: {shown}"


def _bar_encode(encoder):
    rows = [v for r in _versus_all(encoder) for v in r.values()]
    med = statistics.median(x for x, _, _ in rows)
    under, over = sum(hi < BAR for _, _, hi in rows), sum(lo > BAR for _, lo, _ in rows)
    met = med <= BAR and over == 0
    return (f"{'**yes**' if met else 'no'}: {med:.2f}×, {under} of {len(rows)} intervals wholly under, "
            f"{over or 'none'} over")


def verdict_block():
    encs = ["hcc-traffic", "hcc-region", "mlhcc-cost"]
    bars = [("bounce1: beats HCC and MLHCC on the lane-efficiency ratio in ≥ 6 of 8 scenes, losing none by > 2 %", _bar_bounce1),
            ("open scenes: ≥ +10 % over HCC", _bar_open), ("encode within 1.5× HCC (paired, above)", _bar_encode)]
    out = ["| bar | " + " | ".join(encs) + " |", "|---|---|---|---|"]
    for text, bar in bars:
        out.append(f"| {text} | " + " | ".join(bar(e) for e in encs) + " |")
    return "\n".join(out)


def verdict_regions_phrase():
    rows = [v for r in _versus_all("hcc-region") for v in r.values()]
    g = _v2_gains("bounce1", "hcc-region")
    return (" and ".join(f"{signed(pct_of(REGION_V2, s, 'hcc-region'))} %" for s in OPEN_SCENES) +
            f" there, at {statistics.median(x for x, _, _ in rows):.2f}× HCC's encode. They also beat HCC and MLHCC on "
            f"{sum(v > 0 for v in g.values())} of the {len(g)} scenes. They lose "
            f"{-pct_of(REGION_V2, 'breakfast_room', 'hcc-region', base='mlhcc'):.1f} % to MLHCC on breakfast_room")


def verdict_traffic_phrase():
    g = {s: pct_of(REGION_V2, s, "hcc-traffic") for s in SCENES}
    best = max(g, key=g.get)
    return (f"at most {signed(g[best])} % over HCC on the lane-efficiency ratio ({best}), and it loses "
            f"{-g['breakfast_room']:.1f} % to HCC on breakfast_room")


def verdict_mlhcc_phrase():
    return f"{statistics.median(x for r in _versus_all('mlhcc') for x, _, _ in r.values()):.2f}×"


def versus_batches_phrase():
    return f"all {len(glob.glob(os.path.join(ENCODE_VERSUS, 'run1', '*.txt')))} batches"


def versus_min_rounds_phrase():
    rounds = [r["rounds"] for run in ("run1", "run2") for path in glob.glob(os.path.join(ENCODE_VERSUS, run, "*.txt"))
              for r in read_versus(path)[1].values()]
    return f"at least {min(rounds)} rounds each"
