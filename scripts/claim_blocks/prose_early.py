"""results/README.md from its start to "Beyond the paper" and docs/paper.md: the figures quoted in the
prose around the tables (issue 43, item 1), and the cost figures (cells, wall clocks, peak memory, A/A
counts) where a committed file holds them: a set's meta.json ("noise"), cells.csv, its `/usr/bin/time`
log (run-time.txt) or, where that is the only record of a run, the set's own README.md."""
import csv
import functools
import json
import os
import re
import statistics

import gpu_model_validate as validate
from paper_correlation import correlations
from spp_compare import gpu, load

from . import appendix, audit, gpu_model_scoring, paper_tex, sampling
from .sets import (AUDIT_ENCODEBENCH, AUDIT_ORDER, AUDIT_TWOPOINT_BITS, AUDIT_TWOPOINT_VARIANTS, BOUNCES, CLASSES,
                   EIGHT_SPP, EIGHT_SPP_EARLIER, EIGHT_SPP_SHARDS, H200_VALIDATION, HCC_DIR, KERNEL_CLASSES_MODEL,
                   OCLGRIND, ONE_SPP, PACKET_SETUP, PAPER_COLUMN, ROOT, SHARED_ROUNDS, SWEEPS, VIEWPORT)


# --- readers -------------------------------------------------------------------------------------------

def _rows(set_dir):
    with open(os.path.join(set_dir, "cells.csv"), newline="") as f:
        return list(csv.DictReader(f))


def _noise(set_dir):
    with open(os.path.join(set_dir, "meta.json")) as f:
        return json.load(f)["noise"]


def _elapsed_s(log):
    """Wall-clock seconds of a run-time log: `/usr/bin/time -v`'s Elapsed line, bash's `real XmY.Zs`, or the
    `WALL [<arm>] <s> s` line of `/usr/bin/time -f "WALL ... %e s"` at the end of a run.log."""
    with open(log) as f:
        text = f.read()
    m = re.search(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): (?:(\d+):)?(\d+):([\d.]+)", text)
    if m:
        return int(m.group(1) or 0) * 3600 + int(m.group(2)) * 60 + float(m.group(3))
    m = re.search(r"real\s+(\d+)m([\d.]+)s", text)
    if m:
        return int(m.group(1)) * 60 + float(m.group(2))
    m = re.search(r"^WALL (?:\S+ )?([\d.]+) s\b", text, re.M)
    if m:
        return float(m.group(1))
    raise SystemExit(f"claims: {os.path.relpath(log, ROOT)} holds no wall clock (`/usr/bin/time -v` or `time`)")


def _peak_gib(log):
    with open(log) as f:
        kib = int(re.search(r"Maximum resident set size \(kbytes\): (\d+)", f.read()).group(1))
    return kib / 2**20


def duration(seconds, unit="s"):
    """'53 min 44 s', '54 s'; unit 'min': '3 h 27 min', '25 min' (rounded to the unit)."""
    if unit == "min":
        m = int(seconds / 60 + 0.5)
        return f"{m // 60} h {m % 60} min" if m >= 60 else f"{m} min"
    s = int(seconds + 0.5)
    return f"{s // 60} min {s % 60} s" if s >= 60 else f"{s} s"


def _run_time(set_dir):
    return _elapsed_s(os.path.join(set_dir, "run-time.txt"))


def _shard_logs():
    return [os.path.join(EIGHT_SPP_SHARDS, f"run-time-shard-{k}.txt") for k in range(1, 7)]


def _set_cost(set_dir):
    """'45 cells, 9 min 34 s': the set's cells and its run's wall clock."""
    return f"{len(_rows(set_dir))} cells, {duration(_run_time(set_dir))}"


# --- Tables 2 and 3 in the packet class ------------------------------------------------------------------

def packet_cost_phrase(set_dir=CLASSES):
    return f"{len(_rows(set_dir))} cells in {duration(_run_time(set_dir))}"


def packet_aa_phrase(set_dir=CLASSES):
    n = _noise(set_dir)
    return f"A/A {n['aa_containing_one']} of {n['aa_intervals']}"


def packet_setup_cost_phrase():
    return packet_cost_phrase(PACKET_SETUP)


def packet_setup_aa_phrase():
    return packet_aa_phrase(PACKET_SETUP)


@functools.lru_cache(maxsize=None)
def _correlation(set_dir=CLASSES):
    """(table, class) -> (Pearson, its 95 % interval's upper end, the SIMT ratio's Pearson, the Pearson with its
    interval as text), from scripts/paper_correlation.py (one access mode per class in these sets)."""
    return {(table, layout): (c["pearson"], c["hi"], c["simt_pearson"], f"{c['pearson']:.2f} [{c['lo']:.2f}, {c['hi']:.2f}]")
            for (table, layout, _access), c in correlations([set_dir]).items()}


