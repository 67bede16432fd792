"""results/README.md from "Format 3" to the end: the three format-2 reference sets (`paper-cfebb2c`,
`paper-sibenik-cfebb2c`, `accuracy-cost-960x540-cfebb2c`), the binary -> wide comparison, the
pixel-against-shuffled baselines, and the overview table's rows for those sets. Every figure is read
from the sets' cells.json / meta.json (the per-cell records `raysort run` writes)."""
import csv
import json
import os
import statistics

from gpu_model_validate import mae, pearson, spearman

from . import gpu_model, paper_tex
from .sets import (ACCURACY_COST, BASELINES, FORMAT3_WIDE, PAPER_CFEBB2C, PAPER_COLUMN, PAPER_ORDER, PAPER_SIBENIK,
                   PAPER_SPEEDUPS, ROOT)

# The paper's encoders in its tables' order, as the README's per-table rows list them.
PAPER_ENCODERS = ["hcc", "mlhcc", "grid", "twopoint", "aila", "reis", "origin", "ppc"]
# Format 3's rows: every encoder of the paper preset.
FORMAT3_ENCODERS = ["hcc", "mlhcc", "hcc-dir", "grid", "twopoint", "aila", "reis", "origin", "costa", "ppc"]


def cells(set_dir):
    """(scene, batch, encoder, bits, access, variant, top_bits, baseline) -> the cell's record, ok cells only.
    NoSort has bits 0 and one record per baseline (its access is gather)."""
    with open(os.path.join(set_dir, "cells.json")) as f:
        return {(c["scene"], c["batch"], c["encoder"], c["bits"], c["access"], c.get("variant", "robust"),
                 c.get("top_bits", 0), c.get("baseline", "pixel")): c for c in json.load(f) if c["status"] == "ok"}


def cell(c, scene, batch, encoder, bits=32, access="permute", variant="robust", top_bits=0, baseline="pixel"):
    if encoder == "nosort":
        bits, access, top_bits = 0, "gather", 0
    return c[(scene, batch, encoder, bits, access, variant, top_bits, baseline)]


def meta(set_dir):
    with open(os.path.join(set_dir, "meta.json")) as f:
        return json.load(f)


def contains_one(iv):
    return iv["lo"] <= 1.0 <= iv["hi"]


def interval(iv, fmt="{:.2f}"):
    """`1.29 [1.20, 1.39]`, in italics when the interval contains 1 (no effect measurable)."""
    text = f"{fmt.format(iv['value'])} [{fmt.format(iv['lo'])}, {fmt.format(iv['hi'])}]"
    return f"*{text}*" if contains_one(iv) else text


def span(values, fmt="{:.2f}", sep="–"):
    return f"{fmt.format(min(values))}{sep}{fmt.format(max(values))}"


def ms(c, part):
    return c[f"{part}_ms"]["median"]


# --- the overview table (the top of results/README.md) -------------------------------------------

OVERVIEW = [(PAPER_CFEBB2C, "`raysort run --preset paper` (then 1 spp: today's `--preset paper-1spp`)"),
            (PAPER_SIBENIK, "`raysort run --preset paper --scenes sibenik` (1 spp, as above)"),
            (ACCURACY_COST, "see below")]


def overview_block():
    """Cells, A/A calibration and interval widths of the three reference sets, from their meta.json."""
    out = ["| set | command | cells | A/A intervals containing 1 | speedup half-width, median / 90th pct. |",
           "|---|---|---:|---:|---:|"]
    for d, command in OVERVIEW:
        name, n = os.path.basename(d), meta(d)["noise"]
        with open(os.path.join(d, "cells.json")) as f:
            count = len(json.load(f))
        hw = n["speedup_half_width"]
        link = f"{os.path.relpath(d, os.path.join(ROOT, 'results'))}/tables.md"
        out.append(f"| [`{name}`]({link}) | {command} | {count} | {n['aa_containing_one']} of {n['aa_intervals']} "
                   f"({100 * n['aa_coverage']:.1f} %) | {100 * hw['median']:.1f} % / {100 * hw['p90']:.1f} % |")
    return "\n".join(out)


# --- Format 3: binary -> wide (paper-cfebb2c's binary trails, the 1-spp set's wide ones) ---------------

def _format3():
    binary, wide = cells(PAPER_CFEBB2C), cells(FORMAT3_WIDE)
    scenes = meta(PAPER_CFEBB2C)["matrix"]["scenes"]
    return binary, wide, scenes


