# Upper bounds at 160x640 (reference rules): the truth itself shifted or degraded to a coarser grid and
# bilinearly upsampled back, scored as a network answer is. Usage: truth_bounds.py DATASET A B
import sys, numpy as np
sys.path.insert(0, "/work/shared/tools")
import omni_np as o
ds = sys.argv[1]; a, b = int(sys.argv[2]), int(sys.argv[3])
_, _, md = o.load(ds)
def down(gt, f, mode):
    h, w = gt.shape
    if mode == "nearest":
        return gt[f//2::f, f//2::f]
    return gt.reshape(h//f, f, w//f, f).mean(axis=(1, 3))
rows = {}
for fr in range(a, b + 1):
    gt = o.gt_reference(ds, fr, 160, 640, 45.0)
    cands = {
        "shift1col": np.roll(gt, 1, axis=1),
        "shift2col": np.roll(gt, 2, axis=1),
        "half-grid mean, bilinear up": o.upsample(down(gt, 2, "mean"), 160, 640),
        "quarter-grid mean, bilinear up": o.upsample(down(gt, 4, "mean"), 160, 640),
        "half-grid sample, bilinear up": o.upsample(down(gt, 2, "nearest"), 160, 640),
        "quarter-grid sample, bilinear up": o.upsample(down(gt, 4, "nearest"), 160, 640),
    }
    for k, p in cands.items():
        rows.setdefault(k, []).append(o.metrics_reference(p, gt, md))
for k, r in rows.items():
    print(f"{k:36s}", " ".join(f"{m}={np.mean([x[m] for x in r]):.2f}" for m in [">1", ">3", ">5", "MAE", "RMS"]))