BAR = 0.8  # issue 40's bar on the packet class's Pearson correlation with the paper, both tables


def packet_gap_phrase():
    c = _correlation()
    return "; ".join(f"Table {t}: {c[(t, 'packet16')][0]:.2f} against {c[(t, 'wide')][0]:.2f}" for t in "23")


def packet_simt_phrase():
    c = _correlation()
    return f"{c[('2', 'packet16')][2]:.2f} and {c[('3', 'packet16')][2]:.2f}"


def packet_bar_phrase():
    """The bar on the packet kernels as they are now (PACKET_SETUP), not on CLASSES' slower robust packets."""
    c = _correlation(PACKET_SETUP)
    met = [t for t in "23" if c[(t, "packet16")][0] >= BAR]
    short = [t for t in "23" if t not in met]
    text = "met on " + (" and ".join(f"Table {t}" for t in met) or "neither table")
    for t in short:
        text += f", not on Table {t} ({c[(t, 'packet16')][0]:.2f}, its interval reaching {c[(t, 'packet16')][1]:.2f})"
    return f"Issue 40's bar is {BAR} on both: {text}"


def packet_h200_phrase():
    """For scale: the real GPU (the H200's validation matrix, the 4-wide kernel, gather) against the paper,
    on the same 40 cells of each table, beside the packet class."""
    gpu, ours = _correlation(H200_VALIDATION), _correlation(PACKET_SETUP)
    return (f"an NVIDIA H200 running the 4-wide single-ray kernel on the same 40 cells of each table (gather, "
            f"`gpu-validation-12e32f2`) follows the paper's RTX 3060 at Pearson {gpu[('2', 'wide')][3]} on Table 2 and "
            f"{gpu[('3', 'wide')][3]} on Table 3, where the packet class on PoCL follows it at "
            f"{ours[('2', 'packet16')][3]} and {ours[('3', 'packet16')][3]}")


# --- What ordering buys as the kernel gets faster --------------------------------------------------------

def model_classes_stopped_phrase():
    """The cells the stopped run made, of those its command asked for (scenes × batches × orders × layouts)."""
    with open(os.path.join(KERNEL_CLASSES_MODEL, "meta.json")) as f:
        m = json.load(f)["matrix"]
    asked = len(m["scenes"]) * len(m["batches"]) * (len(m["encoders"]) + 1) * len(m["layout"].split(","))
    return f"{len(_rows(KERNEL_CLASSES_MODEL))} of its {asked} cells"


def model_classes_count_phrase():
    return f"{len(_rows(KERNEL_CLASSES_MODEL))} cells"


def model_classes_pocl_speed_phrase():
    """The PoCL trace speed the binary and compressed classes made on the way, MRays/s."""
    sp = [float(r["trace_mrays"]) for r in _rows(KERNEL_CLASSES_MODEL)
          if r["layout"] in ("binary", "binary-ww", "cwbvh") and r["trace_mrays"]]
    return f"{min(sp):.2f}–{max(sp):.2f} MRays/s"


# --- Shared rounds ----------------------------------------------------------------------------------------

def _shared_wall_clocks():
    """binary -> seconds, from the A/B set's README table (the only record of its runs' wall clocks)."""
    with open(os.path.join(SHARED_ROUNDS, "README.md")) as f:
        return {m.group(1): float(m.group(2)) for m in re.finditer(r"\| `\w+-(\w+)/` \| \w+ \|[^|]*\| ([\d.]+) s", f.read())}


SHARED_ARMS = ["unshared-e549fcc", "shared-f3a19f6", "shared-be9b74a"]  # the old rule first


def shared_share_phrase():
    w = _shared_wall_clocks()
    old = w[SHARED_ARMS[0].split("-")[1]]
    shares = [100 * w[a.split("-")[1]] / old for a in SHARED_ARMS[1:]]
    return f"{min(shares):.0f}-{max(shares):.0f} %"


def _shared_cells(arm):
    return {r["id"]: r for r in _rows(os.path.join(SHARED_ROUNDS, arm)) if r["status"] == "ok"}