def format3_nosort_block():
    binary, wide, scenes = _format3()
    out = ["| NoSort | " + " | ".join(scenes) + " |", "|---|" + "---:|" * len(scenes)]
    for field, label in (("simt_lane_efficiency", "lane efficiency"),
                         ("simt_distinct_per_visit", "distinct nodes per visit")):
        out.append(f"| {label}, binary → wide | " + " | ".join(
            f"{cell(binary, s, 'bounce1', 'nosort')[field]:.3f} → {cell(wide, s, 'bounce1', 'nosort')[field]:.3f}"
            for s in scenes) + " |")
    return "\n".join(out)


def format3_encoders_block():
    binary, wide, scenes = _format3()
    out = ["| encoder | " + " | ".join(scenes) + " |", "|---|" + "---:|" * len(scenes)]
    for e in FORMAT3_ENCODERS:
        row = []
        for s in scenes:
            b, w = cell(binary, s, "bounce1", e, access="gather"), cell(wide, s, "bounce1", e, access="gather")
            row.append(f"{b['simt_lane_efficiency_ratio']:.2f}→{w['simt_lane_efficiency_ratio']:.2f} · "
                       f"{b['simt_distinct_per_visit_ratio']:.2f}→{w['simt_distinct_per_visit_ratio']:.2f}")
        out.append(f"| {e} | " + " | ".join(row) + " |")
    return "\n".join(out)


def format3_summary_block():
    binary, wide, scenes = _format3()
    lane, dist, same = [], [], 0
    for s in scenes:
        pairs = [(cell(binary, s, "bounce1", e, access="gather"), cell(wide, s, "bounce1", e, access="gather"))
                 for e in FORMAT3_ENCODERS]
        lane += [w["simt_lane_efficiency_ratio"] / b["simt_lane_efficiency_ratio"] for b, w in pairs]
        dist += [w["simt_distinct_per_visit_ratio"] / b["simt_distinct_per_visit_ratio"] for b, w in pairs]
        best_b = max(zip(pairs, FORMAT3_ENCODERS), key=lambda p: p[0][0]["simt_lane_efficiency_ratio"])[1]
        best_w = max(zip(pairs, FORMAT3_ENCODERS), key=lambda p: p[0][1]["simt_lane_efficiency_ratio"])[1]
        same += best_b == best_w
    return (f"Over the {len(lane)} encoder cells, wide/binary: lane-efficiency ratio median {statistics.median(lane):.3f} "
            f"(range {span(lane, '{:.3f}')}); distinct-nodes ratio median {statistics.median(dist):.3f} "
            f"(range {span(dist, '{:.3f}')}).\n"
            f"Best encoder by lane-efficiency ratio is the same on both layouts in {same} of {len(scenes)} scenes.")


def paper_speedups(table):
    """(scene, encoder) -> the paper's speedup at 32 bits (results/gpu-model/paper_tables.csv)."""
    with open(PAPER_SPEEDUPS, newline="") as f:
        return {(r["scene"], r["encoder"]): float(r["paper_speedup"]) for r in csv.DictReader(f)
                if r["table"] == table and r["bits"] == "32"}


def format3_correlation_phrase():
    """Table 2's 40 cells: the paper's speedup against each layout's two SIMT ratios."""
    binary, wide, _ = _format3()
    paper = paper_speedups("2")
    keys = sorted(paper)
    truth = [paper[k] for k in keys]
    figures = {}
    for name, c in (("binary", binary), ("wide", wide)):
        rows = [cell(c, s, "bounce1", e, access="gather") for s, e in keys]
        figures[name] = ([r["simt_lane_efficiency_ratio"] for r in rows],
                         [1 / r["simt_distinct_per_visit_ratio"] for r in rows])
    f = lambda stat, i: ", ".join(f"{n} {stat(figures[n][i], truth):.2f}" for n in ("binary", "wide"))  # noqa: E731
    return (f"Table 2 speedups (the {len(keys)} cells of {len({e for _, e in keys})} encoders × {len({s for s, _ in keys})} "
            f"scene analogs): Pearson {f(pearson, 0)}; Spearman {f(spearman, 0)}; 1 / distinct-nodes ratio: "
            f"Pearson {f(pearson, 1)}; Spearman {f(spearman, 1)}")


# --- Pixel against shuffled baseline (baselines-bounce1-6c6ecfe, wide BVH) ------------------------

