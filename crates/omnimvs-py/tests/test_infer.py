"""omnimvs.infer (the bundled networks and weights files) against the TIFF that
`omnimvs infer` writes, images given as arrays, and bad input."""

from pathlib import Path

import numpy as np
import pytest
import tifffile

import omnimvs

MODEL = Path(__file__).resolve().parents[3] / "models" / "omnimvs-tiny.safetensors"


@pytest.fixture(scope="module")
def itbt(itbt_path):
    return omnimvs.Dataset(itbt_path)


@pytest.fixture(scope="module")
def itbt_net(itbt):
    """The default bundled model, the cascade."""
    return omnimvs.infer(itbt, 1)


@pytest.fixture(scope="module")
def itbt_tiny(itbt):
    """The bundled `tiny`, the paper's network, small."""
    return omnimvs.infer(itbt, 1, weights="tiny")


def test_equals_the_tiff_of_the_command_line(itbt_path, itbt_net, cli, tmp_path):
    cli("infer", itbt_path, "--frames", 1, "--out", tmp_path)
    expected = tifffile.imread(tmp_path / "00001.tiff")
    assert itbt_net.dtype == np.float32
    assert itbt_net.shape == expected.shape == (160, 640)
    np.testing.assert_allclose(itbt_net, expected, rtol=1e-5, atol=1e-6)


def test_is_a_plausible_depth_map(itbt, itbt_net):
    assert np.isfinite(itbt_net).all()
    assert itbt_net.min() >= 0 and itbt_net.max() <= 1 / itbt.min_depth + 1e-6
    assert itbt_net.std() > 0.05


def test_weights_file_is_the_bundled_model(itbt, itbt_tiny):
    np.testing.assert_array_equal(omnimvs.infer(itbt, 1, weights=MODEL), itbt_tiny)
    np.testing.assert_array_equal(omnimvs.infer(itbt, 1, str(MODEL)), itbt_tiny)


def test_images_as_arrays_with_a_rig(itbt_path, itbt, itbt_net):
    rig = omnimvs.Rig.from_config(itbt_path)
    np.testing.assert_array_equal(omnimvs.infer(itbt.images(1), rig=rig), itbt_net)


def test_sunny_rig(sunny_path):
    out = omnimvs.infer(omnimvs.Dataset(sunny_path), 1)
    assert out.shape == (160, 640) and np.isfinite(out).all()


def test_bad_input(itbt, tmp_path):
    missing = tmp_path / "no-such-weights.safetensors"
    with pytest.raises(FileNotFoundError, match="weights .*no-such-weights"):
        omnimvs.infer(itbt, 1, weights=missing)
    with pytest.raises(ValueError, match="backend"):
        omnimvs.infer(itbt, 1, backend="abacus")
    with pytest.raises(FileNotFoundError, match="frame 7"):
        omnimvs.infer(itbt, 7)
    images = itbt.images(1)
    with pytest.raises(ValueError, match=r"images\[2\].*uint16"):
        omnimvs.infer([*images[:2], images[2].astype(np.uint16), images[3]], rig=itbt.rig)


def test_bundled_models_by_name(itbt, itbt_net, itbt_tiny):
    # The default bundled model is the cascade; both bundled models can be named.
    np.testing.assert_array_equal(omnimvs.infer(itbt, 1, weights="cascade"), itbt_net)
    assert itbt_tiny.dtype == np.float32 and itbt_tiny.shape == (32, 128)
    assert np.isfinite(itbt_tiny).all() and itbt_tiny.min() >= 0
    assert itbt_tiny.max() <= 1 / itbt.min_depth + 1e-6
    assert itbt_tiny.std() > 0.05


def test_snap_edges(itbt_path, itbt, itbt_net, cli, tmp_path):
    snapped = omnimvs.infer(itbt, 1, snap_edges=8)
    moved = snapped != itbt_net
    # Depth edges are a minority of the pixels, and there are some in a room with people.
    assert 0 < moved.mean() < 0.25
    # Every moved pixel took the answer of a pixel of its 3x3 neighbourhood, the nearer of
    # the neighbourhood's two extremes (rows clamped, longitude wrapped).
    padded = np.pad(itbt_net, ((1, 1), (0, 0)), mode="edge")
    shifts = np.stack(
        [np.roll(padded, dx, axis=1)[1 + dy:161 + dy] for dy in (-1, 0, 1) for dx in (-1, 0, 1)]
    )
    lo, hi = shifts.min(0), shifts.max(0)
    nearer = np.where(itbt_net - lo < hi - itbt_net, lo, hi)
    np.testing.assert_allclose(snapped[moved], nearer[moved], rtol=1e-5)
    # The command line's --snap-edges (8 when given alone) writes the same map.
    cli("infer", itbt_path, "--frames", 1, "--snap-edges", "--out", tmp_path)
    expected = tifffile.imread(tmp_path / "00001.tiff")
    np.testing.assert_allclose(snapped, expected, rtol=1e-5, atol=1e-6)
    for bad in (0, -3, 101, float("nan")):
        with pytest.raises(ValueError, match="snap_edges"):
            omnimvs.infer(itbt, 1, snap_edges=bad)


