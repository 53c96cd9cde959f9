#!/usr/bin/env python3
"""strip_tensors.py SRC DST PREFIX: a safetensors file without the tensors whose names start with PREFIX (stop 37:
cascade-45 e2 without its half-grid selector, `up_mid.`, with `same_grid_selector` false in a copy of its JSON)."""
import json, struct, sys
src, dst, prefix = sys.argv[1], sys.argv[2], sys.argv[3]
b = open(src, "rb").read(); n = struct.unpack("<Q", b[:8])[0]; h = json.loads(b[8:8+n]); d = b[8+n:]
out_h, chunks, off = {}, [], 0
for k, v in h.items():
    if k == "__metadata__": out_h[k] = v; continue
    if k.startswith(prefix): continue
    s, e = v["data_offsets"]; chunks.append(d[s:e]); out_h[k] = dict(v, data_offsets=[off, off + e - s]); off += e - s
hb = json.dumps(out_h).encode(); hb += b" " * ((8 - len(hb) % 8) % 8)
open(dst, "wb").write(struct.pack("<Q", len(hb)) + hb + b"".join(chunks))
