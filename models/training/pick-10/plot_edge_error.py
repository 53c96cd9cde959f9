# Stop 44: edge_error.txt as a figure: for each output in it (ZNCC+SGM, the default, --pick chain),
# the share of the pixels and of the error by distance to the truth's nearest depth edge, and the
# MAE there. Usage: plot_edge_error.py edge_error.txt OUT.png   (a python with matplotlib)
import re, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

names = {"sgm": "ZNCC+SGM", "pick6": "the default (cascade + pick)", "pick8b": "--pick chain"}
blocks, cur = [], None
for line in open(sys.argv[1]):
    m = re.match(r"/\S*/(\w+)-test-things-s7001:", line)
    if m:
        cur = {"name": names.get(m.group(1), m.group(1)), "rows": []}
        blocks.append(cur)
        continue
    parts = [p.strip() for p in line.split("|")]
    if cur and len(parts) == 5 and parts[0].endswith("px") and "side" not in parts[0]:
        cur["rows"].append((parts[0], *map(float, parts[1:4])))
labels = [r[0] for r in blocks[0]["rows"]]
fig, (a, b) = plt.subplots(1, 2, figsize=(11, 3.6))
x = range(len(labels))
a.bar([i - 0.3 for i in x], [r[1] * 100 for r in blocks[0]["rows"]], 0.2, color="0.7", label="share of the pixels")
for k, blk in enumerate(blocks):
    a.bar([i - 0.1 + 0.2 * k for i in x], [r[2] * 100 for r in blk["rows"]], 0.2, label=f"share of the error: {blk['name']}")
    b.plot(list(x), [r[3] for r in blk["rows"]], "o-", label=blk["name"])
for ax in (a, b):
    ax.set_xticks(list(x), labels, rotation=20)
    ax.set_xlabel("distance to the nearest depth edge of the truth")
a.set_ylabel("%")
a.legend(fontsize=7)
b.set_ylabel("MAE there (% of N = 192)")
b.legend(fontsize=8)
fig.suptitle("Held-out things (seed 7001, frames 1-20), scored by the reference's rules at 160 x 640", fontsize=10)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
