#!/usr/bin/python3
"""Plots `vkmesh soak` CSVs side by side: hash entries (+ tombstones), blocks, vertices and triangle chunks in
use per frame, one line per run, and prints the per-lap high-water marks as a Markdown table.

    /usr/bin/python3 bench/soak_plot.py RUN.csv[:LABEL] ... [--out soak.png]

Without matplotlib it prints the table only.
"""
import argparse
import csv
import sys

COLUMNS = [("hash_entries", "hash entries"), ("hash_slots_used", "hash entries + tombstones"),
           ("blocks_in_use", "blocks in use"), ("vertices_in_use", "vertices in use"),
           ("chunks_in_use", "triangle chunks in use")]


def load(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    data = {k: [int(r[k]) for r in rows] for k in ("frame", "lap", "hash_entries", "hash_tombstones", "blocks_in_use",
                                                   "vertices_in_use", "chunks_in_use")}
    data["hash_slots_used"] = [e + t for e, t in zip(data["hash_entries"], data["hash_tombstones"])]
    return data


def high_water_per_lap(data, key):
    out = {}
    for lap, value in zip(data["lap"], data[key]):
        out[lap] = max(out.get(lap, 0), value)
    return [out[lap] for lap in sorted(out)]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="+", help="CSV files written by `vkmesh soak`, optionally PATH:LABEL")
    ap.add_argument("--out", help="PNG to write (needs matplotlib)")
    args = ap.parse_args()
    runs = []
    for spec in args.runs:
        path, _, label = spec.partition(":")
        runs.append((label or path, load(path)))

    for label, data in runs:
        laps = sorted(set(data["lap"]))
        print(f"\n{label}: high water per lap")
        print("| quantity | " + " | ".join(f"lap {lap}" for lap in laps) + " |")
        print("|---|" + "---:|" * len(laps))
        for key, name in COLUMNS:
            print(f"| {name} | " + " | ".join(str(v) for v in high_water_per_lap(data, key)) + " |")

    if not args.out:
        return 0
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("matplotlib is not installed: table only", file=sys.stderr)
        return 0
    fig, grid = plt.subplots(2, 3, figsize=(13, 7))
    axes = grid.flatten()
    axes[-1].axis("off")
    for ax, (key, name) in zip(axes, COLUMNS):
        for label, data in runs:
            ax.plot(data["frame"], data[key], label=label, linewidth=1)
        ax.set_title(name)
        ax.set_xlabel("frame")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out, dpi=110)
    print(f"\nwrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
