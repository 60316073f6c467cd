#!/usr/bin/python3
"""Map size over time, std vs HOC, from the frames.csv files run_hoc.sh leaves in OUT_DIR.
Usage: tests/benchmarks/hoc/plot_map_size.py OUT_DIR PNG  (needs python3-matplotlib)"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out, png = sys.argv[1], sys.argv[2]
scenes = [s for s in ("static_camera_dynamic", "static_camera_crowd", "moving_camera_dynamic", "relocalization", "room_loop", "fr1_rpy", "augment")
          if os.path.exists(os.path.join(out, s + "_std", "frames.csv"))]
cols = min(3, len(scenes))
rows_n = (len(scenes) + cols - 1) // cols
fig, axes = plt.subplots(rows_n, cols, figsize=(4.2 * cols, 3.2 * rows_n), squeeze=False)
flat = [a for row in axes for a in row]
for a in flat[len(scenes):]:
    a.axis("off")
for ax, s in zip(flat, scenes):
    for variant, style in (("std", "r-"), ("hoc", "g-")):
        rows = list(csv.DictReader(open(os.path.join(out, s + "_" + variant, "frames.csv"))))
        ax.plot([int(r["index"]) for r in rows], [int(r["landmarks"]) for r in rows], style, label=variant.upper() if variant == "hoc" else "std")
    ax.set_title(s.replace("_", " "), fontsize=9)
    ax.set_xlabel("frame")
    ax.grid(alpha=0.3)
for row in axes:
    row[0].set_ylabel("map size [landmarks]")
axes[0][0].legend()
fig.tight_layout()
fig.savefig(png, dpi=80)