BASELINE_SCENES = ["sibenik", "breakfast_room"]
BASELINE_ENCODERS = ["origin", "hcc", "mlhcc", "twopoint", "ppc"]


def _noise(d):
    n = meta(d)["noise"]
    return n, n["speedup_half_width"]


def baselines_cells_phrase():
    with open(os.path.join(BASELINES, "cells.json")) as f:
        return f"{len(json.load(f))} cells"


def baselines_noise_phrase():
    n, hw = _noise(BASELINES)
    return (f"speedup half-width median {100 * hw['median']:.1f} %, 90th percentile {100 * hw['p90']:.1f} %; "
            f"{n['aa_containing_one']} of {n['aa_intervals']} A/A intervals contain 1")


def baselines_block():
    """Model (lane-efficiency ratio · distinct-nodes ratio) and PoCL gather speedup against each baseline."""
    c = cells(BASELINES)
    cols = [(s, b) for s in BASELINE_SCENES for b in ("pixel", "shuffled")]
    out = ["| encoder | " + " | ".join(f"{s} vs {b}" for s, b in cols) + " |", "|---|" + "---:|" * len(cols)]
    nosort = [cell(c, s, "bounce1", "nosort", baseline=b) for s, b in cols]
    out.append("| NoSort (LE · DNV, MRays/s) | " + " | ".join(
        f"{n['simt_lane_efficiency']:.3f} · {n['simt_distinct_per_visit']:.3f}, {n['trace_mrays']:.2f}" for n in nosort) + " |")
    for e in BASELINE_ENCODERS:
        row = [cell(c, s, "bounce1", e, access="gather", baseline=b) for s, b in cols]
        out.append(f"| {e} | " + " | ".join(
            f"{r['simt_lane_efficiency_ratio']:.2f} · {r['simt_distinct_per_visit_ratio']:.2f}, "
            f"{interval(r['speedup'], '{:.3f}')}" for r in row) + " |")
    return "\n".join(out)


def _ratios(c, scene, encoder, baseline):
    r = cell(c, scene, "bounce1", encoder, access="gather", baseline=baseline)
    return r["simt_lane_efficiency_ratio"], r["simt_distinct_per_visit_ratio"]


def baselines_shuffle_phrase():
    """What the shuffle does to NoSort's distinct nodes and to the encoders' ratios."""
    c = cells(BASELINES)
    more = [cell(c, s, "bounce1", "nosort", baseline="shuffled")["simt_distinct_per_visit"]
            / cell(c, s, "bounce1", "nosort")["simt_distinct_per_visit"] for s in BASELINE_SCENES]
    d = lambda s, e, b: f"{_ratios(c, s, e, b)[1]:.2f}"  # noqa: E731
    lane = lambda s, e, b: f"{_ratios(c, s, e, b)[0]:.2f}"  # noqa: E731
    return (f"the NoSort warps fetch {span(more, '{:.1f}')}× more distinct nodes per visit, and every encoder's "
            f"distinct-nodes ratio drops accordingly (sibenik HCC {d('sibenik', 'hcc', 'pixel')} → "
            f"{d('sibenik', 'hcc', 'shuffled')}, PPC {d('sibenik', 'ppc', 'pixel')} → {d('sibenik', 'ppc', 'shuffled')}); "
            f"on breakfast_room the lane-efficiency ratios rise too (HCC {lane('breakfast_room', 'hcc', 'pixel')} → "
            f"{lane('breakfast_room', 'hcc', 'shuffled')})")


def baselines_origin_phrase():
    c = cells(BASELINES)
    f = lambda s, b: " · ".join(f"{v:.2f}" for v in _ratios(c, s, "origin", b))  # noqa: E731
    return (f"({f('sibenik', 'pixel')}), recovers {f('sibenik', 'shuffled')} on sibenik and "
            f"{f('breakfast_room', 'shuffled')} on breakfast_room")


# --- The paper's tables against paper-cfebb2c ---------------------------------------------------------

TABLE_BATCH = {"2": "bounce1", "3": "shadow0"}


def _paper_table(table):
    """Per encoder and stand-in: paper speedup · lane ratio · distinct ratio · gather · permute speedup."""
    c, paper, batch = cells(PAPER_CFEBB2C), paper_speedups(table), TABLE_BATCH[table]
    out = ["| encoder | " + " | ".join(f"{s} ({PAPER_COLUMN[s]})" for s in PAPER_ORDER) + " |",
           "|---|" + "---:|" * len(PAPER_ORDER)]
    for e in PAPER_ENCODERS:
        row = []
        for s in PAPER_ORDER:
            g, p = cell(c, s, batch, e, access="gather"), cell(c, s, batch, e)
            row.append(f"{paper[(s, e)]:.2f} · {g['simt_lane_efficiency_ratio']:.2f} · "
                       f"{g['simt_distinct_per_visit_ratio']:.2f} · {interval(g['speedup'])} · {interval(p['speedup'])}")
        out.append(f"| {e} | " + " | ".join(row) + " |")
    return "\n".join(out)


