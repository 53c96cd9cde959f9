# What the misses near depth edges are: for pixels within 4 px of a depth discontinuity of the
# truth whose |error| > 5 index units, the local foreground (largest true index in the 9x9
# window) and background (smallest); the answer is "the other side" when within 3 of the side
# the pixel does not belong to, "a blend" when strictly between the two sides (more than 3 from
# both), "neither" otherwise. Usage: edge_kinds.py DATASET FRAME,... NAME=DIR ...
import sys, os, numpy as np, scipy.ndimage as nd, tifffile
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o, truth  # noqa: E402
ds = sys.argv[1]; frames = [int(x) for x in sys.argv[2].split(',')]
cfg, cams, md = o.load(ds)
res = {}
for fr in frames:
    gi, valid, dist = truth(ds, fr, md)
    fg = nd.maximum_filter(np.where(valid, gi, -1e9), size=9, mode=('nearest', 'wrap'))
    bg = nd.minimum_filter(np.where(valid, gi, 1e9), size=9, mode=('nearest', 'wrap'))
    near = valid & (dist < 4)
    is_fg = np.abs(gi - fg) <= np.abs(gi - bg)
    for spec in sys.argv[3:]:
        name, d = spec.split('=')
        p = tifffile.imread(f'{d}/{fr:05d}_index.tiff').astype(np.float64)
        e = np.abs(p - gi)
        miss = near & (e > 5)
        other = np.where(is_fg, np.abs(p - bg) <= 3, np.abs(p - fg) <= 3)
        lo, hi = np.minimum(fg, bg), np.maximum(fg, bg)
        blend = (p > lo + 3) & (p < hi - 3) & ~other
        r = res.setdefault(name, dict(near=0, miss=0, err=0.0, fg_miss=0, bg_miss=0, other=0, blend=0, neither=0, e_other=0.0, e_blend=0.0, e_neither=0.0))
        r['near'] += near.sum(); r['miss'] += miss.sum(); r['err'] += e[near].sum()
        r['fg_miss'] += (miss & is_fg).sum(); r['bg_miss'] += (miss & ~is_fg).sum()
        for k, m in (('other', other), ('blend', blend), ('neither', ~other & ~blend)):
            r[k] += (miss & m).sum(); r['e_' + k] += e[miss & m].sum()
for name, r in res.items():
    m = max(r['miss'], 1)
    print(f"{name}: near-edge pixels {r['near']}, MAE there {r['err'] / r['near']:.2f}, |err| > 5: {100 * r['miss'] / r['near']:.1f} %"
          f" (on the foreground side {100 * r['fg_miss'] / m:.0f} %, background {100 * r['bg_miss'] / m:.0f} %)")
    for k in ('other', 'blend', 'neither'):
        print(f"   {k:8s} {100 * r[k] / m:5.1f} % of the misses, {100 * r['e_' + k] / max(r['err'], 1):5.1f} % of the near-edge error")
