"""results/README.md, "The paper preset against the issue's commit": issue 42's wall-clock bar, measured
side by side on one day per result set (results/pocl-cpu-pthread-skylake-avx512-amd-epyc/protocol-time-ca43944,
2026-11-29, and protocol-time-00cb31e, 2026-12-01, after the gathered rays' prefetch). Each arm is a result
set with its run's log (run.log, whose last line is `/usr/bin/time`'s "WALL <arm> <s> s")."""
import csv
import functools
import json
import os
import statistics

from .prose_early import _elapsed_s
from .sets import PROTOCOL_TIME, PROTOCOL_TIME_PREFETCH

BAR = 7 / 12.92  # issue 42: 7 minutes where the commit took 12 min 55 s, as a share of its time

# (folder, what runs, the folder of the commit's run it is compared with), in the order of the table.
ARMS = [
    ("b17c516", "the issue's commit: each cell group in rounds of its own, one warm-up round", "b17c516"),
    ("ca43944", "shared rounds (up to 8 groups), no warm-up round: the default", "b17c516"),
    ("ca43944-warmup-1", "the same with `--warmup 1`", "b17c516"),
    ("ca43944-max-time-3", "the same with `--max-time 3`", "b17c516"),
    ("b17c516-run2", "the issue's commit again", "b17c516-run2"),
    ("fa4b665", "the default again (fa4b665: ca43944 and the ETA fix)", "b17c516-run2"),
    ("0606a6b", "and with each ray's SIMT trail recorded once per batch (0606a6b)", "b17c516-run3"),
    ("b17c516-run3", "the issue's commit, a third time", "b17c516-run3"),
    # Stop 59, the same day, in the order A B B A: pair 4, then pair 5.
    ("1d00992", "the default at 1d00992 (0606a6b, and the host twins' rays in blocks)", "b17c516-run4"),
    ("b17c516-run4", "the issue's commit, a fourth time", "b17c516-run4"),
    ("b17c516-run5", "the issue's commit, a fifth time", "b17c516-run5"),
    ("1d00992-run2", "the default at 1d00992 again", "b17c516-run5"),
]

# protocol-time-00cb31e: the code with the trace kernels' prefetch of the gathered ray (00cb31e), in pairs
# with the commit, in the order A B B A B A.
PREFETCH_ARMS = [
    ("00cb31e", "the default at 00cb31e (1d00992, and the gathered rays prefetched on a CPU)", "b17c516"),
    ("b17c516", "the issue's commit", "b17c516"),
    ("b17c516-run2", "the issue's commit again", "b17c516-run2"),
    ("00cb31e-run2", "the default at 00cb31e again", "b17c516-run2"),
    ("b17c516-run3", "the issue's commit, a third time", "b17c516-run3"),
    ("00cb31e-run3", "the default at 00cb31e, a third time", "b17c516-run3"),
]


@functools.lru_cache(maxsize=None)
def _wall_s(arm, root=PROTOCOL_TIME):
    return _elapsed_s(os.path.join(root, arm, "run.log"))


@functools.lru_cache(maxsize=None)
def _noise(arm, root=PROTOCOL_TIME):
    with open(os.path.join(root, arm, "meta.json")) as f:
        return json.load(f)["noise"]


@functools.lru_cache(maxsize=None)
def _cells(arm, root=PROTOCOL_TIME):
    """A run's cells.csv rows by cell id (read once)."""
    with open(os.path.join(root, arm, "cells.csv"), newline="") as f:
        return {r["id"]: r for r in csv.DictReader(f)}


def _sorted_rows(arm, batch, root=PROTOCOL_TIME):
    return [r for r in _cells(arm, root).values() if r["batch"] == batch and r["encoder"] != "nosort"]


def _half_width(r):
    return (float(r["speedup_hi"]) - float(r["speedup_lo"])) / (2 * float(r["speedup"]))


def _nosort_ms(arm, batch, root=PROTOCOL_TIME):
    """The median NoSort trace of the batch: how fast the machine traced during that run."""
    return next(float(r["nosort_trace_ms"]) for r in _cells(arm, root).values()
                if r["batch"] == batch and r["encoder"] == "nosort")