def shared_rounds_phrase():
    """The A/B paragraph's figures: wall clocks, equal orders, speedup new / old, half-widths, A/A."""
    w = _shared_wall_clocks()
    old, new, final = (_shared_cells(a) for a in SHARED_ARMS)
    same = sum(old[i]["order_hash"] == new[i]["order_hash"] == final[i]["order_hash"] and
               old[i]["anc"] == new[i]["anc"] == final[i]["anc"] for i in old if i in new and i in final)
    ratio = lambda arm: statistics.median(float(arm[i]["speedup"]) / float(old[i]["speedup"])  # noqa: E731
                                          for i in old if i in arm and old[i]["speedup"] and arm[i]["speedup"])
    noise = [_noise(os.path.join(SHARED_ROUNDS, a)) for a in SHARED_ARMS]
    b = [a.split("-")[1] for a in SHARED_ARMS]
    return (f"({b[0]}, {w[b[0]]} s) and with up to 8 groups of a batch sharing one NoSort and one A/A trace per "
            f"round ({b[1]}, {w[b[1]]} s; with each group's own time budget, {b[2]}, {w[b[2]]} s), on a quiet "
            f"machine: the same {same} orders and ANCs, speedups new / old median {ratio(new):.3f} and "
            f"{ratio(final):.3f}, median half-width "
            + " / ".join(f"{100 * n['speedup_half_width']['median']:.2f} %" for n in noise)
            + ", A/A calibration " + " / ".join(f"{100 * n['aa_coverage']:.1f} %" for n in noise)
            + f" ({noise[2]['aa_containing_one']} of {noise[2]['aa_intervals']})")


# --- Oclgrind ---------------------------------------------------------------------------------------------

def oclgrind_cells_phrase():
    rows = _rows(OCLGRIND)
    return f"{len(rows)} cells"


def oclgrind_failed_phrase():
    return f"{sum(r['status'] != 'ok' for r in _rows(OCLGRIND))} failed cells"


def oclgrind_time_phrase():
    with open(os.path.join(OCLGRIND, "run-time.txt")) as f:
        return re.search(r"wall clock (\d+) s", f.read()).group(0).replace("wall clock ", "")


# --- The paper at its sampling ----------------------------------------------------------------------------

def _eight_spp_cost():
    """(summed wall clock s, peak GiB) of the six shards of the 8-spp set."""
    return sum(_elapsed_s(p) for p in _shard_logs()), max(_peak_gib(p) for p in _shard_logs())


def spp_sets_block():
    """The whole preset at both samplings: cells, failed, wall clock, peak RSS."""
    eight_s, eight_gib = _eight_spp_cost()
    rows8, rows1 = _rows(EIGHT_SPP), _rows(ONE_SPP)
    failed = lambda rows: sum(r["status"] != "ok" for r in rows)  # noqa: E731
    shards = len(_shard_logs())
    return "\n".join([
        "| set | command | cells | wall clock | peak RSS |", "|---|---|---:|---:|---:|",
        f"| [`paper-8spp-9dab0ed`](pocl-cpu-pthread-skylake-avx512-amd-epyc/paper-8spp-9dab0ed/README.md) (`merged/`) | "
        f"`bash scripts/paper-8spp.sh`, {NUMBER_WORDS[shards]} times: `raysort run --preset paper --shard K/{shards} …`, "
        f"then `raysort merge` | {len(rows8)}, {failed(rows8)} failed | {duration(eight_s, 'min')} "
        f"({NUMBER_WORDS[shards]} shards, summed) | {eight_gib:.1f} GiB |",
        f"| [`paper-1spp-9dab0ed`](pocl-cpu-pthread-skylake-avx512-amd-epyc/paper-1spp-9dab0ed/tables.md) | "
        f"`bash scripts/paper-8spp.sh companion`: `raysort run --preset paper-1spp …` | {len(rows1)}, {failed(rows1)} failed | "
        f"{duration(_run_time(ONE_SPP))} | {_peak_gib(os.path.join(ONE_SPP, 'run-time.txt')):.1f} GiB |"])


def _earlier_phrase(set_dir):
    return f"{_set_cost(set_dir)}, {_peak_gib(os.path.join(set_dir, 'run-time.txt')):.1f} GiB"


def spp_earlier_sibenik_phrase():
    return _earlier_phrase(EIGHT_SPP_EARLIER[0])


def spp_earlier_grey_phrase():
    return _earlier_phrase(EIGHT_SPP_EARLIER[1])


IDENTICAL = ["rays", "keys_hash", "order_hash", "anc", "simt_lane_efficiency_ratio"]


def spp_earlier_identical_phrase():
    """The cells the earlier 8-spp sets share with the whole one, and how many of their deterministic values agree."""
    merged = {r["id"]: r for r in _rows(EIGHT_SPP) if r["status"] == "ok"}
    shared = [(r, merged[r["id"]]) for d in EIGHT_SPP_EARLIER for r in _rows(d) if r["status"] == "ok" and r["id"] in merged]
    same = sum(a[f] == b[f] for a, b in shared for f in IDENTICAL)
    return (f"The {len(shared)} cells they share with `paper-8spp-9dab0ed` have identical rays, keys and order hashes, "
            f"ANC and SIMT lane-efficiency ratios ({same} of {len(shared) * len(IDENTICAL)} values)")


