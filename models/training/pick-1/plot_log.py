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
    # "name before->after", then from pick-2 on " (sky before->after)": the with-sky figures, a
    # series of their own ("name, sky").
    for name, before, after, sky_before, sky_after in re.findall(
            r"(\S+) ([\d.]+)->([\d.]+)(?: \(sky ([\d.]+)->([\d.]+)\))?", m.group(4)):
        for key, b, a in ((name, before, after), (name + ", sky", sky_before, sky_after)):
            if not a:
                continue
            sets.setdefault(key, ([], [], []))
            sets[key][0].append(step); sets[key][1].append(float(b)); sets[key][2].append(float(a))
fig, ax = plt.subplots(1, 2, figsize=(11, 4))
ax[0].plot(steps, loss, "o-"); ax[0].set_xlabel("step"); ax[0].set_ylabel("training L1 (index units)")
for name, (s, b, a) in sets.items():
    line, = ax[1].plot(s, a, "o:" if name.endswith("sky") else "o-", label=f"{name} with the pick")
    ax[1].axhline(b[0], ls="--", color=line.get_color(), lw=0.8)
ax[1].set_xlabel("step"); ax[1].set_ylabel("validation MAE, % of N (dashed: the network alone)")
ax[1].legend(fontsize=8)
fig.tight_layout(); fig.savefig(sys.argv[2], dpi=90)
