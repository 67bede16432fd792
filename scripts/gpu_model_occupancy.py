#!/usr/bin/env python3
"""Occupancy as a second fitted constant of the GPU cost model (results/gpu-model/README.md, "Occupancy").

Each SET is the paper's Table 2 matrix replayed with a profile that differs from rtx3060 only in
resident_warps_per_sm, and PROFILE is that profile. For each held-out scene, the occupancy and
step_cycles with the least mean absolute error on the other four scenes are chosen, and the held-out
scene is predicted with them; the script prints those choices, the pooled leave-one-scene-out figures,
and each occupancy's in-sample fit.

    scripts/gpu_model_occupancy.py w16:PROFILE16 w24:PROFILE24 ...   (SET:PROFILE pairs)
"""
import csv
import importlib.util
import os
import sys
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location("validate", os.path.join(HERE, "gpu_model_validate.py"))
v = importlib.util.module_from_spec(spec)
spec.loader.exec_module(v)


def main():
    pairs = [a.split(":", 1) for a in sys.argv[1:]]
    if not pairs or any(len(p) != 2 for p in pairs):
        sys.exit(__doc__)
    with open(os.path.join(HERE, "..", "results/gpu-model/paper_tables.csv"), newline="") as f:
        paper = [r for r in csv.DictReader(f) if r["table"] == "2"]
    runs = []
    for set_dir, profile in pairs:
        with open(profile, "rb") as f:
            prof = tomllib.load(f)
        cells = [dict(c, gpu_warps=str((int(c["rays"]) + 31) // 32)) for c in v.load_cells([set_dir])]
        runs.append((prof, v.pair(paper, cells)))
    scenes = sorted({r["scene"] for r in runs[0][1]})
    truth, pred = [], []
    for s in scenes:
        best = None
        for prof, rows in runs:
            train = [r for r in rows if r["scene"] != s]
            k = v.fit_k(train, prof)
            err = v.mae(v.predict(train, prof, k), [r["paper"] for r in train])
            if best is None or err < best[0]:
                best = (err, prof, rows, k)
        err, prof, rows, k = best
        test = [r for r in rows if r["scene"] == s]
        p = v.predict(test, prof, k)
        truth += [r["paper"] for r in test]
        pred += p
        print(f"{s}: {prof['resident_warps_per_sm']} warps, step_cycles {k:.1f} (train MAE {err:.3f}); "
              f"held-out MAE {v.mae(p, [r['paper'] for r in test]):.3f}")
    print(f"leave-one-scene-out, both constants fitted: Pearson {v.pearson(pred, truth):.2f} "
          f"Spearman {v.spearman(pred, truth):.2f} MAE {v.mae(pred, truth):.3f} ({len(truth)} cells)")
    for prof, rows in runs:
        k = v.fit_k(rows, prof)
        print(f"{prof['resident_warps_per_sm']} warps: step_cycles {k:.1f} on all cells, in-sample MAE "
              f"{v.mae(v.predict(rows, prof, k), [r['paper'] for r in rows]):.3f}")


if __name__ == "__main__":
    main()