def paper_table2_block():
    return _paper_table("2")


def paper_table3_block():
    return _paper_table("3")


def _paired(table):
    """The paper's speedups and the set's figures over a table's 40 cells."""
    c, paper, batch = cells(PAPER_CFEBB2C), paper_speedups(table), TABLE_BATCH[table]
    keys = sorted(paper)
    gather = [cell(c, s, batch, e, access="gather") for s, e in keys]
    return ([paper[k] for k in keys], [g["speedup"]["value"] for g in gather],
            [cell(c, s, batch, e)["speedup"]["value"] for s, e in keys],
            [g["simt_lane_efficiency_ratio"] for g in gather], [1 / g["simt_distinct_per_visit_ratio"] for g in gather])


def _signed(v):
    return f"{v:.2f}".replace("-", "−")


def paper_correlation_block():
    out = ["| | PoCL gather | PoCL permute | SIMT lane efficiency | SIMT 1 / distinct nodes |", "|---|---:|---:|---:|---:|"]
    for table, label in (("2", "Table 2 (bounce1)"), ("3", "Table 3 (shadow0)")):
        truth, *figures = _paired(table)
        out.append(f"| {label} | " + " | ".join(_signed(pearson(f, truth)) for f in figures) + " |")
    return "\n".join(out)


def paper_spearman_phrase():
    s = {t: _paired(t) for t in TABLE_BATCH}
    f = lambda i: " and ".join(_signed(spearman(s[t][i], s[t][0])) for t in TABLE_BATCH)  # noqa: E731
    return f"Spearman: gather {f(1)}, permute {f(2)}"


def gpu_model_loso_phrase():
    """The GPU model's leave-one-scene-out score on Table 2 (results/gpu-model/cells.csv, its README's table)."""
    with open(gpu_model.CELLS, newline="") as f:
        rows = [r for r in csv.DictReader(f) if r["table"] == "2"]
    pred, truth = [float(r["predicted_loso"]) for r in rows], [float(r["paper_speedup"]) for r in rows]
    return f"leave-one-scene-out Spearman {spearman(pred, truth):.2f}, MAE {mae(pred, truth):.3f} on Table 2"


GATHER_PERMUTE_ENCODERS = ["origin", "aila", "twopoint", "grid", "hcc", "mlhcc", "ppc"]


def _gather_permute(scene):
    """Bounce1 at 32 bits: both access modes' trace and speedups, the permute kernel, encode + sort, net."""
    c = cells(PAPER_CFEBB2C)
    out = [f"| {scene} | trace ms | speedup gather | speedup permute | permute ms (% of trace) | encode + sort ms | "
           "net gather | net permute |", "|---|---|---:|---:|---:|---:|---:|---:|"]
    for e in GATHER_PERMUTE_ENCODERS:
        g, p = cell(c, scene, "bounce1", e, access="gather"), cell(c, scene, "bounce1", e)
        out.append(f"| {e} | {ms(g, 'trace'):.0f} / {ms(p, 'trace'):.0f} ({ms(g, 'nosort_trace'):.0f}) | "
                   f"{interval(g['speedup'])} | {interval(p['speedup'])} | "
                   f"{ms(p, 'permute'):.1f} ({100 * ms(p, 'permute') / ms(p, 'trace'):.1f} %) | "
                   f"{ms(p, 'encode'):.1f} + {ms(p, 'sort'):.1f} | {interval(g['net_speedup'])} | "
                   f"{interval(p['net_speedup'])} |")
    return "\n".join(out)


def gather_permute_sibenik_block():
    return _gather_permute("sibenik")


def gather_permute_breakfast_block():
    return _gather_permute("breakfast_room")