def test_max_entropy(itbt, itbt_net):
    # Above the largest entropy nothing is left; at 0 (nearly) everything is; in between, the
    # pixels left are NaN and the others keep the default answer.
    np.testing.assert_array_equal(omnimvs.infer(itbt, 1, max_entropy=100.0), itbt_net)
    assert np.isnan(omnimvs.infer(itbt, 1, max_entropy=0.0)).mean() > 0.99
    some = omnimvs.infer(itbt, 1, max_entropy=1.8)
    left = np.isnan(some)
    assert 0.01 < left.mean() < 0.5
    np.testing.assert_array_equal(some[~left], itbt_net[~left])
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(ValueError, match="max_entropy"):
            omnimvs.infer(itbt, 1, max_entropy=bad)


def test_max_spread(itbt, itbt_net):
    np.testing.assert_array_equal(omnimvs.infer(itbt, 1, max_spread=1000.0), itbt_net)
    some = omnimvs.infer(itbt, 1, max_spread=10.0)
    left = np.isnan(some)
    assert 0.01 < left.mean() < 0.9
    np.testing.assert_array_equal(some[~left], itbt_net[~left])
    with pytest.raises(ValueError, match="max_spread"):
        omnimvs.infer(itbt, 1, max_spread=-0.5)


def test_maps(itbt_path, itbt, itbt_net, cli, tmp_path):
    # Every map of the estimate, as the command line writes them.
    maps = omnimvs.infer(itbt, 1, maps=True)
    assert set(maps) == {"inv_depth", "index", "entropy", "spread"}
    np.testing.assert_array_equal(maps["inv_depth"], itbt_net)
    cli("infer", itbt_path, "--frames", 1, "--out", tmp_path)
    for key in ("index", "entropy", "spread"):
        expected = tifffile.imread(tmp_path / f"00001_{key}.tiff")
        assert maps[key].dtype == np.float32 and maps[key].shape == (160, 640)
        np.testing.assert_allclose(maps[key], expected, rtol=1e-5, atol=1e-6)
    # The cascade's uncertainty spans the range: entropy at most ln 32, spread in N units.
    assert 0 <= maps["entropy"].min() and maps["entropy"].max() <= np.log(32) + 1e-4
    assert 0 <= maps["spread"].min() and maps["spread"].max() <= 192
    # The paper's network has an entropy and no spread.
    tiny = omnimvs.infer(itbt, 1, weights="tiny", maps=True)
    assert tiny["spread"] is None and tiny["entropy"].shape == (32, 128)


def test_pick(itbt_path, itbt, itbt_net, cli, tmp_path):
    # "auto" (the default) runs the bundled cascade's learnt picks after it, as the command line
    # does: its two in turn ("chain"); "single" the first alone.
    without = omnimvs.infer(itbt, 1, pick="off")
    cli("infer", itbt_path, "--frames", 1, "--pick", "off", "--out", tmp_path)
    np.testing.assert_allclose(without, tifffile.imread(tmp_path / "00001.tiff"), rtol=1e-5, atol=1e-6)
    # Moved by more than 2 index units (inverse depth, 1/m): some pixels (18 % on this frame),
    # not most (the softmax leaves every pixel a little of its neighbours).
    two_indices = 2 * (1 / itbt.min_depth) / 191
    moved = np.abs(without - itbt_net) > two_indices
    assert 0.01 < moved.mean() < 0.3
    # Pick files: the bundled two by path, in turn, are the default's; the first alone is
    # "single"'s.
    models = Path(__file__).resolve().parents[3] / "models"
    bundled = models / "omnimvs-cascade-pick.safetensors"
    second = models / "omnimvs-cascade-pick2.safetensors"
    np.testing.assert_array_equal(omnimvs.infer(itbt, 1, pick=f"{bundled},{second}"), itbt_net)
    np.testing.assert_array_equal(omnimvs.infer(itbt, 1, pick="chain"), itbt_net)
    single = omnimvs.infer(itbt, 1, pick="single")
    np.testing.assert_array_equal(omnimvs.infer(itbt, 1, pick=str(bundled)), single)
    assert np.abs(single - itbt_net).max() > 0
    with pytest.raises(FileNotFoundError, match="nonexistent"):
        omnimvs.infer(itbt, 1, pick="/nonexistent/pick.safetensors")
    # No pick after the paper's network: "auto" leaves it out, a file is refused.
    np.testing.assert_array_equal(omnimvs.infer(itbt, 1, weights="tiny", pick="auto"),
                                  omnimvs.infer(itbt, 1, weights="tiny", pick="off"))
    with pytest.raises(ValueError, match="cascade network only"):
        omnimvs.infer(itbt, 1, weights="tiny", pick=str(bundled))
