"""omnimvs.sgm against the TIFF that `omnimvs sgm` writes, images given as arrays, the GIL,
and bad input."""

import threading
import time

import numpy as np
import pytest
import tifffile

import omnimvs

# A small grid keeps the suite fast; the code path is the same at any size.
H, W, N = 48, 192, 32


@pytest.fixture(scope="module")
def itbt(itbt_path):
    return omnimvs.Dataset(itbt_path)


@pytest.fixture(scope="module")
def itbt_sgm(itbt):
    return omnimvs.sgm(itbt, 2, height=H, width=W, ndepth=N)


def test_equals_the_tiff_of_the_command_line(itbt_path, itbt_sgm, cli, tmp_path):
    cli("sgm", itbt_path, "--frames", 2, "--size", f"{H}x{W}", "--ndepth", N, "--out", tmp_path)
    expected = tifffile.imread(tmp_path / "00002.tiff")
    assert itbt_sgm.dtype == np.float32
    assert itbt_sgm.shape == expected.shape == (H, W)
    np.testing.assert_allclose(itbt_sgm, expected, rtol=1e-6, atol=1e-7)


def test_is_a_plausible_depth_map(itbt, itbt_sgm):
    # Indoors: inverse depths between the sphere at infinity and 1 / min_depth, not constant.
    assert np.isfinite(itbt_sgm).all()
    assert itbt_sgm.min() >= 0 and itbt_sgm.max() <= 1 / itbt.min_depth + 1e-6
    assert itbt_sgm.std() > 0.05


def test_images_as_arrays_with_a_rig(itbt_path, itbt, itbt_sgm):
    rig = omnimvs.Rig.from_config(itbt_path / "config.yaml")
    live = omnimvs.sgm(itbt.images(2), height=H, width=W, ndepth=N, rig=rig)
    np.testing.assert_array_equal(live, itbt_sgm)
    stacked = np.stack(itbt.images(2))  # one (cameras, rows, cols) array works too
    np.testing.assert_array_equal(omnimvs.sgm(stacked, None, H, W, N, rig=itbt.rig), itbt_sgm)


def test_releases_the_gil(itbt):
    ticks = 0
    worker = threading.Thread(target=omnimvs.sgm, args=(itbt, 1, H, W, N))
    worker.start()
    while worker.is_alive():
        ticks += 1
        time.sleep(0.001)
    worker.join()
    assert ticks > 20, "the main thread did not run while sgm computed"


def test_bad_arrays_name_the_argument(itbt):
    images = itbt.images(1)
    rig = itbt.rig
    with pytest.raises(ValueError, match=r"images\[1\].*uint8.*float32"):
        omnimvs.sgm([images[0], images[1].astype(np.float32), *images[2:]], rig=rig)
    with pytest.raises(ValueError, match=r"images\[0\].*shape"):
        omnimvs.sgm([images[0][:-1], *images[1:]], rig=rig)
    with pytest.raises(ValueError, match=r"images\[3\]"):
        omnimvs.sgm([*images[:3], images[3][None]], rig=rig)
    with pytest.raises(ValueError, match="images: expected 4 arrays"):
        omnimvs.sgm(images[:3], rig=rig)
    with pytest.raises(ValueError, match="rig: required"):
        omnimvs.sgm(images)
    with pytest.raises(TypeError, match="images"):
        omnimvs.sgm(42, rig=rig)


def test_bad_arguments_name_them(itbt):
    with pytest.raises(FileNotFoundError, match="frame 99"):
        omnimvs.sgm(itbt, 99, H, W, N)
    with pytest.raises(ValueError, match="frame: required"):
        omnimvs.sgm(itbt)
    with pytest.raises(ValueError, match="frame"):
        omnimvs.sgm(itbt, -3)
    with pytest.raises(ValueError, match="rig: not used"):
        omnimvs.sgm(itbt, 1, rig=itbt.rig)
    with pytest.raises(ValueError, match="ndepth"):
        omnimvs.sgm(itbt, 1, H, W, 1)
    with pytest.raises(ValueError, match="odd|even"):
        omnimvs.sgm(itbt, 1, H, W, 31)


@pytest.mark.parametrize("cost", ["mccnn", "sweepnet"])
def test_learned_costs_equal_the_command_line(itbt_path, itbt, cost, cli, tmp_path):
    ours = omnimvs.sgm(itbt, 2, height=H, width=W, ndepth=N, cost=cost)
    cli("sgm", itbt_path, "--frames", 2, "--size", f"{H}x{W}", "--ndepth", N, "--cost", cost,
        "--out", tmp_path)
    expected = tifffile.imread(tmp_path / "00002.tiff")
    np.testing.assert_allclose(ours, expected, rtol=1e-6, atol=1e-7)
    assert np.isfinite(ours).all() and ours.std() > 0.05


def test_an_unknown_cost_is_named(itbt):
    with pytest.raises(ValueError, match="cost.*sweepnet"):
        omnimvs.sgm(itbt, 1, cost="sad")


def test_speed_presets_are_the_settings_they_name(itbt_path):
    ds = omnimvs.Dataset(itbt_path)
    fast = omnimvs.sgm(ds, 1, height=40, width=160, speed="fast")
    np.testing.assert_array_equal(fast, omnimvs.sgm(ds, 1, height=40, width=160, ndepth=32))
    with pytest.raises(ValueError, match="speed"):
        omnimvs.sgm(ds, 1, speed="fast", ndepth=64)
    with pytest.raises(ValueError, match="speed"):
        omnimvs.sgm(ds, 1, speed="quick")
    with pytest.raises(ValueError, match="speed"):
        omnimvs.infer(ds, 1, speed="fast", pick="off")