def spp_cost_ratio_phrase():
    eight_s, eight_gib = _eight_spp_cost()
    one_s, one_gib = _run_time(ONE_SPP), _peak_gib(os.path.join(ONE_SPP, "run-time.txt"))
    return (f"{eight_s / one_s:.1f}× the wall clock of the same {len(_rows(ONE_SPP))} cells at 1 spp "
            f"({duration(eight_s, 'min')} against {duration(one_s, 'min')}) and {eight_gib / one_gib:.1f}× the peak "
            f"memory ({eight_gib:.1f} against {one_gib:.1f} GiB")


QUIET_SHARDS = 3  # the last three shards ran alone (paper-8spp-9dab0ed/README.md)


def spp_shards_phrase():
    """The first shards' wall clocks beside other work, the last ones' alone, and the quiet estimate."""
    t = [_elapsed_s(p) / 60 for p in _shard_logs()]
    loud, quiet = t[:-QUIET_SHARDS], t[-QUIET_SHARDS:]
    return (f"took {int(min(loud) + 0.5)}–{int(max(loud) + 0.5)} min each; the last three ran alone in "
            f"{int(min(quiet) + 0.5)}–{int(max(quiet) + 0.5)} min for the same estimated cost, so on a quiet 2-core "
            f"machine the preset takes {paper_cost_quiet_phrase()}")


def spp_ppc_shadow_phrase():
    one, eight = sampling._sets()
    f = lambda s: (f"{one[(s, 'shadow0', 'ppc')]['simt_lane_efficiency_ratio']:.2f} to "  # noqa: E731
                   f"{eight[(s, 'shadow0', 'ppc')]['simt_lane_efficiency_ratio']:.2f}")
    return f"drops from {f('breakfast_room')} on Breakfast and from {f('jacksboro_terrain')} on jacksboro_terrain"


def spp_nosort_bounce_phrase():
    one, eight = sampling._sets()
    d = [abs(eight[k]["simt_lane_efficiency"] - one[k]["simt_lane_efficiency"]) for k in one
         if k[1] == "bounce1" and k[2] == "nosort" and k in eight]
    return f"moves by at most {max(d):.3f}"


def _loso_mae(set_dir):
    rows = gpu_model_scoring.scored("2", PAPER_COLUMN, gpu_model_scoring.model_cells(set_dir))
    pred, _ = validate.loso(rows, gpu_model_scoring.profile())
    return validate.mae(pred["model"], [r["paper"] for r in rows])


def spp_loso_one_phrase():
    return f"MAE {_loso_mae(ONE_SPP):.3f}"


def spp_loso_eight_phrase():
    return f"leave-one-scene-out MAE {_loso_mae(EIGHT_SPP):.3f}, against {_loso_mae(ONE_SPP):.3f} at 1 spp"


WORDS = ["none", "one", "two", "three", "four", "five"]


def spp_overshoot_phrase():
    """Table 2's scenes where the 8-spp predictions are further from the paper than the 1-spp ones, and by how
    much they miss there on average."""
    rows = sampling._model_rows("2")
    worse = []
    for scene in sorted({r[0] for r in rows}):
        mine = [r for r in rows if r[0] == scene]
        s = sampling._stats(mine)
        if s[1] > s[0]:
            worse.append(statistics.fmean(r[3] - r[1] for r in mine))
    return (f"overshoot the paper in {WORDS[len(worse)]} of {WORDS[len({r[0] for r in rows})]} scenes (by "
            f"{min(worse):.1f}–{max(worse):.1f} on average")


def _best_picks(table):
    """(scenes where the model's top encoder is the paper's at 1 spp, at 8 spp, the shared scenes -> encoder)."""
    one, eight = sampling._sets()
    paper = [p for p in sampling._paper(table)]
    picks = [set(), set()]
    for scene in {p["scene"] for p in paper}:
        mine = [p for p in paper if p["scene"] == scene]
        best = max(mine, key=lambda p: float(p["paper_speedup"]))["encoder"]
        batch = sampling.BATCH[table]
        for i, cells in enumerate((one, eight)):
            top = max(mine, key=lambda p: gpu(cells[(scene, batch, p["encoder"])]))["encoder"]
            if top == best:
                picks[i].add((scene, best))
    return picks


def spp_best_picks_phrase():
    (t2_one, t2_eight), (t3_one, t3_eight) = _best_picks("2"), _best_picks("3")
    same = ("the same" if t2_one == t2_eight else "different") + f" {WORDS[len(t2_one)]}"
    named = "; ".join(f"{PAPER_COLUMN[s]}: {e.upper()}" for s, e in
                      sorted(t2_one, key=lambda x: list(PAPER_COLUMN).index(x[0])))
    return (f"on Table 2 it picks the paper's best in {same} of five scenes at both ({named}), on Table 3 in "
            f"{WORDS[len(t3_one)]} at 1 spp and {WORDS[len(t3_eight)]} at 8 spp")


