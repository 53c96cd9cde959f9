# Is an estimate's uncertainty map worth anything? Sparsification on validation frames
# 481-500: leave out the most uncertain pixels first (by each `infer` output's _entropy.tiff)
# and report the MAE of the rest (reference rules, percent of N; pixels pooled over the
# frames), beside the oracle (leaving out the largest errors first). Every OUT must hold the
# same depth maps (the first one's are scored); only their uncertainty differs.
# Usage: uncertainty.py DATASET NAME=OUT[:MAP] [NAME=OUT[:MAP] ...]   (MAP: entropy, the default,
# or spread: the maps %05d_MAP.tiff)
import os, sys, numpy as np, tifffile
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o  # noqa: E402

ds = sys.argv[1]
outs = {}
for arg in sys.argv[2:]:
    name, spec = arg.split('=', 1)
    out, _, kind = spec.partition(':')
    outs[name] = (out, kind or 'entropy')
_, _, md = o.load(ds)
unc = {k: [] for k in outs}
errs = []
for f in range(481, 501):
    gi, valid, minv, step = o.reference_gt_index(o.gt_reference(ds, f, 160, 640, 45.0), md)
    first = next(iter(outs.values()))[0]
    pred = o.read_f32_tiff(f'{first}/{f:05d}.tiff')
    errs.append(np.abs((pred - minv) / step - gi)[valid] / 192 * 100)
    for k, (d, kind) in outs.items():
        unc[k].append(tifffile.imread(f'{d}/{f:05d}_{kind}.tiff')[valid])
err = np.concatenate(errs)
print(f'{os.path.basename(ds)}: MAE of all scored pixels {err.mean():.3f}; MAE of the rest after leaving out')
for frac in (0.05, 0.1, 0.2, 0.3):
    keep = int(len(err) * (1 - frac))
    row = [f'{int(frac * 100):3d} %: oracle {np.sort(err)[:keep].mean():.3f}']
    for k, u in unc.items():
        order = np.argsort(np.concatenate(u), kind='stable')
        row.append(f'{k} {err[order[:keep]].mean():.3f}')
    print('  '.join(row))
