"""A round trip: omnimvs.synth renders a dataset with exact ground truth, then the network
and SGM estimate depth and omnimvs.evaluate scores them, as `omnimvs eval` does."""

import json

import numpy as np
import pytest
import tifffile

import omnimvs

SIZE = (192, 200)  # small fisheye images keep rendering fast; the rig is rescaled to them


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    out = tmp_path_factory.mktemp("synth") / "things"
    return out, omnimvs.synth("things", out, frames=(1, 1), seed=3, size=SIZE)


def test_synth_writes_a_dataset(synthetic):
    out, ds = synthetic
    assert isinstance(ds, omnimvs.Dataset)
    assert ds.frames == [1] and ds.num_cameras == 4
    assert (out / "config.yaml").is_file() and (out / "synth.json").is_file()
    assert all(image.shape == SIZE and image.dtype == np.uint8 for image in ds.images(1))
    assert all(image.std() > 5 for image in ds.images(1))
    gt = ds.ground_truth(1)
    assert gt.dtype == np.float32 and gt.shape == (320, 640)
    # The released two-page layout: an RGB picture, then the f32 values.
    with tifffile.TiffFile(out / "omnidepth_gt_640" / "00001.tiff") as tif:
        assert len(tif.pages) == 2
        assert tif.pages[0].dtype == np.uint8 and tif.pages[0].shape == (320, 640, 3)
        np.testing.assert_array_equal(gt, tif.pages[1].asarray())
    assert (gt > 0).mean() > 0.5


def test_synth_resumes_and_is_deterministic(synthetic, tmp_path):
    out, ds = synthetic
    stamp = (out / "cam1" / "00001.png").stat().st_mtime_ns
    again = omnimvs.synth("things", out, frames=(1, 1), seed=3, size=SIZE)
    assert (out / "cam1" / "00001.png").stat().st_mtime_ns == stamp  # complete frame skipped
    assert again.frames == [1]
    other = omnimvs.synth("things", tmp_path / "copy", frames=1, seed=3, size=SIZE, rig=ds.rig)
    for a, b in zip(ds.images(1), other.images(1)):
        np.testing.assert_array_equal(a, b)


def test_ground_truth_scores_perfectly(synthetic):
    _, ds = synthetic
    gt = ds.ground_truth(1)
    middle = gt[80:240]  # the +-45 degree rows of the +-90 degree map
    metrics = omnimvs.evaluate(middle, ds, 1)
    assert set(metrics) == {"over1_pct", "over3_pct", "over5_pct", "mae", "rms", "valid_pixels"}
    assert metrics["valid_pixels"] > 0.5 * middle.size
    assert metrics["mae"] < 1e-3 and metrics["over1_pct"] == 0.0
    worse = omnimvs.evaluate(middle * 0.8, ds, 1)
    assert worse["mae"] > 1.0


def test_evaluate_equals_the_command_line(synthetic, cli, tmp_path):
    # eval scores each method at the 160x640, N = 192 evaluation grid: SGM and the default
    # network (the bundled cascade) answer there, a coarser output (e.g. `tiny`'s 32x128) is
    # resampled on the sphere; evaluate does the same.
    out, ds = synthetic
    cli("eval", "--data", out, "--method", "net,sgm", "--frames", 1, "--out", tmp_path)
    report = json.loads((tmp_path / "eval.json").read_text())
    assert (report["height"], report["width"], report["ndepth"]) == (160, 640, 192)
    expected = {m["method"]: m for m in report["methods"]}
    predictions = {"net": omnimvs.infer(ds, 1), "ZNCC+SGM": omnimvs.sgm(ds, 1)}
    assert predictions["net"].shape == (160, 640)
    for method, prediction in predictions.items():
        for protocol, key in (("reference", "metrics"), ("with-sky", "metrics_with_sky")):
            metrics = omnimvs.evaluate(prediction, ds, 1, protocol=protocol)
            want = expected[method][key]
            assert metrics["valid_pixels"] == want["valid_pixels"], (method, protocol)
            for name in ("over1_pct", "over3_pct", "over5_pct", "mae", "rms"):
                assert metrics[name] == pytest.approx(want[name], rel=1e-3, abs=1e-3), (method, protocol, name)


def test_bad_input(synthetic, itbt_path, tmp_path):
    _, ds = synthetic
    with pytest.raises(ValueError, match="kind"):
        omnimvs.synth("castle", tmp_path / "x", frames=1)
    with pytest.raises(ValueError, match="frames"):
        omnimvs.synth("things", tmp_path / "x", frames=(5, 2))
    with pytest.raises(FileNotFoundError, match="no-such-rig.yaml"):
        omnimvs.synth("things", tmp_path / "x", frames=1, rig=tmp_path / "no-such-rig.yaml")
    with pytest.raises(ValueError, match="size"):
        omnimvs.synth("things", tmp_path / "x", frames=1, size=(0, 10))
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    with pytest.raises(OSError, match="file"):
        omnimvs.synth("things", blocker, frames=1, size=SIZE)
    with pytest.raises(ValueError, match="ground truth"):
        omnimvs.evaluate(np.zeros((32, 128), np.float32), omnimvs.Dataset(itbt_path), 1)
    with pytest.raises(ValueError, match="prediction.*int64"):
        omnimvs.evaluate(np.zeros((32, 128), np.int64), ds, 1)
    with pytest.raises(ValueError, match="prediction"):
        omnimvs.evaluate(np.zeros((4, 32, 128), np.float32), ds, 1)
    with pytest.raises(ValueError, match="protocol"):
        omnimvs.evaluate(np.zeros((32, 128), np.float32), ds, 1, protocol="paper")


def test_a_random_three_camera_rig_through_synth_and_infer(tmp_path):
    # `random:1` draws three cameras; the default cascade runs on them (its four-camera picks
    # stand aside) and answers a depth for every pixel.
    ds = omnimvs.synth("things", tmp_path / "random", frames=1, seed=4, size=SIZE, rig="random:1")
    assert ds.num_cameras == 3
    inv_depth = omnimvs.infer(ds, 1)
    assert inv_depth.shape == (160, 640) and np.isfinite(inv_depth).all()
    assert inv_depth.std() > 0


def test_photometric_difference_on_a_real_frame(itbt_path):
    """A constant 3 m on itbt_sample frame 1 scores as the independent NumPy reading does
    (scripts/photometric_golden/make_photometric_golden.py), and ZNCC+SGM's depth explains the
    images better."""
    ds = omnimvs.Dataset(itbt_path)
    const = np.full((160, 640), np.float32(1.0 / 3.0), np.float32)
    value = omnimvs.photometric_difference(const, ds, 1)
    assert abs(value - 0.19175727033170414) < 1e-6
    assert omnimvs.photometric_difference(omnimvs.sgm(ds, 1), ds, 1) < value
    # No depth anywhere: no point two cameras share.
    assert omnimvs.photometric_difference(np.zeros((160, 640), np.float32), ds, 1) is None