def gather_permute_phrase():
    """The permute kernel's share of a trace and what it buys over gather (the ratio of the two speedups)."""
    c = cells(PAPER_CFEBB2C)
    share, gain = [], []
    for s in ("sibenik", "breakfast_room"):
        for e in GATHER_PERMUTE_ENCODERS:
            g, p = cell(c, s, "bounce1", e, access="gather"), cell(c, s, "bounce1", e)
            share.append(100 * ms(p, "permute") / ms(p, "trace"))
            gain.append(100 * (p["speedup"]["value"] / g["speedup"]["value"] - 1))
    return f"costs {span(share, '{:.0f}')} % of a trace and buys {span(gain, '{:.0f}')} % over gather"


def _printed(table):
    return {(r["row"], r["column"]): r["value"] for r in paper_tex.printed() if r["table"] == table}


TABLE5_ENCODERS = ["hcc", "mlhcc", "twopoint", "ppc", "origin", "grid"]  # the paper's four, then two it lacks


def table5_block():
    """Overhead on breakfast_room, bounce1, 32 bits: the paper's encode + sort beside ours (the gather cell's
    share of its trace), the permute kernel and both net speedups."""
    c, paper = cells(PAPER_CFEBB2C), _printed("5")
    out = ["| encoder | paper encode + sort ms (% of trace) | ours encode + sort ms (% of trace) | ours permute ms | "
           "net speedup gather | net speedup permute |", "|---|---|---|---:|---:|---:|"]
    for e in TABLE5_ENCODERS:
        row = "mlhcc32" if e == "mlhcc" else e
        p = (f"{paper[(row, 'encode ms')]} + {paper[(row, 'sort ms')]} ({float(paper[(row, 'percentage')]):.1f} %)"
             if (row, "encode ms") in paper else "–")
        g, q = cell(c, "breakfast_room", "bounce1", e, access="gather"), cell(c, "breakfast_room", "bounce1", e)
        out.append(f"| {e} | {p} | {ms(g, 'encode'):.1f} + {ms(g, 'sort'):.1f} ({g['overhead_pct']['value']:.1f} %) | "
                   f"{ms(q, 'permute'):.1f} | {interval(g['net_speedup'])} | {interval(q['net_speedup'])} |")
    return "\n".join(out)


KEY_LENGTH_ENCODERS = ["hcc", "mlhcc", "twopoint", "ppc", "grid", "origin"]
KEY_LENGTHS = (16, 32, 64)


def key_length_block():
    """Sibenik, bounce1, permute: speedup (ANC, lane ratio) per key length, and the paper's Table 7 ANC."""
    c, paper = cells(PAPER_CFEBB2C), _printed("7")
    out = ["| encoder | 16 bits | 32 bits | 64 bits | paper ANC 16/32/64 |", "|---|---|---|---|---|"]
    for e in KEY_LENGTH_ENCODERS:
        row = [cell(c, "sibenik", "bounce1", e, bits=b) for b in KEY_LENGTHS]
        anc = "/".join(paper[(e, str(b))] for b in KEY_LENGTHS) if (e, "16") in paper else "–"
        out.append(f"| {e} | " + " | ".join(f"{interval(r['speedup'])} ({r['anc']:.2f}, {r['simt_lane_efficiency_ratio']:.2f})"
                                             for r in row) + f" | {anc} |")
    return "\n".join(out)


# --- "Which of the paper's conclusions survive their intervals on PoCL": the figures the bullets quote ---

INTERIORS = ["sibenik", "grey_white_room", "multi-instance-real", "breakfast_room"]  # the real interiors
PATH_KEYS = ["hcc", "mlhcc", "ppc", "twopoint"]


def _sp(scene, batch, encoder, bits=32, access="permute", field="speedup"):
    return cell(cells(PAPER_CFEBB2C), scene, batch, encoder, bits=bits, access=access)[field]


def survive_secondary_phrase():
    """Bounce1, permute: the speedup range over the real interiors, and the cells whose interval reaches 1."""
    values = [_sp(s, "bounce1", e)["value"] for s in INTERIORS for e in PAPER_ENCODERS]
    reach = [f"{e} on {s}" for s in PAPER_ORDER for e in PAPER_ENCODERS if _sp(s, "bounce1", e)["lo"] <= 1.0]
    return (f"{span(values, '{:.1f}')}× in every real interior, every encoder (bounce1, permute: every interval above 1"
            + (f" except {', '.join(reach)}" if reach else "") + ")")


def survive_path_keys_phrase():
    """Per interior: the path keys' permute range against Origin's."""
    parts = []
    for s in INTERIORS:
        keys = [_sp(s, "bounce1", e)["value"] for e in PATH_KEYS]
        parts.append(f"{PAPER_COLUMN[s] if s != 'sibenik' else 'sibenik'} ({span(keys)} vs "
                     f"{_sp(s, 'bounce1', 'origin')['value']:.2f})")
    return ", ".join(parts[:-1]) + " and " + parts[-1]