# --- Table by table ---------------------------------------------------------------------------------------

def viewport_cost_phrase():
    return _set_cost(VIEWPORT)


def hcc_dir_cost_phrase():
    return _set_cost(HCC_DIR)


def bounces_cost_phrase():
    return _set_cost(BOUNCES)


def _viewport_ratio(scene, enc):
    return round(float(appendix.cells(VIEWPORT)[(scene, "bounce1", enc, 32)]["simt_lane_efficiency_ratio"]), 3)


def viewport_breakfast_phrase():
    printed = appendix._printed("4")[("mlhcc32", "Breakfast")]["printed_speedup"]
    return f"the paper: MLHCC32 {printed}, ours {_viewport_ratio('breakfast_room_limited', 'mlhcc'):.2f}"


def viewport_living_phrase():
    lead = [_viewport_ratio("grey_white_room_limited", e) for e in ("ppc", "hcc", "mlhcc")]
    return (f"PPC, HCC and MLHCC ({min(lead):.2f}–{max(lead):.2f}) stay just ahead of TwoPoint "
            f"({_viewport_ratio('grey_white_room_limited', 'twopoint'):.2f})")


OVERHEAD_ENCODERS = ["hcc", "mlhcc", "twopoint", "ppc"]
OVERHEAD_ARMS = ["encode_ms", "sort_ms", "permute_ms"]


def overhead_earlier_phrase():
    """The earlier 8-spp set's Table 5 times against the whole set's, and its overhead shares."""
    old, new = load(EIGHT_SPP_EARLIER[0], "permute", 32), sampling._sets()[1]
    key = lambda e: ("breakfast_room", "bounce1", e)  # noqa: E731
    r = {a: [old[key(e)][a]["median"] / new[key(e)][a]["median"] for e in OVERHEAD_ENCODERS] for a in OVERHEAD_ARMS}
    every = [x for a in OVERHEAD_ARMS for x in r[a]]
    share = lambda e: old[key(e)]["overhead_pct"]["value"]  # noqa: E731
    return (f"measured {min(every):.1f}–{max(every):.1f}× these times (encode {min(r['encode_ms']):.1f}–"
            f"{max(r['encode_ms']):.1f}×) with about the same shares: HCC {share('hcc'):.0f} %, PPC {share('ppc'):.0f} %")


def overhead_share_phrase():
    """Our overhead share against the paper's Table 5 percentage, both samplings, the four encoders."""
    paper = {r["row"]: float(r["value"]) for r in paper_tex.printed() if r["table"] == "5" and r["column"] == "percentage"}
    ratios = [cells[("breakfast_room", "bounce1", e)]["overhead_pct"]["value"] / paper["mlhcc32" if e == "mlhcc" else e]
              for cells in sampling._sets() for e in OVERHEAD_ENCODERS]
    return f"every share is {min(ratios):.0f}–{max(ratios):.0f}× the paper's"


def _anc(bits, enc, spp=0):
    return sampling._sets(bits)[spp][("sibenik", "bounce1", enc)]["anc"]


def _table7():
    return {(r["row"], int(r["column"])): float(r["value"]) for r in paper_tex.printed() if r["table"] == "7"}


def anc_hcc_mlhcc_phrase():
    p = _table7()
    d = max(abs(round(_anc(b, e), 2) - p[(e, b)]) for e in ("hcc", "mlhcc") for b in (16, 32, 64))
    return f"within {d:.2f}"


def anc_ppc_phrase():
    p = _table7()
    return f"{_anc(32, 'ppc'):.2f} against {p[('ppc', 32)]:.2f} at 32 bits, {_anc(64, 'ppc'):.2f} against {p[('ppc', 64)]:.2f} at 64"


def anc_ppc_within_phrase():
    p = _table7()
    d = max(abs(round(_anc(b, "ppc"), 2) - p[("ppc", b)]) for b in (16, 32, 64))
    return f"PPC's within {d:.1f}"


def anc_twopoint_phrase():
    p = _table7()
    return (f"{_anc(16, 'twopoint'):.2f} and {_anc(64, 'twopoint'):.2f} against {p[('twopoint', 16)]:.2f} and "
            f"{p[('twopoint', 64)]:.2f}")


def anc_twopoint_ours_phrase():
    return "ours " + " / ".join(f"{_anc(b, 'twopoint'):.2f}" for b in (16, 32, 64))


def anc_eight_spp_phrase():
    return f"HCC {_anc(32, 'hcc', 1):.2f} and PPC {_anc(32, 'ppc', 1):.2f} at 32 bits"


