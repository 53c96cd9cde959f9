# A top-down view of what `infer --snap-edges` changes: the points of the 160x640 rows within
# +-LAT degrees of the horizon (a 2D scan, as a robot's obstacle map would take it), seen from
# above, for the ground truth, the network's answer and the same with --snap-edges; points in
# the free space between two surfaces are the blends the option removes.
# Usage: bird_view.py DATASET FRAME NET_OUT SNAP_OUT OUT.png [RANGE_M [LAT_DEG]]
import os, sys, numpy as np
from PIL import Image, ImageDraw
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..'))
from studylib import o  # noqa: E402

ds, frame, net_dir, snap_dir, dst = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4], sys.argv[5]
rng = float(sys.argv[6]) if len(sys.argv) > 6 else 6.0
lat = float(sys.argv[7]) if len(sys.argv) > 7 else 10.0
h, w, size = 160, 640, 420
R = o.rays(h, w, 45.0).reshape(3, h, w)
rows = np.abs(np.linspace(-45, 45, h)) <= lat


def panel(inv, title):
    img = Image.new('RGB', (size, size + 22), (255, 255, 255))
    d = ImageDraw.Draw(img)
    d.text((6, 4), title, fill=(0, 0, 0))
    ok = np.isfinite(inv) & (inv > 1e-3) & rows[:, None]
    X = R[:, ok] / inv[ok]
    near = np.hypot(X[0], X[2]) <= rng
    px = ((X[0][near] / rng + 1) / 2 * (size - 1)).astype(int)
    pz = ((1 - (X[2][near] / rng + 1) / 2) * (size - 1)).astype(int) + 22
    for x, z in zip(px, pz):
        d.point((x, z), fill=(20, 20, 120))
    c = size // 2
    d.ellipse((c - 3, c + 22 - 3, c + 3, c + 22 + 3), fill=(200, 0, 0))  # the rig
    return img


gt = o.gt_reference(ds, frame, h, w, 45.0)
net = o.read_f32_tiff(f'{net_dir}/{frame:05d}.tiff')
snap = o.read_f32_tiff(f'{snap_dir}/{frame:05d}.tiff')
panels = [panel(gt, 'ground truth'), panel(net, 'network'), panel(snap, 'network, --snap-edges')]
out = Image.new('RGB', (3 * size + 20, size + 22), (255, 255, 255))
for i, p in enumerate(panels):
    out.paste(p, (i * (size + 10), 0))
out.save(dst + '.tmp.png')
os.replace(dst + '.tmp.png', dst)
print(dst, f'{rng} m around the rig, rows within +-{lat} degrees of the horizon')
