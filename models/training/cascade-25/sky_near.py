# Phantom obstacles in the sky: among the pixels within +-LAT degrees of the horizon, the share
# that is sky in the truth, the share of those sky pixels (and of the non-sky pixels farther than
# RANGE m) that an `infer` output answers within RANGE m, and the share of those near-answered
# sky pixels (and of every non-sky pixel) whose uncertainty is above a bound, i.e. that
# `infer --max-entropy NATS` (BOUND entropy:NATS, the default entropy:2.6) or `infer --max-spread
# UNITS` (spread:UNITS) leaves without an answer.
# Usage: sky_near.py DATASET OUT FIRST LAST [RANGE_M [LAT_DEG [BOUND]]]
import os, sys, numpy as np, tifffile
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o  # noqa: E402

ds, out, a, b = sys.argv[1], sys.argv[2], int(sys.argv[3]), int(sys.argv[4])
rng = float(sys.argv[5]) if len(sys.argv) > 5 else 6.0
lat = float(sys.argv[6]) if len(sys.argv) > 6 else 10.0
kind, bound = (sys.argv[7] if len(sys.argv) > 7 else 'entropy:2.6').split(':')
bound = float(bound)
rows = np.abs(np.linspace(-45, 45, 160)) <= lat
sky_all, sky_near, far_near, left_sky, left_rest = [], [], [], [], []
for f in range(a, b + 1):
    gt = o.gt_reference(ds, f, 160, 640, 45.0)[rows]
    net = o.read_f32_tiff(f'{out}/{f:05d}.tiff')[rows]
    unc = tifffile.imread(f'{out}/{f:05d}_{kind}.tiff')[rows]
    sky = gt < 1e-3
    near = net > 1 / rng
    far = ~sky & (gt < 1 / rng)
    sky_all.append(sky.ravel()); sky_near.append(near[sky]); far_near.append(near[far])
    left_sky.append(unc[sky & near] > bound); left_rest.append(unc[~sky] > bound)
cat = np.concatenate
print(f'frames {a}-{b}, rows within +-{lat} degrees: sky {100 * cat(sky_all).mean():.1f} % of the pixels; '
      f'answered within {rng} m: {100 * cat(sky_near).mean():.1f} % of the sky pixels, '
      f'{100 * cat(far_near).mean():.1f} % of the non-sky ones farther than {rng} m; '
      f'{kind} above {bound:g}: {100 * cat(left_sky).mean():.1f} % of the sky pixels answered near, '
      f'{100 * cat(left_rest).mean():.1f} % of the non-sky pixels')