def _hcc_dir_ratios():
    """scene -> (HCC 32, HCC_DIR, HCC 31) lane ratios as the table prints them (three decimals)."""
    c = appendix.cells(HCC_DIR)
    return {s: [round(float(c[(s, "bounce1", e, b)]["simt_lane_efficiency_ratio"]), 3)
                for e, b in (("hcc", 32), ("hcc-dir", 32), ("hcc", 31))] for s, _ in appendix.HCC_DIR_SCENES}


def hcc_dir_cut_bit_phrase():
    d = [v[0] - v[2] for v in _hcc_dir_ratios().values()]
    return f"HCC 32 vs 31 bits: {min(d):+.3f} to {max(d):+.3f}"


def hcc_dir_bit_phrase():
    """What the direction bit buys over HCC with 31 bits, against what the 32nd cut bit buys."""
    r = _hcc_dir_ratios()
    wins = {s: v[1] - v[2] for s, v in r.items() if v[1] - v[2] > v[0] - v[2]}
    losses = {s: (v[0] - v[2]) - (v[1] - v[2]) for s, v in r.items() if s not in wins}
    small = {s: g for s, g in wins.items() if g < 0.01}
    big = {s: g for s, g in wins.items() if s not in small}
    names = {"grey_white_room": "the Living room", "breakfast_room": "Breakfast", "sponza_dabrovic": "sponza"}
    part = [f"{g:+.3f} on {names.get(s, s)}" for s, g in small.items()]
    if big:
        part.append(f"{min(big.values()):+.3f} to {max(big.values()):+.3f} on "
                    + ", ".join(names.get(s, s) for s in list(big)[:-1]) + f" and {names.get(list(big)[-1], list(big)[-1])}")
    lost = "; ".join(f"losing only on {names.get(s, s)}, by {g:.3f}" for s, g in losses.items())
    return f"worth more than it on {WORDS[len(wins)]} of {WORDS[len(r)]} scenes ({', '.join(part)}), {lost}"


def bounces_nosort_phrase():
    c = appendix.cells(BOUNCES)
    lanes = [float(c[("breakfast_room", b, "nosort", 0)]["simt_lane_efficiency"])
             for b in sorted({k[1] for k in c})]
    return f"NoSort {lanes[0]:.2f} → {lanes[-1]:.2f}"


def sweep_twopoint_phrase():
    values = ["0.1", "0.25", "0.5", "0.75", "1.0"]
    sets = {v: appendix.cells(os.path.join(SWEEPS, f"twopoint-{v}")) for v in values}
    ratio = lambda v, s: round(float(sets[v][(s, "bounce1", "twopoint", 32)]["simt_lane_efficiency_ratio"]), 3)  # noqa: E731
    scenes = {k[0] for k in sets["0.25"]}
    gap = max(max(ratio(v, s) for v in values) - ratio("0.25", s) for s in scenes)
    return f"TwoPoint's 0.25 is within {gap:.3f} of the best value in every scene"


# --- Open questions of the audit --------------------------------------------------------------------------

def _order(layout, enc, bits=32, batch="bounce1", field="simt_lane_efficiency_ratio"):
    return float(audit.cells(AUDIT_ORDER)[(layout, batch, enc, bits)][field])


NEAREST = "file:ppc_nearest_first"


def audit_ppc_ties_phrase():
    lane = lambda layout: f"{_order(layout, 'ppc'):.3f} and {_order(layout, 'twopoint'):.3f} {layout}"  # noqa: E731
    model = lambda layout: (f"{_order(layout, 'ppc', field='gpu_model_speedup'):.2f} against "  # noqa: E731
                            f"{_order(layout, 'twopoint', field='gpu_model_speedup'):.2f}")
    return f"{lane('wide')}, {lane('binary')}; GPU model {model('wide')}, {model('binary')}"


def audit_ppc_tie_wide_phrase():
    return f"{_order('wide', 'ppc'):.3f} and {_order('wide', 'twopoint'):.3f}"


def audit_distinct_phrase():
    d = lambda enc: _order("wide", enc, field="simt_distinct_per_visit_ratio")  # noqa: E731
    return f"distinct nodes per visit {d('twopoint'):.3f} of NoSort's against PPC's {d('ppc'):.3f}"


def audit_nearest_phrase():
    return f"{_order('wide', NEAREST):.3f} and {_order('binary', NEAREST):.3f}"


def audit_ppc_leads_phrase():
    """PPC's lead over TwoPoint (lane ratio, wide tree) against the paper's (Table 6 over Table 2's NoSort)."""
    paper = {enc: [float(x) for x in v.split(" / ")] for enc, v in audit._paper_speedups().items()}
    lead = lambda b, batch: _order("wide", "ppc", b, batch) - _order("wide", "twopoint", b, batch)  # noqa: E731
    return (f"by {lead(16, 'bounce1'):.2f} and {lead(64, 'bounce1'):.2f} where the paper has "
            f"{paper['ppc'][0] - paper['twopoint'][0]:.2f} and {paper['ppc'][2] - paper['twopoint'][2]:.2f}; on primary "
            f"shadow rays it leads by {lead(32, 'shadow0'):.2f} at 32 bits and {lead(64, 'shadow0'):.2f} at 64")