def survive_cut_grid_phrase():
    f = lambda s, e: _sp(s, "bounce1", e)["value"]  # noqa: E731
    return (f"Living room (HCC {interval(_sp('grey_white_room', 'bounce1', 'hcc'))} vs grid "
            f"{interval(_sp('grey_white_room', 'bounce1', 'grid'))}), MultiInstance ({f('multi-instance-real', 'hcc'):.2f} "
            f"vs {f('multi-instance-real', 'grid'):.2f}) and landscape ({f('landscape', 'hcc'):.2f} vs {f('landscape', 'grid'):.2f})")


def survive_bits_phrase():
    return (f"HCC on sibenik {interval(_sp('sibenik', 'bounce1', 'hcc', bits=16))} at 16 bits against "
            f"{interval(_sp('sibenik', 'bounce1', 'hcc'))} at 32")


def survive_ppc_phrase():
    nets = [_sp(s, "bounce1", "ppc", access=a, field="net_speedup")["value"]
            for s in ("sibenik", "breakfast_room") for a in ("gather", "permute")]
    encode = [ms(cell(cells(PAPER_CFEBB2C), s, "bounce1", "ppc"), "encode") for s in ("sibenik", "breakfast_room")]
    return f"net {span(nets)} on bounce1 with either access mode (its encode is a trace of its own, {span(encode, '{:.0f}')} ms here)"


def survive_anc_phrase():
    paper = _printed("7")
    f = lambda e: "/".join(f"{_sp('sibenik', 'bounce1', e, bits=b, field='anc'):.2f}" for b in KEY_LENGTHS)  # noqa: E731
    p = lambda e: "/".join(paper[(e, str(b))] for b in KEY_LENGTHS)  # noqa: E731
    return f"HCC {f('hcc')} (paper {p('hcc')}), MLHCC {f('mlhcc')} ({p('mlhcc')}), PPC {f('ppc')} ({p('ppc')})"


def differ_shadow_phrase():
    sp = lambda s, e: interval(_sp(s, "shadow0", e))  # noqa: E731
    return (f"On Breakfast shadow0 Aila {sp('breakfast_room', 'aila')} is just above HCC {sp('breakfast_room', 'hcc')} "
            f"and TwoPoint {sp('breakfast_room', 'twopoint')} touches it; on sibenik TwoPoint {sp('sibenik', 'twopoint')}, "
            f"Aila {sp('sibenik', 'aila')} and HCC {sp('sibenik', 'hcc')} overlap")


def differ_mlhcc_phrase():
    return f"sibenik {interval(_sp('sibenik', 'bounce1', 'mlhcc'))} vs {interval(_sp('sibenik', 'bounce1', 'hcc'))}"


def differ_mlhcc_model_phrase():
    lane = lambda e: _sp("sibenik", "bounce1", e, access="gather", field="simt_lane_efficiency_ratio")  # noqa: E731
    return f"{lane('mlhcc'):.2f} vs {lane('hcc'):.2f}"


def differ_net_phrase():
    net = lambda e, a: _sp("breakfast_room", "bounce1", e, access=a, field="net_speedup")  # noqa: E731
    gather = [net(e, "gather")["value"] for e in GATHER_PERMUTE_ENCODERS]
    four = [net(e, "permute")["value"] for e in ("hcc", "mlhcc", "twopoint", "aila")]
    return (f"on Breakfast (net {span(gather)}), with permute most do ({span(four)} for HCC, MLHCC, TwoPoint, Aila; "
            f"Origin's and the grid's intervals reach 1; PPC {net('ppc', 'permute')['value']:.2f})")


def differ_shadow_size_phrase():
    return f"PoCL's stay at {span([_sp(s, 'shadow0', e)['value'] for s in PAPER_ORDER for e in PAPER_ENCODERS])} with permute"


def differ_shadow_lane_phrase():
    lane = [_sp(s, "shadow0", e, access="gather", field="simt_lane_efficiency_ratio") for s in PAPER_ORDER for e in PAPER_ENCODERS]
    return f"up to {max(lane):.2f}"


def differ_multi_instance_phrase():
    ppc = lambda f, a="permute": _sp("multi-instance-real", "bounce1", "ppc", access=a, field=f)  # noqa: E731
    return f"{ppc('speedup')['value']:.2f}, SIMT {ppc('simt_lane_efficiency_ratio', 'gather'):.2f}"


