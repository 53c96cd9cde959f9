"""The PyTorch parts: the U-Net's convolutions wrapping in longitude, its size and start, the
pick's answer, the weights it writes, a short training run and its resumption, and the second
pick's first-pick loading (skipped where PyTorch is not installed)."""
import os
import sys

import numpy as np
import pytest

torch = pytest.importorskip("torch")

import train_pick as tp  # noqa: E402
import second_inputs as si  # noqa: E402
from pick_common import layout_metadata, read_safetensors, write_safetensors  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
BUNDLED = os.path.join(ROOT, "models", "omnimvs-cascade-pick.safetensors")


@pytest.mark.parametrize("stride", [1, 2])
def test_wrap_conv_against_a_loop(stride):
    torch.manual_seed(0)
    conv = tp.WrapConv(2, 3, stride)
    x = torch.randn(1, 2, 6, 10)
    with torch.no_grad():
        y = conv(x)[0].numpy()
    w, b, a = conv.weight.detach().numpy(), conv.bias.detach().numpy(), x[0].numpy()
    h, wd = 6, 10
    out_h, out_w = (h + 2 - 3) // stride + 1, (wd + 2 - 3) // stride + 1
    assert y.shape == (3, out_h, out_w)
    for o in range(3):
        for yy in range(out_h):
            for xx in range(out_w):
                s = b[o]
                for dy in range(3):
                    r = yy * stride + dy - 1
                    if not 0 <= r < h:
                        continue  # rows: zeros beyond the border
                    for dx in range(3):
                        c = (xx * stride + dx - 1) % wd  # columns wrap in longitude
                        s += (w[o, :, dy, dx] * a[:, r, c]).sum()
                assert y[o, yy, xx] == pytest.approx(s, abs=1e-5)


@pytest.mark.parametrize("width,parameters", [(16, 199143), (8, 51191), (24, 443863)])
def test_unet_size(width, parameters):
    # The parameter counts the bundled width and the half and one-and-a-half widths trained with.
    assert sum(p.numel() for p in tp.UNet(29, width).parameters()) == parameters


def test_a_fresh_pick_starts_on_the_answer():
    net = tp.UNet(29, 4)
    with torch.no_grad():
        weights = torch.softmax(net(torch.randn(1, 29, 16, 32)), 1)
    assert weights.shape == (1, tp.K, 16, 32)
    start = 1 / (1 + (tp.K - 1) * np.exp(-5.0))  # bias 0 on the answer, -5 on the others
    assert start == pytest.approx(0.9612, abs=1e-4)
    np.testing.assert_allclose(weights[0, 0].numpy(), start, rtol=1e-6)


def test_the_answer_stays_among_its_candidates():
    rng = np.random.default_rng(10)
    v = rng.uniform(0, 191, size=(1, 16, 32)).astype(np.float32)
    c = torch.as_tensor(tp.cands(v))
    r = tp.answer(torch.randn(1, tp.K, 16, 32) * 5, c)
    assert (r >= c.min(1).values - 1e-4).all() and (r <= c.max(1).values + 1e-4).all()
    # All weight on one candidate: that candidate.
    logits = torch.full((1, tp.K, 16, 32), -1e4)
    logits[:, 3] = 0
    torch.testing.assert_close(tp.answer(logits, c), c[:, 3])


def test_save_safetensors_writes_the_bundled_file_again(tmp_path):
    state, metadata = tp.load_state(BUNDLED)
    assert metadata == tp.layout()
    net = tp.UNet(29, tp.width_of(state))
    net.load_state_dict(state)
    out = str(tmp_path / "pick.safetensors")
    tp.save_safetensors(net, out, tp.layout())
    with open(out, "rb") as a, open(BUNDLED, "rb") as b:
        assert a.read() == b.read()


def test_safetensors_path():
    assert tp.safetensors_path("/a/b.pt/pick6.pt") == "/a/b.pt/pick6.safetensors"
    assert tp.safetensors_path("pick") == "pick.safetensors"