def _eight_spp_sibenik(enc):
    return load(EIGHT_SPP, "permute", 32)[("sibenik", "bounce1", enc)]


def audit_batch_phrase():
    tp, ppc = _eight_spp_sibenik("twopoint"), _eight_spp_sibenik("ppc")
    return (f"{tp['simt_lane_efficiency_ratio']:.3f} against {ppc['simt_lane_efficiency_ratio']:.3f}; GPU model "
            f"{gpu(tp):.2f} against {gpu(ppc):.2f}")


def audit_behind_phrase():
    """How far PPC stays behind TwoPoint on bounce1 at 32 bits over both walking orders, both layouts and the
    8-spp batch, as the tables print them."""
    lane, model = [], []
    for layout in ("wide", "binary"):
        for enc in ("ppc", NEAREST):
            lane.append(round(_order(layout, "twopoint"), 3) - round(_order(layout, enc), 3))
            model.append(round(_order(layout, "twopoint", field="gpu_model_speedup"), 2)
                         - round(_order(layout, enc, field="gpu_model_speedup"), 2))
    tp, ppc = _eight_spp_sibenik("twopoint"), _eight_spp_sibenik("ppc")
    lane.append(round(tp["simt_lane_efficiency_ratio"], 3) - round(ppc["simt_lane_efficiency_ratio"], 3))
    model.append(round(gpu(tp), 2) - round(gpu(ppc), 2))
    return (f"lane ratio {min(lane):.3g} to {max(lane):.3f} behind, GPU model {min(model):.2f} to "
            f"{max(model):.2f} behind")


def _twopoint_bits(enc="twopoint", field="anc"):
    c = audit.cells(AUDIT_TWOPOINT_BITS)
    c.update(audit.cells(AUDIT_TWOPOINT_VARIANTS))
    return {b: float(r[field]) for (layout, batch, e, b), r in c.items() if e == enc and batch == "bounce1"}


def audit_twopoint_64_phrase():
    anc = _twopoint_bits()
    full = min(b for b, v in anc.items() if all(anc[x] >= v for x in anc if x >= b) and v > 0.9 * 32)
    return f"{anc[64]:.2f}: from {full} bits on, {anc[full]:.2f} and up"


def audit_twopoint_cap32_phrase():
    return (f"{_twopoint_bits('file:twopoint_cap32')[64]:.2f} · "
            f"{_twopoint_bits('file:twopoint_cap32', 'simt_lane_efficiency_ratio')[64]:.3f}")


def audit_twopoint_64_gain_phrase():
    lane = _twopoint_bits(field="simt_lane_efficiency_ratio")
    return f"lane ratio {lane[32]:.3f} → {lane[64]:.3f}"


@functools.lru_cache(maxsize=None)
def _encodebench():
    """(encoder, bits) -> distinct keys, and the batch's rays, from the audit's encodebench log."""
    with open(AUDIT_ENCODEBENCH) as f:
        text = f.read()
    rays = int(re.search(r"batch bounce1: (\d+) rays", text).group(1))
    distinct = {(m.group(1), int(m.group(2))): int(m.group(3)) for m in
                re.finditer(r"^(\S+)\s+(\d+)\s+[\d.]+\s+[\d.]+\s+[\d.]+%\s+(\d+)", text, re.M)}
    return distinct, rays


def _paper_twopoint16():
    return _table7()[("twopoint", 16)] - 1


def audit_twopoint_16_bound_phrase():
    distinct, rays = _encodebench()
    keys, warps = distinct[("twopoint", 16)], (rays + 31) // 32
    return (f"only {keys:,} of the {2**16:,} values occur (`encodebench`, distinct keys), and with {rays:,} rays = "
            f"{warps:,} warps the ANC can be at most 1 + {keys - 1:,} / {warps:,} = {1 + (keys - 1) / warps:.3f}")


def audit_twopoint_16_ours_phrase():
    return f"ours is {_anc(16, 'twopoint'):.2f}"


