"""results/gpu-model/README.md, "The viewport, HCC_DIR and bounce sets" (issue 43, item 4): the GPU
model's predicted speedups (the `gpu_model_speedup` column `raysort run --gpu-model rtx3060` writes,
at the profile's step_cycles, which was fitted on Table 2) on the sets of the paper's Table 4, Table 8
and bounces figure, re-run with the model on (results/gpu-model/paper-*-gm-*/), beside the SIMT
lane-efficiency ratio of the same cells and the paper's figure."""
from . import paper_tex
from .appendix import ENCODERS, HCC_DIR_SCENES, VIEWPORT_SCENES
from .gpu_model_scoring import model_cells, profile
from .sets import GPU_BOUNCES, GPU_HCC_DIR, GPU_VIEWPORT


# The re-runs hold the scenes that stand for a paper column only (the tables' scenes), as appendix.py pairs them.
VIEWPORT_PAPER_SCENES = [(s, col) for s, col in VIEWPORT_SCENES if col]
HCC_DIR_PAPER_SCENES = [(s, col) for s, col in HCC_DIR_SCENES if col]


def _by_key(set_dir):
    return {(c["scene"], c["batch"], c["encoder"], int(c["bits"])): c for c in model_cells(set_dir)}


def _model(c):
    return float(c["gpu_model_speedup"])


def _lane(c):
    return float(c["simt_lane_efficiency_ratio"])


def _printed(table):
    return {(r["row"], r["column"]): r for r in paper_tex.printed() if r["table"] == table}


def viewport_block():
    """Table 4: the model's speedup per encoder and scene (paper speedup in brackets)."""
    c, paper = _by_key(GPU_VIEWPORT), _printed("4")
    heads = [f"{col} ({s})" for s, col in VIEWPORT_PAPER_SCENES]
    out = ["| encoder | " + " | ".join(heads) + " |", "|---|" + "---:|" * len(heads)]
    for e in ENCODERS:
        row = []
        for s, col in VIEWPORT_PAPER_SCENES:
            p = paper[("mlhcc32" if e == "mlhcc" else e, col)]
            row.append(f"{_model(c[(s, 'bounce1', e, 32)]):.2f} ({p['printed_speedup']})")
        out.append(f"| {e} | " + " | ".join(row) + " |")
    return "\n".join(out)


HCC_DIR_ARMS = [("hcc", 32, "HCC"), ("hcc-dir", 32, "HCC_DIR"), ("hcc", 31, "HCC_31bit")]


def hcc_dir_block():
    """Table 8: the model's speedup of HCC 32, HCC_DIR and HCC 31 bits (paper MRays/s in brackets)."""
    c, paper = _by_key(GPU_HCC_DIR), _printed("8")
    out = ["| scene | HCC 32 bits | HCC_DIR (31 cut bits + 1 direction bit) | HCC 31 bits | model: HCC_DIR − HCC 31 bits |",
           "|---|---:|---:|---:|---:|"]
    for s, col in HCC_DIR_PAPER_SCENES:
        vals = [_model(c[(s, "bounce1", e, b)]) for e, b, _ in HCC_DIR_ARMS]
        shown = [f"{v:.3f} ({paper[(col, head)]['value']})" for v, (_, _, head) in zip(vals, HCC_DIR_ARMS)]
        label = f"{s} ({col}" + (" stand-in: Table 8 has no landscape row)" if s == "landscape" else ")")
        out.append(f"| {label} | " + " | ".join(shown) + f" | {vals[1] - vals[2]:+.3f} |".replace("-", "−"))
    return "\n".join(out)


BOUNCE_SCENE = "breakfast_room"


def _bounces():
    c = _by_key(GPU_BOUNCES)
    return c, sorted({k[1] for k in c})


def bounces_block():
    """The model's speedup (and the SIMT lane-efficiency ratio) of every encoder at bounces 1-5 of Breakfast."""
    c, batches = _bounces()
    out = ["| encoder: model speedup (SIMT lane ratio) | " + " | ".join(batches) + " |", "|---|" + "---:|" * len(batches),
           "| rays | " + " | ".join(f"{int(c[(BOUNCE_SCENE, b, 'nosort', 0)]['rays']):,}" for b in batches) + " |"]
    for e in ENCODERS:
        out.append(f"| {e} | " + " | ".join(
            f"{_model(c[(BOUNCE_SCENE, b, e, 32)]):.2f} ({_lane(c[(BOUNCE_SCENE, b, e, 32)]):.2f})" for b in batches) + " |")
    return "\n".join(out)


def bounces_trend_phrase():
    """How many encoders' predicted speedups fall, and rise, from bounce 1 to the deepest bounce."""
    c, batches = _bounces()
    first, last = batches[0], batches[-1]
    change = {e: _model(c[(BOUNCE_SCENE, last, e, 32)]) - _model(c[(BOUNCE_SCENE, first, e, 32)]) for e in ENCODERS}
    falls = [e for e in ENCODERS if change[e] < 0]
    rises = [e for e in ENCODERS if change[e] > 0]
    hcc = [_model(c[(BOUNCE_SCENE, b, "hcc", 32)]) for b in batches]
    hcc_lane = [_lane(c[(BOUNCE_SCENE, b, "hcc", 32)]) for b in batches]
    # after the rise: encoders whose speedup peaks before the deepest bounce, and how far they fall back
    series = {e: [_model(c[(BOUNCE_SCENE, b, e, 32)]) for b in batches] for e in ENCODERS}
    early = [e for e in ENCODERS if max(series[e]) > series[e][-1]]
    fall_back = max((max(series[e]) - series[e][-1] for e in early), default=0.0)
    return (f"from {first} to {last} the model's speedup falls for {len(falls)} of {len(ENCODERS)} encoders"
            f"{' (' + ', '.join(falls) + ')' if falls else ''} and rises for {len(rises)}; HCC "
            f"{' → '.join(f'{v:.2f}' for v in hcc)} (SIMT lane ratio {hcc_lane[0]:.2f} → {hcc_lane[-1]:.2f}). "
            f"{len(early)} of {len(ENCODERS)} peak before {last} and fall back by at most {fall_back:.2f}")


def _issue_memory(c, prof):
    """The two terms of bench/gpu_model.cpp's time (docs/gpu-model.md, "From counts to time"), in seconds."""
    issue = float(c["gpu_warp_steps"]) * prof["step_cycles"] / (prof["sms"] * prof["clock_ghz"] * 1e9)
    l2_sectors = float(c["gpu_l2_hits"]) + float(c["gpu_l2_misses"])
    memory = float(c["gpu_dram_bytes"]) / (prof["dram_gbps"] * 1e9) + l2_sectors * prof["sector_bytes"] / (prof["l2_gbps"] * 1e9)
    return issue, memory


def bounces_memory_phrase():
    """Why the model's HCC speedup levels off while the lane ratio rises: NoSort's memory time over HCC's
    per bounce, and the memory term's share of HCC's predicted time."""
    c, batches = _bounces()
    prof = profile()
    ratio, share = [], []
    for b in batches:
        ni, nm = _issue_memory(c[(BOUNCE_SCENE, b, "nosort", 0)], prof)
        hi, hm = _issue_memory(c[(BOUNCE_SCENE, b, "hcc", 32)], prof)
        ratio.append(nm / hm)
        share.append(100 * hm / (hi + hm))
    return (f"NoSort's memory time over HCC's runs {' → '.join(f'{v:.2f}' for v in ratio)}, while the memory "
            f"term's share of HCC's predicted time grows from {share[0]:.0f} % to {share[-1]:.0f} %")