def differ_landscape_phrase():
    return f"{span([_sp('landscape', 'bounce1', e)['value'] for e in PAPER_ENCODERS])} with permute"


# --- The paper preset on sibenik: paper-sibenik-cfebb2c ---------------------------------------------------

SIBENIK_ENCODERS = ["origin", "reis", "costa", "aila", "twopoint", "grid", "hcc", "mlhcc", "ppc", "hcc-dir"]


def _all_cells(d):
    with open(os.path.join(d, "cells.json")) as f:
        return json.load(f)


def sibenik_cells_phrase():
    every = _all_cells(PAPER_SIBENIK)
    sorted_cells = [c for c in every if c["encoder"] != "nosort"]
    failed = sum(c["status"] != "ok" for c in every)
    return (f"{len(every)} cells ({len({c['encoder'] for c in sorted_cells})} encoders × "
            f"{'/'.join(str(b) for b in sorted({c['bits'] for c in sorted_cells}))} bits × "
            f"{len({c['access'] for c in sorted_cells})} access modes × {', '.join(sorted({c['batch'] for c in every}))}, "
            f"and the {len(every) - len(sorted_cells)} NoSort cells), {failed} failed")


def sibenik_noise_phrase():
    n, hw = _noise(PAPER_SIBENIK)
    return (f"{n['aa_containing_one']} of {n['aa_intervals']} A/A intervals contain 1.00; the speedup intervals' "
            f"half-width has a median of {100 * hw['median']:.1f} % (90th percentile {100 * hw['p90']:.1f} %); every "
            f"cell ran {n['rounds']['min']}–{n['rounds']['max']} rounds")