def _needed():
    _, rays = _encodebench()
    return _paper_twopoint16() * ((rays + 31) // 32)


def audit_twopoint_16_needed_phrase():
    _, rays = _encodebench()
    return f"{_paper_twopoint16():.2f} × {(rays + 31) // 32:,} ≈ {round(_needed(), -3):,.0f}"


def audit_twopoint_16_needed_short_phrase():
    return f"about {round(_needed(), -3):,.0f}"


NUMBER_WORDS = {5: "five", 6: "six", 7: "seven", 8: "eight", 9: "nine", 10: "ten", 11: "eleven", 12: "twelve"}


def audit_twopoint_16_times_phrase():
    distinct, _ = _encodebench()
    return f"{NUMBER_WORDS[round(_needed() / distinct[('twopoint', 16)])]} times"


def audit_twopoint_16_distinct_phrase():
    return f"{_encodebench()[0][('twopoint', 16)]:,}"


def audit_twopoint_short_keys_phrase():
    anc = _twopoint_bits()
    return f"{anc[20]:.2f} only at 20 bits, {anc[24]:.2f} at 24"


def audit_twopoint_low16_phrase():
    distinct, _ = _encodebench()
    return (f"{distinct[('file:twopoint_low16', 16)]:,} values and give ANC "
            f"{_twopoint_bits('file:twopoint_low16')[16]:.2f}")


def audit_twopoint_low16_lane_phrase():
    return f"lane ratio {_twopoint_bits('file:twopoint_low16', 'simt_lane_efficiency_ratio')[16]:.3f}"


def audit_twopoint_smaller_batch_phrase():
    distinct, _ = _encodebench()
    keys = distinct[("twopoint", 16)] - 1
    return f"{keys:,} × 32 / {_paper_twopoint16():.2f} ≈ {round(keys * 32 / _paper_twopoint16(), -5):,.0f} rays"


def audit_twopoint_32_phrase():
    anc, paper = _twopoint_bits(), _table7()[("twopoint", 32)]
    below = max(b for b in anc if anc[b] < paper)
    above = min(b for b in anc if anc[b] > paper)
    return f"{paper:.2f} against {anc[32]:.2f}, ours between {below} and {above} bits"


# --- docs/paper.md: what a run of the paper's sampling costs ----------------------------------------------

def paper_cost_eight_phrase():
    eight_s, _ = _eight_spp_cost()
    shards = len(_shard_logs())
    return f"{len(_rows(EIGHT_SPP))}-cell preset took {duration(eight_s, 'min')} as {NUMBER_WORDS[shards]} shards"


def paper_cost_quiet_phrase():
    """On a quiet machine: twice what the quiet shards took (they hold half the estimated cost), to 5 minutes."""
    t = [_elapsed_s(p) for p in _shard_logs()]
    return f"about {duration(300 * round(2 * sum(t[-QUIET_SHARDS:]) / 300), 'min')}"


def paper_cost_one_phrase():
    _, eight_gib = _eight_spp_cost()
    one_gib = _peak_gib(os.path.join(ONE_SPP, "run-time.txt"))
    return (f"against {duration(_run_time(ONE_SPP), 'min')} at 1 spp, with a peak of {eight_gib:.1f} GiB of host "
            f"memory ({one_gib:.1f} GiB at 1 spp)")


# --- Table 1 (light setup), from the scene files ------------------------------------------------------------

# The paper's Table 1 as printed (light index: relative radius), the scenes standing for it here, and what
# the comparison says; "ours" is read from scenes/<scene>.toml, as `raysort scenes --lights` prints it.
TABLE1 = [
    ("Breakfast", "0: 8.3 %; 1-2: 1.6 %", ["breakfast_room"], "same"),
    ("Salle de Bain", "0: 1.1 %", [], "scene not available"),
    ("Living room", "0: 5 %", ["grey_white_room"], "another living room, its own lights"),
    ("Sibenik", "0: 7.5 %; 1-2: 2.5 %; 3-12: 0.5 %", ["sibenik"], "same"),
    ("Vokselia", "0: 12 %", ["landscape", "jacksboro_terrain"], "open scenes with a sun and a sky"),
]


def _lights(scene):
    """'0: 8.30 %; 1-2: 1.60 %' (+ ' + sky'): runs of equal radius, as `raysort scenes --lights` groups them."""
    import tomllib

    with open(os.path.join(ROOT, "scenes", scene + ".toml"), "rb") as f:
        toml = tomllib.load(f)
    radii = [float(light["radius"]) for light in toml.get("sphere_light", [])]
    runs, i = [], 0
    while i < len(radii):
        j = i
        while j + 1 < len(radii) and radii[j + 1] == radii[i]:
            j += 1
        runs.append(f"{i if i == j else f'{i}-{j}'}: {100 * radii[i]:.2f} %")
        i = j + 1
    return "; ".join(runs) + (" + sky" if "sky" in toml else "")


def table1_block():
    lines = ["| paper scene | paper: light, relative radius | here | ours (`raysort scenes --lights`) | |",
             "|---|---|---|---|---|"]
    for paper, printed, scenes, verdict in TABLE1:
        here = " / ".join(scenes) or "–"
        ours = " / ".join(_lights(s) for s in scenes) or "–"
        lines.append(f"| {paper} | {printed} | {here} | {ours} | {verdict} |")
    return "\n".join(lines)
