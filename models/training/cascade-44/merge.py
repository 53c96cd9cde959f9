#!/usr/bin/env python3
"""Merges two networks trained from the same start on disjoint parts: every tensor of BASE,
and the tensors of EXTRA whose names start with one of PREFIXES (comma-separated), which BASE
must not have or must hold unchanged from the common start. Writes OUT.safetensors and
OUT.json (EXTRA's configuration, which has the parts BASE lacks).

    python3 merge.py BASE.safetensors EXTRA.safetensors PREFIXES OUT
"""
import json
import struct
import sys


def read(path):
    data = open(path, 'rb').read()
    n = struct.unpack('<Q', data[:8])[0]
    header = json.loads(data[8:8 + n])
    meta = header.pop('__metadata__', None)
    tensors = {}
    for name, info in header.items():
        start, end = info['data_offsets']
        tensors[name] = (info['dtype'], info['shape'], data[8 + n + start:8 + n + end])
    return meta, tensors


def write(path, meta, tensors):
    header, blobs, offset = {}, [], 0
    if meta is not None:
        header['__metadata__'] = meta
    for name in sorted(tensors):
        dtype, shape, blob = tensors[name]
        header[name] = {'dtype': dtype, 'shape': shape, 'data_offsets': [offset, offset + len(blob)]}
        blobs.append(blob)
        offset += len(blob)
    text = json.dumps(header, separators=(',', ':')).encode()
    text += b' ' * (-len(text) % 8)
    tmp = path + '.tmp'
    with open(tmp, 'wb') as f:
        f.write(struct.pack('<Q', len(text)))
        f.write(text)
        for blob in blobs:
            f.write(blob)
    import os
    os.replace(tmp, path)


base_path, extra_path, prefixes, out = sys.argv[1], sys.argv[2], sys.argv[3].split(','), sys.argv[4]
meta, base = read(base_path)
_, extra = read(extra_path)
taken = [k for k in extra if any(k.startswith(p) for p in prefixes)]
clash = [k for k in taken if k in base]
if clash:
    sys.exit(f'{base_path} has {clash[:3]}...: not disjoint parts')
for k in taken:
    base[k] = extra[k]
write(out + '.safetensors', meta, base)
config = json.load(open(extra_path[:-len('.safetensors')] + '.json'))
tmp = out + '.json.tmp'
json.dump(config, open(tmp, 'w'), indent=2)
import os
os.replace(tmp, out + '.json')
print(f'{out}.safetensors: {len(base)} tensors ({len(taken)} from {extra_path})')
