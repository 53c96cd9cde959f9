"""The weights file the trainer writes and `PickRefiner::from_bytes` reads
(crates/omnimvs-net/src/pick.rs): the byte layout, the layout metadata, the module names and
shapes, checked with a parser written here and against the bundled picks."""
import json
import os
import struct

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
from pick_common import layout_metadata, read_safetensors, write_safetensors

BUNDLED = [os.path.join(ROOT, "models", f) for f in
           ("omnimvs-cascade-pick.safetensors", "omnimvs-cascade-pick2.safetensors")]


def parse(path):
    """An independent reading of a safetensors file: header length, header (in order), body."""
    with open(path, "rb") as f:
        data = f.read()
    (n,) = struct.unpack("<Q", data[:8])
    return n, json.loads(data[8:8 + n].decode("utf-8"), object_pairs_hook=lambda kv: kv), data[8 + n:]


def pick_shapes(inputs, width, candidates):
    """The tensors PickRefiner::from_bytes asks for: name -> shape (3 x 3 convolutions)."""
    w, out = width, {}
    for name, c_in, c_out in [
            ("e0.0.0", inputs, w), ("e0.1.0", w, w), ("e1.0.0", w, 2 * w), ("e1.1.0", 2 * w, 2 * w),
            ("e2.0.0", 2 * w, 3 * w), ("e2.1.0", 3 * w, 3 * w), ("e3.0.0", 3 * w, 4 * w),
            ("e3.1.0", 4 * w, 4 * w), ("d2.0", 7 * w, 3 * w), ("d1.0", 5 * w, 2 * w),
            ("d0.0", 3 * w, w), ("head", w, candidates)]:
        out[name + ".weight"] = [c_out, c_in, 3, 3]
        out[name + ".bias"] = [c_out]
    return out


def rust_layout(metadata):
    """PickLayout::from_metadata's reading: comma-separated integers, defaults where absent."""
    ints = lambda key, default: [int(t.strip()) for t in metadata[key].split(",")] if key in metadata else default
    radii, depth, zncc = ints("candidate_radii", [1, 2, 4]), ints("depth_radii", [2]), ints("zncc", [0])
    modes = ints("coarse_modes", [0])
    assert all(1 <= r <= 64 for r in radii + depth) and radii
    assert len(zncc) == 1 and (zncc[0] == 0 or (zncc[0] % 2 == 1 and zncc[0] <= 31))
    assert len(modes) == 1 and modes[0] <= 8
    return radii, depth, zncc[0], modes[0]


def test_layout_on_disk(tmp_path):
    tensors = {"b": np.arange(6, dtype=np.float32).reshape(2, 3), "a": np.array([1.5], np.float64)}
    path = str(tmp_path / "x.safetensors")
    write_safetensors(tensors, path, {"candidate_radii": "1,2,4", "zncc": "0"})
    n, header, body = parse(path)
    assert n % 8 == 0
    names = [k for k, _ in header]
    assert names == ["__metadata__", "b", "a"]  # the metadata first, then the tensors in order
    assert dict(header[0][1]) == {"candidate_radii": "1,2,4", "zncc": "0"}
    entries = {k: dict(e) for k, e in header[1:]}
    assert entries["b"] == {"dtype": "F32", "shape": [2, 3], "data_offsets": [0, 24]}
    assert entries["a"] == {"dtype": "F32", "shape": [1], "data_offsets": [24, 28]}
    assert len(body) == 28
    assert struct.unpack("<6f", body[:24]) == (0, 1, 2, 3, 4, 5)
    assert struct.unpack("<f", body[24:]) == (1.5,)
    assert not os.path.exists(path + ".tmp")
    back, metadata = read_safetensors(path)
    assert list(back) == ["b", "a"] and metadata == {"candidate_radii": "1,2,4", "zncc": "0"}
    np.testing.assert_array_equal(back["b"], tensors["b"])


def test_no_metadata(tmp_path):
    path = str(tmp_path / "y.safetensors")
    write_safetensors({"t": np.zeros((2, 2), np.float32)}, path)
    _, header, _ = parse(path)
    assert [k for k, _ in header] == ["t"]
    assert read_safetensors(path)[1] == {}


def test_layout_metadata():
    assert layout_metadata((1, 2, 4), (2,), 0) == {"candidate_radii": "1,2,4", "depth_radii": "2", "zncc": "0"}
    wide = layout_metadata((1, 2, 4, 7, 12), (2, 12), 5, 3)
    assert wide == {"candidate_radii": "1,2,4,7,12", "depth_radii": "2,12", "zncc": "5", "coarse_modes": "3"}
    assert rust_layout(wide) == ([1, 2, 4, 7, 12], [2, 12], 5, 3)


@pytest.mark.parametrize("path", BUNDLED)
def test_bundled_picks_rewritten_byte_for_byte(tmp_path, path):
    tensors, metadata = read_safetensors(path)
    assert metadata == layout_metadata((1, 2, 4), (2,), 0)
    radii, depth, zncc, modes = rust_layout(metadata)
    candidates = 1 + 2 * len(radii) + modes
    inputs = 2 + 3 * len(depth) + 2 * 4 * (1 + 2 * len(depth))  # four cameras
    expected = pick_shapes(inputs, 16, candidates)
    assert list(tensors) == list(expected)
    assert {k: list(a.shape) for k, a in tensors.items()} == expected
    out = str(tmp_path / "again.safetensors")
    write_safetensors(tensors, out, metadata)
    with open(out, "rb") as a, open(path, "rb") as b:
        assert a.read() == b.read()


def test_the_safetensors_library_reads_it(tmp_path):
    st = pytest.importorskip("safetensors.numpy")
    tensors = {"w": np.random.default_rng(9).normal(size=(3, 2, 3, 3)).astype(np.float32)}
    path = str(tmp_path / "z.safetensors")
    write_safetensors(tensors, path, {"zncc": "5"})
    np.testing.assert_array_equal(st.load_file(path)["w"], tensors["w"])