def write_frames(path, frames, rng, h=64, w=32, channels=29):
    v = rng.uniform(10, 180, size=(frames, h, w)).astype(np.float32)
    gt = (v + rng.normal(0, 3, size=v.shape)).astype(np.float32)
    gt[:, :4] = -1e-3  # a band of sky (just below index 0)
    gt[:, 4, :3] = -1.0  # a hole
    feats = rng.normal(size=(frames, channels, h, w)).astype(np.float16)
    np.savez(path, feats=feats, v=v, gt=gt, valid=(gt >= 0) & (gt <= 192))


def run_main(monkeypatch, capsys, args):
    monkeypatch.setattr(sys, "argv", ["train_pick.py"] + [str(a) for a in args])
    tp.main()
    return capsys.readouterr().out


def test_a_short_run_writes_and_resumes(tmp_path, monkeypatch, capsys):
    rng = np.random.default_rng(11)
    train, val = tmp_path / "f-a.npz", tmp_path / "v-a.npz"
    write_frames(train, 3, rng)
    write_frames(val, 1, rng)
    out = tmp_path / "p.pt"
    log = run_main(monkeypatch, capsys, [3, train, val, 2, out, 1])
    lines = log.strip().splitlines()
    assert lines[0].startswith("parameters") and "inputs 29 train frames 3" in lines[0]
    assert lines[1].startswith("0 s 0 v-a ") and lines[2].startswith("3 s ")
    for suffix in ("", ".ckpt"):
        assert os.path.exists(str(out) + suffix)
    tensors, metadata = read_safetensors(str(tmp_path / "p.safetensors"))
    assert metadata == layout_metadata((1, 2, 4), (2,), 0)
    assert list(tensors["e0.0.0.weight"].shape) == [2, 29, 3, 3]
    assert list(tensors["head.weight"].shape) == [7, 2, 3, 3]
    first = (tmp_path / "p.safetensors").read_bytes()
    # Started again with the same arguments: it resumes after its last step, and changes nothing.
    log = run_main(monkeypatch, capsys, [3, train, val, 2, out, 1])
    assert "resumed after step 3" in log
    assert (tmp_path / "p.safetensors").read_bytes() == first
    # A second run from scratch draws the same bands: the same weights.
    again = tmp_path / "q.pt"
    run_main(monkeypatch, capsys, [3, train, val, 2, again, 1])
    assert (tmp_path / "q.safetensors").read_bytes() == first


def test_init_from_safetensors_and_sky_weight(tmp_path, monkeypatch, capsys):
    rng = np.random.default_rng(12)
    train, val = tmp_path / "f-a.npz", tmp_path / "v-a.npz"
    write_frames(train, 2, rng)
    write_frames(val, 1, rng)
    monkeypatch.setenv("PICK_INIT", BUNDLED)
    monkeypatch.setattr(tp, "SKY_WEIGHT", 0.25)
    log = run_main(monkeypatch, capsys, [1, train, val, 16, tmp_path / "p.pt", 1])
    assert "parameters 199143" in log
    state, _ = read_safetensors(str(tmp_path / "p.safetensors"))
    bundled, _ = read_safetensors(BUNDLED)
    # One step at the schedule's low start rate: near the bundled weights, not equal to them.
    diff = max(np.abs(state[k] - bundled[k]).max() for k in state)
    assert 0 < diff < 1e-3


def test_first_pick_loading(tmp_path):
    net = si.first_pick(BUNDLED)
    assert sum(p.numel() for p in net.parameters()) == 199143
    rng = np.random.default_rng(13)
    v = rng.uniform(10, 180, size=(16, 32)).astype(np.float32)
    r = si.pick_answer(net, rng.normal(size=(29, 16, 32)).astype(np.float16), v)
    c = tp.cands(v[None])[0]
    assert r.shape == v.shape and (r >= c.min(0) - 1e-3).all() and (r <= c.max(0) + 1e-3).all()
    tensors, _ = read_safetensors(BUNDLED)
    other = str(tmp_path / "wide.safetensors")
    write_safetensors(tensors, other, layout_metadata((1, 2, 4, 7, 12), (2,), 0))
    with pytest.raises(SystemExit):
        si.first_pick(other)
