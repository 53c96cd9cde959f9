# The parts of the pick trainer that need numpy and scipy only (train_pick.py re-exports them):
#   - minmax(): the minimum and maximum over a window wrapping in longitude, which the
#     candidates and pick_inputs.py's depths share;
#   - candidates(): the answers a pick chooses among, per pixel: the answer v, then the minimum
#     and maximum of the answers over the (2 r + 1)^2 pixels around for each radius r (columns
#     wrap in longitude, rows stop at the border); `PickLayout::candidate_maps` in Rust;
#   - layout_metadata(): a pick's layout as the strings of its safetensors' `__metadata__`,
#     which `PickLayout::from_metadata` parses (comma-separated integers);
#   - write_safetensors() / read_safetensors(): the weights file `PickRefiner::from_bytes` reads:
#     an 8-byte little-endian header length, a JSON header (`__metadata__` first, then each
#     tensor's dtype "F32", shape and data_offsets, in order), padded with spaces to a multiple
#     of 8 bytes, then the tensors' little-endian float32 values back to back.
import json
import os
import struct
from collections import OrderedDict

import numpy as np
from scipy import ndimage


def minmax(v, k):
    """The minimum and maximum of v (..., H, W) over the k x k pixels around each pixel (k odd),
    each leading axis on its own: columns wrap in longitude, rows stop at the border."""
    p = k // 2
    size = (1,) * (v.ndim - 2) + (k, k)
    vp = np.concatenate([v[..., -p:], v, v[..., :p]], -1)
    mn = ndimage.minimum_filter(vp, size=size, mode="nearest")[..., p:-p]
    mx = ndimage.maximum_filter(vp, size=size, mode="nearest")[..., p:-p]
    return mn, mx


def candidates(v, radii):
    """v (B, H, W) -> (B, 1 + 2 len(radii), H, W): v, then the minimum and maximum over
    (2 r + 1)^2 pixels for each r in radii (minmax)."""
    out = [v]
    for r in radii:
        out.extend(minmax(v, 2 * r + 1))
    return np.stack(out, 1)


def layout_metadata(candidate_radii, depth_radii, zncc, coarse_modes=0):
    """A pick's layout as safetensors metadata (string values); `coarse_modes` only when set."""
    out = {"candidate_radii": ",".join(str(int(r)) for r in candidate_radii),
           "depth_radii": ",".join(str(int(r)) for r in depth_radii), "zncc": str(int(zncc))}
    if coarse_modes:
        out["coarse_modes"] = str(int(coarse_modes))
    return out


def write_safetensors(tensors, path, metadata=None):
    """Writes `tensors` (name -> array, in order) as float32 safetensors with `metadata` (a dict
    of strings, or None for none). Written beside `path` first, then renamed."""
    arrays = OrderedDict((k, np.ascontiguousarray(a, dtype="<f4")) for k, a in tensors.items())
    header, off = ({"__metadata__": metadata} if metadata else {}), 0
    for k, a in arrays.items():
        header[k] = {"dtype": "F32", "shape": list(a.shape), "data_offsets": [off, off + a.nbytes]}
        off += a.nbytes
    h = json.dumps(header).encode()
    h += b" " * ((8 - len(h) % 8) % 8)
    with open(path + ".tmp", "wb") as f:
        f.write(struct.pack("<Q", len(h))); f.write(h)
        for a in arrays.values():
            f.write(a.tobytes())
    os.replace(path + ".tmp", path)


def read_safetensors(path):
    """A float32 safetensors file's tensors (name -> array, in the header's order) and its
    metadata (a dict, empty without one)."""
    with open(path, "rb") as f:
        data = f.read()
    n = struct.unpack("<Q", data[:8])[0]
    header = json.loads(data[8:8 + n], object_pairs_hook=OrderedDict)
    metadata = dict(header.pop("__metadata__", {}))
    body, tensors = data[8 + n:], OrderedDict()
    for k, e in header.items():
        if e["dtype"] != "F32":
            raise ValueError(f"{path}: tensor {k} is {e['dtype']}, not F32")
        a, b = e["data_offsets"]
        tensors[k] = np.frombuffer(body[a:b], dtype="<f4").reshape(e["shape"]).copy()
    return tensors, metadata
