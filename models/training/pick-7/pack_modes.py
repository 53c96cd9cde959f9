# Packs pick_modes_data's per-frame files (FRAME.f32, [4 k + 2 + k, H, W]) of one set into an
# npz beside pick_inputs.py's: `modes` (the input channels that PickLayout::coarse_modes adds,
# float16) and `mode_cands` (the k modes' depths, index units of N = 192, float32), frames A..B
# in order.
# Usage: pack_modes.py DIR A B K DST.npz   (the venv of ../../../../shared/tools/omni_np.py)
import os, sys
import numpy as np

d, a, b, k, dst = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
chans = 4 * k + 2
frames = [np.fromfile(f"{d}/{f:05d}.f32", "<f4").reshape(chans + k, 160, 640) for f in range(a, b + 1)]
modes = np.stack([x[:chans] for x in frames]).astype(np.float16)
cands = np.stack([x[chans:] for x in frames]).astype(np.float32)
np.savez(dst + ".tmp.npz", modes=modes, mode_cands=cands)
os.replace(dst + ".tmp.npz", dst)
print(dst, len(frames), "frames")
