# Curves of pick-1 from its log (train_pick.py's lines: step, seconds, loss, then per validation set
# "name before->after"): the training loss and each set's validation MAE (reference rules) before
# and after the pick. Usage: plot_log.py train.log curves.png
import re, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt

steps, loss, sets = [], [], {}
for line in open(sys.argv[1]):
    m = re.match(r"(\d+) s (\d+) (?:loss ([\d.]+) )?(.*)", line)
    if not m or "->" not in line:
        continue
    step = int(m.group(1))
    if m.group(3):
        steps.append(step); loss.append(float(m.group(3)))
    for name, before, after in re.findall(r"(\S+) ([\d.]+)->([\d.]+)", m.group(4)):
        sets.setdefault(name, ([], [], []))
        sets[name][0].append(step); sets[name][1].append(float(before)); sets[name][2].append(float(after))
fig, ax = plt.subplots(1, 2, figsize=(11, 4))
ax[0].plot(steps, loss, "o-"); ax[0].set_xlabel("step"); ax[0].set_ylabel("training L1 (index units)")
for name, (s, b, a) in sets.items():
    line, = ax[1].plot(s, a, "o-", label=f"{name} with the pick")
    ax[1].axhline(b[0], ls="--", color=line.get_color(), lw=0.8)
ax[1].set_xlabel("step"); ax[1].set_ylabel("validation MAE, % of N (dashed: the network alone)")
ax[1].legend(fontsize=8)
fig.tight_layout(); fig.savefig(sys.argv[2], dpi=90)
