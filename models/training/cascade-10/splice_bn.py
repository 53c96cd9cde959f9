#!/usr/bin/env python3
"""Puts one weights file's batch-norm running statistics into another's tensors (safetensors,
standard library only): how cascade-10's first try was taken apart.

    python3 splice_bn.py WEIGHTS_FROM STATS_FROM OUT.safetensors

WEIGHTS_FROM gives every tensor but `*.running_mean` / `*.running_var`, which come from
STATS_FROM; the .json beside WEIGHTS_FROM is copied beside OUT. Used as
    splice_bn.py /work/runs/cascade-10-bnbatch/model.safetensors \
        /work/runs/cascade-9-epoch1.safetensors /work/runs/splice-w10e1-bn9.safetensors
then validated on cascade-10's 40 frames (a run with --init OUT --stop-after 0).
"""
import json
import shutil
import struct
import sys


def load(path):
    data = open(path, "rb").read()
    n = struct.unpack("<Q", data[:8])[0]
    return data, n, json.loads(data[8:8 + n])


def main():
    src, stats, out = sys.argv[1:4]
    a, na, ha = load(src)
    b, nb, hb = load(stats)
    spliced = bytearray(a)
    for name, meta in ha.items():
        if name == "__metadata__" or "running" not in name:
            continue
        s, e = meta["data_offsets"]
        s2, e2 = hb[name]["data_offsets"]
        if e - s != e2 - s2:
            raise SystemExit(f"{name}: {e - s} bytes in {src}, {e2 - s2} in {stats}")
        spliced[8 + na + s:8 + na + e] = b[8 + nb + s2:8 + nb + e2]
    open(out, "wb").write(spliced)
    shutil.copy(src[: -len(".safetensors")] + ".json", out[: -len(".safetensors")] + ".json")


if __name__ == "__main__":
    main()
