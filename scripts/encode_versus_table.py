#!/usr/bin/env python3
"""Collect `raysort encodebench --versus ENCODER` outputs (one file per scene and batch, named
SCENE-BATCH.txt) into a markdown table: the reference's encode ms with its interval, then each
encoder's paired cost ratio with its 95 % interval and rounds, and a median row.

  scripts/encode_versus_table.py DIR [--bar 1.5]
"""
import argparse
import glob
import os
import re
import statistics

ROW = re.compile(r"^(\S+)\s+(\d+)\s+([\d.]+) \[([\d.]+), ([\d.]+)\]\s+[\d.]+\s+\S+ \[[^\]]*\]\s+"
                 r"(?:(-)|([\d.]+) \[([\d.]+), ([\d.]+)\])\s+\d+\s+(\S+)\s+(\d+)(\*?)\s*$")


def read(path):
    versus, rows = None, {}
    for line in open(path):
        m = re.search(r"x (\S+) = paired estimate", line)
        if m:
            versus = m.group(1)
        m = ROW.match(line)
        if m:
            rows[m.group(1)] = dict(ms=float(m.group(3)), ms_lo=float(m.group(4)), ms_hi=float(m.group(5)),
                                    x=None if m.group(6) else float(m.group(7)),
                                    lo=None if m.group(6) else float(m.group(8)),
                                    hi=None if m.group(6) else float(m.group(9)),
                                    host=m.group(10), rounds=int(m.group(11)) , capped=bool(m.group(12)))
    return versus, rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir")
    ap.add_argument("--bar", type=float, default=1.5, help="count the rows whose interval lies under this ratio")
    a = ap.parse_args()
    files = sorted(glob.glob(os.path.join(a.dir, "*.txt")))  # by name: the same in any checkout
    table, versus, encoders = [], None, []
    for f in files:
        v, rows = read(f)
        if not rows:
            continue
        versus = versus or v
        for e in rows:
            if e != versus and e not in encoders:
                encoders.append(e)
        table.append((os.path.basename(f)[:-4], rows))
    bad = [(n, e) for n, rows in table for e, r in rows.items() if r["host"] != "yes"]
    print(f"| scene-batch | {versus} ms [95 %] | " + " | ".join(f"{e} × {versus} [95 %] (rounds)" for e in encoders) + " |")
    print("|---|---:|" + "---:|" * len(encoders))
    for name, rows in table:
        ref = rows[versus]
        cells = []
        for e in encoders:
            r = rows.get(e)
            cells.append("-" if not r or r["x"] is None else
                         f"{r['x']:.3f} [{r['lo']:.3f}, {r['hi']:.3f}] ({r['rounds']}{'*' if r['capped'] else ''})")
        print(f"| {name} | {ref['ms']:.2f} [{ref['ms_lo']:.2f}, {ref['ms_hi']:.2f}] | " + " | ".join(cells) + " |")
    med = []
    for e in encoders:
        xs = [rows[e]["x"] for _, rows in table if e in rows and rows[e]["x"] is not None]
        under = sum(1 for _, rows in table if e in rows and rows[e]["hi"] is not None and rows[e]["hi"] < a.bar)
        over = sum(1 for _, rows in table if e in rows and rows[e]["lo"] is not None and rows[e]["lo"] > a.bar)
        med.append(f"**{statistics.median(xs):.3f}** ({min(xs):.3f}–{max(xs):.3f}); "
                   f"{under} of {len(xs)} wholly under {a.bar}, {over} wholly over")
    print(f"| median (range) | | " + " | ".join(med) + " |")
    if bad:
        print(f"\nkeys differing from the host twin: {bad}")


if __name__ == "__main__":
    main()