def _table(arms, root):
    """Per arm: wall clock and its share of the issue's commit's in the same pair, A/A, half-widths, rounds."""
    lines = ["| set | what runs | wall clock | of the issue's commit's | NoSort bounce1 trace | A/A calibration "
             "| speedup half-width, median / 90th pct. | bounce1: rounds, half-width | shadow0: rounds, half-width |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for arm, what, base in arms:
        n = _noise(arm, root)
        per_batch = []
        for batch in ("bounce1", "shadow0"):
            rows = _sorted_rows(arm, batch, root)
            per_batch.append(f"{statistics.median(int(r['rounds']) for r in rows):.0f}, "
                             f"{100 * statistics.median(_half_width(r) for r in rows):.1f} %")
        lines.append(f"| `{arm}/` | {what} | {_wall_s(arm, root):.1f} s | {_wall_s(arm, root) / _wall_s(base, root):.3f} | "
                     f"{_nosort_ms(arm, 'bounce1', root):.1f} ms | "
                     f"{n['aa_containing_one']} of {n['aa_intervals']} ({100 * n['aa_coverage']:.1f} %) | "
                     f"{100 * n['speedup_half_width']['median']:.2f} % / {100 * n['speedup_half_width']['p90']:.1f} % | "
                     f"{per_batch[0]} | {per_batch[1]} |")
    return "\n".join(lines)


def protocol_time_block():
    return _table(ARMS, PROTOCOL_TIME)


def protocol_time_prefetch_block():
    return _table(PREFETCH_ARMS, PROTOCOL_TIME_PREFETCH)


def _same_orders(arms, root):
    """How many of the first arm's cells have the same order hash and ANC in every arm, and of how many."""
    first = _cells(arms[0][0], root)
    same = sum(all((_cells(a, root)[i]["order_hash"], _cells(a, root)[i]["anc"]) == (first[i]["order_hash"], first[i]["anc"])
                   for a, _, _ in arms[1:]) for i in first)
    return same, len(first)


def _pairs(arms, mine, root):
    """Per arm of `mine`: its wall clock over its pair's issue's-commit run, and the two median half-widths (%)."""
    base = {arm: b for arm, _, b in arms}
    ratios = [_wall_s(a, root) / _wall_s(base[a], root) for a in mine]
    widths = [(100 * _noise(a, root)["speedup_half_width"]["median"],
               100 * _noise(base[a], root)["speedup_half_width"]["median"]) for a in mine]
    return ratios, widths


def _aa(runs, root):
    """A/A intervals containing 1, and all of them, pooled over the runs."""
    return (sum(_noise(a, root)["aa_containing_one"] for a in runs), sum(_noise(a, root)["aa_intervals"] for a in runs))


def protocol_time_same_phrase():
    """The deterministic figures agree across the arms; the speedups of the default against the issue's."""
    same, count = _same_orders(ARMS, PROTOCOL_TIME)
    base = _cells(ARMS[0][0])
    new = _cells(ARMS[1][0])
    ratios = [float(new[i]["speedup"]) / float(base[i]["speedup"]) for i in base if base[i]["encoder"] != "nosort"]
    return (f"the same {same} of {count} order hashes and ANCs in all {len(ARMS)} sets; speedups of `{ARMS[1][0]}/` "
            f"over `{ARMS[0][0]}/`'s, per cell: median {statistics.median(ratios):.3f} ({min(ratios):.3f} to "
            f"{max(ratios):.3f})")


# The arms that ran the code of 0606a6b to 1d00992 (1d00992 changes only the host twins' thread split), the
# last before the prefetch, and every arm of the default protocol (shared rounds, no warm-up round, the 5 s
# budget: ca43944 on) in that set.
FINAL = ["0606a6b", "1d00992", "1d00992-run2"]
DEFAULT_PROTOCOL = ["ca43944", "fa4b665"] + FINAL


def protocol_time_final_phrase():
    """The bar over every pair that ran 0606a6b's code: each pair's ratio, their median, the half-widths, and
    the A/A calibration pooled over every run of the default protocol (a run's 23-26 intervals are too few)."""
    ratios, widths = _pairs(ARMS, FINAL, PROTOCOL_TIME)
    under = sum(r <= BAR for r in ratios)
    contain, total = _aa(DEFAULT_PROTOCOL, PROTOCOL_TIME)
    return (f"{', '.join(f'{r:.3f}' for r in ratios)} of the issue's commit's time in the {len(FINAL)} pairs that ran "
            f"0606a6b's code (median {statistics.median(ratios):.3f}; {under} of {len(FINAL)} at or under the bar's "
            f"{BAR:.3f}), at a median half-width of {', '.join(f'{w:.2f}' for w, _ in widths)} % against the issue's "
            f"commit's {', '.join(f'{b:.2f}' for _, b in widths)} % in the same pairs; A/A calibration over the "
            f"{len(DEFAULT_PROTOCOL)} runs of the default protocol: {contain} of {total} ({100 * contain / total:.1f} %)")


def protocol_time_prefetch_phrase():
    """The bar over the pairs of protocol-time-00cb31e: each pair's ratio, their median, the half-widths, the A/A
    calibration pooled over the code's runs, and the order hashes and ANCs against the issue's commit."""
    mine = [arm for arm, _, base in PREFETCH_ARMS if arm != base]
    ratios, widths = _pairs(PREFETCH_ARMS, mine, PROTOCOL_TIME_PREFETCH)
    under = sum(r <= BAR for r in ratios)
    contain, total = _aa(mine, PROTOCOL_TIME_PREFETCH)
    old_contain, old_total = _aa(DEFAULT_PROTOCOL, PROTOCOL_TIME)
    same, count = _same_orders(PREFETCH_ARMS, PROTOCOL_TIME_PREFETCH)
    return (f"{', '.join(f'{r:.3f}' for r in ratios)} of the issue's commit's time in the {len(mine)} pairs (median "
            f"{statistics.median(ratios):.3f}; {under} of {len(mine)} at or under the bar's {BAR:.3f}), at a median "
            f"half-width of {', '.join(f'{w:.2f}' for w, _ in widths)} % against the issue's commit's "
            f"{', '.join(f'{b:.2f}' for _, b in widths)} % in the same pairs; A/A calibration over the {len(mine)} runs: "
            f"{contain} of {total} ({100 * contain / total:.1f} %), and over every run of the default protocol in "
            f"both sets ({len(DEFAULT_PROTOCOL) + len(mine)}): {contain + old_contain} of {total + old_total} "
            f"({100 * (contain + old_contain) / (total + old_total):.1f} %); the same {same} of {count} order "
            f"hashes and ANCs in all {len(PREFETCH_ARMS)} sets")