def sibenik_block():
    c = cells(PAPER_SIBENIK)
    out = ["| encoder | bounce1 gather | bounce1 permute | net gather | net permute | shadow0 gather | shadow0 permute | "
           "net gather | net permute |", "|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for e in SIBENIK_ENCODERS:
        row = []
        for b in ("bounce1", "shadow0"):
            g, p = cell(c, "sibenik", b, e, access="gather"), cell(c, "sibenik", b, e)
            row += [interval(g["speedup"]), interval(p["speedup"]), interval(g["net_speedup"]), interval(p["net_speedup"])]
        out.append(f"| {e} | " + " | ".join(row) + " |")
    return "\n".join(out)


def sibenik_shadow_phrase():
    """Shadow0 on sibenik: the net range, the NoSort trace and what encode + sort + permute cost."""
    c = cells(PAPER_SIBENIK)
    nets = [cell(c, "sibenik", "shadow0", e, access=a)["net_speedup"]["value"] for e in SIBENIK_ENCODERS
            for a in ("gather", "permute")]
    nosort = cell(c, "sibenik", "shadow0", "nosort")
    cost = {e: sum(ms(cell(c, "sibenik", "shadow0", e), part) for part in ("encode", "sort", "permute"))
            for e in SIBENIK_ENCODERS}
    others = [v for e, v in cost.items() if e != "ppc"]
    return (f"(net {span(nets)}): a {nosort['rays'] / 1e6:.1f} M-ray shadow batch traces in ~{ms(nosort, 'trace'):.0f} ms, "
            f"and encode + sort + permute cost {span(others, '{:.0f}')} ms of it (PPC: {cost['ppc']:.0f} ms)")


# --- What accuracy costs in time: accuracy-cost-960x540-cfebb2c (robust variant, bounce1) ---------------

ACCURACY_ENCODERS = ["hcc", "mlhcc", "twopoint", "ppc", "origin"]
ACCURACY_COLUMNS = [(16, 0, "16 bits"), (32, 0, "32 bits"), (64, 0, "64 bits"), (64, 8, "top-8 of 64")]


def accuracy_cells_phrase():
    every = _all_cells(ACCURACY_COST)
    return f"{len(every)} cells, {sum(c['status'] != 'ok' for c in every)} failed"


def _value(iv):
    """A figure without its interval, in italics when the interval contains 1."""
    return f"*{iv['value']:.2f}*" if contains_one(iv) else f"{iv['value']:.2f}"


def _accuracy(scene, encoder, bits, top_bits=0):
    c = cells(ACCURACY_COST)
    return (cell(c, scene, "bounce1", encoder, bits=bits, access="gather", top_bits=top_bits),
            cell(c, scene, "bounce1", encoder, bits=bits, top_bits=top_bits))


def _accuracy_block(scene):
    """encode + sort ms → ANC, SIMT lane-efficiency ratio; speedup gather / permute; net speedup permute."""
    out = [f"| {scene} | " + " | ".join(label for _, _, label in ACCURACY_COLUMNS) + " |",
           "|---|" + "---|" * len(ACCURACY_COLUMNS)]
    for e in ACCURACY_ENCODERS:
        row = []
        for bits, top, _ in ACCURACY_COLUMNS:
            g, p = _accuracy(scene, e, bits, top)
            row.append(f"{ms(p, 'encode'):.1f}+{ms(p, 'sort'):.1f} → {p['anc']:.2f}, {p['simt_lane_efficiency_ratio']:.2f}; "
                       f"{_value(g['speedup'])} / {_value(p['speedup'])}; {_value(p['net_speedup'])}")
        out.append(f"| {e} | " + " | ".join(row) + " |")
    return "\n".join(out)


def accuracy_sibenik_block():
    return _accuracy_block("sibenik")


def accuracy_breakfast_block():
    return _accuracy_block("breakfast_room")


def accuracy_bits_phrase():
    """How encode, sort and the lane ratio move with the key length (HCC)."""
    s = {b: _accuracy("sibenik", "hcc", b)[1] for b in KEY_LENGTHS}
    br = {b: _accuracy("breakfast_room", "hcc", b)[1] for b in KEY_LENGTHS}
    sort = " → ".join(f"{ms(s[b], 'sort'):.1f}" for b in KEY_LENGTHS)
    lane = " → ".join(f"{br[b]['simt_lane_efficiency_ratio']:.2f}" for b in KEY_LENGTHS)
    return (f"the cut codes' encode grows with the bits (HCC {ms(s[16], 'encode'):.1f} → {ms(s[64], 'encode'):.1f} ms on "
            f"sibenik), so does the sort ({sort} ms), and the modelled warp efficiency rises (breakfast HCC {lane})")


def accuracy_permute_phrase():
    """Sibenik, permute: HCC's speedup per key length, and MLHCC's net at 16 and 64 bits."""
    hcc = " / ".join(f"{_accuracy('sibenik', 'hcc', b)[1]['speedup']['value']:.2f}" for b in KEY_LENGTHS)
    net = {b: interval(_accuracy("sibenik", "mlhcc", b)[1]["net_speedup"]) for b in (16, 64)}
    return (f"(sibenik HCC {hcc}, intervals overlapping), so the cheapest key wins net: 16-bit MLHCC nets {net[16]} on "
            f"sibenik, 64-bit {net[64]}")


def accuracy_top_bits_phrase():
    """Sibenik HCC: sorting 64-bit keys by their top 8 bits against the whole key."""
    whole, top = _accuracy("sibenik", "hcc", 64)[1], _accuracy("sibenik", "hcc", 64, 8)[1]
    return (f"cuts the sort from {ms(whole, 'sort'):.1f} to {ms(top, 'sort'):.1f} ms (sibenik HCC) but the speedup falls "
            f"from {whole['speedup']['value']:.2f} to {top['speedup']['value']:.2f} and the SIMT ratio to "
            f"{top['simt_lane_efficiency_ratio']:.2f}")


def _nosort(scene, batch, variant):
    return cell(cells(ACCURACY_COST), scene, batch, "nosort", variant=variant)


def accuracy_variants_phrase():
    """The NoSort cells of the two variants (different times, so no interval): speed ratio robust / fast."""
    r = lambda s: _nosort(s, "bounce1", "robust")["trace_mrays"] / _nosort(s, "bounce1", "fast")["trace_mrays"]  # noqa: E731
    return f"sibenik bounce1 robust/fast speed {r('sibenik'):.2f}, breakfast_room {r('breakfast_room'):.2f}"


def accuracy_leaks_phrase():
    """Rays per million that a variant's NoSort shadow trace leaks (its hits differ from the reference's)."""
    leaks = lambda v: [_nosort(s, "shadow0", v)["leaks_per_million"] for s in ("sibenik", "breakfast_room")]  # noqa: E731
    fast = "leaked no ray" if not any(leaks("fast")) else "leaked " + " and ".join(f"{x:.1f}" for x in leaks("fast"))
    return (f"The fast variant {fast} on these batches; robust differs on "
            f"{' and '.join(f'{x:.1f}' for x in leaks('robust'))} rays per million shadow rays")
