"""omnimvs.Dataset and omnimvs.Rig on the real samples, and their errors."""

from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

import omnimvs


def test_dataset_reads_the_sample_as_the_config_says(itbt_path):
    config = yaml.safe_load((itbt_path / "config.yaml").read_text())
    for path in (str(itbt_path), itbt_path, itbt_path / "config.yaml"):
        ds = omnimvs.Dataset(path)
        assert ds.frames == [1, 2, 3]
        assert ds.num_cameras == len(config["cameras"]) == 4
        assert ds.min_depth == config["config"]["omnimvs_sweep_min_depth"]
        assert Path(ds.root) == itbt_path
    assert "4 cameras" in repr(ds)


def test_images_are_the_png_pixels(itbt_path):
    ds = omnimvs.Dataset(itbt_path)
    images = ds.images(2)
    assert len(images) == 4
    for cam, image in enumerate(images, start=1):
        expected = np.asarray(Image.open(itbt_path / f"cam{cam}" / "00002.png"))
        assert image.dtype == np.uint8
        assert image.shape == expected.shape
        np.testing.assert_array_equal(image, expected)


def test_rgb_images_are_the_channel_mean(sunny_path):
    # FORMATS.md: RGB is converted to gray by the channel mean; sunny names frames 0001.png.
    ds = omnimvs.Dataset(sunny_path)
    assert ds.frames == [1]
    image = ds.images(1)[0]
    rgb = np.asarray(Image.open(sunny_path / "cam1" / "0001.png").convert("RGB")).astype(np.float64)
    assert image.shape == rgb.shape[:2]
    assert np.abs(image.astype(np.float64) - rgb.mean(axis=2)).max() <= 0.5 + 1e-9


def test_colour_images_are_the_png_channels(sunny_path, itbt_path):
    # colour=True: a colour image as decoded, (H, W, 3) RGB; the default stays gray.
    ds = omnimvs.Dataset(sunny_path)
    colour = ds.images(1, colour=True)
    gray = ds.images(1)
    assert len(colour) == len(gray) == 4
    for cam, (image, flat) in enumerate(zip(colour, gray), start=1):
        expected = np.asarray(Image.open(sunny_path / f"cam{cam}" / "0001.png").convert("RGB"))
        assert image.dtype == np.uint8
        assert image.shape == expected.shape
        np.testing.assert_array_equal(image, expected)
        assert flat.shape == expected.shape[:2]
    assert (colour[0][..., 0] != colour[0][..., 2]).any()
    # Gray images stay (H, W) and the same pixels.
    itbt = omnimvs.Dataset(itbt_path)
    for image, flat in zip(itbt.images(1, colour=True), itbt.images(1)):
        assert image.shape == flat.shape
        np.testing.assert_array_equal(image, flat)


def test_samples_have_no_ground_truth(itbt_path):
    assert omnimvs.Dataset(itbt_path).ground_truth(1) is None


def test_rig_from_config(itbt_path):
    config = yaml.safe_load((itbt_path / "config.yaml").read_text())
    for path in (itbt_path / "config.yaml", str(itbt_path)):
        rig = omnimvs.Rig.from_config(path)
        assert rig.num_cameras == 4
        assert rig.min_depth == 0.5
        assert rig.image_sizes == [tuple(c["image_size"]) for c in config["cameras"]]
    assert omnimvs.Dataset(itbt_path).rig.image_sizes == rig.image_sizes


def test_missing_folder_names_the_path(tmp_path):
    missing = tmp_path / "no-such-dataset"
    with pytest.raises(FileNotFoundError, match="no-such-dataset"):
        omnimvs.Dataset(missing)
    with pytest.raises(FileNotFoundError, match="no-such-dataset"):
        omnimvs.Rig.from_config(missing / "config.yaml")


def test_bad_config_names_the_field(tmp_path, itbt_path):
    text = (itbt_path / "config.yaml").read_text().replace("omnimvs_sweep_min_depth: 0.5", "omnimvs_sweep_min_depth: -1")
    (tmp_path / "config.yaml").write_text(text)
    with pytest.raises(ValueError, match="omnimvs_sweep_min_depth"):
        omnimvs.Dataset(tmp_path)


def test_frame_that_does_not_exist(itbt_path):
    ds = omnimvs.Dataset(itbt_path)
    with pytest.raises(FileNotFoundError, match="frame 99"):
        ds.images(99)
    with pytest.raises(FileNotFoundError, match="frame 99"):
        ds.ground_truth(99)
    with pytest.raises(ValueError, match="frame"):
        ds.images(-1)


def _released_sunny(sunny_path, folder, factor):
    """The sunny rig in the released layout, poses.txt translations in metres * factor."""
    config = yaml.safe_load((sunny_path / "config.yaml").read_text())
    folder.mkdir()
    lines = []
    for k, cam in enumerate(config["cameras"], start=1):
        (folder / f"cam{k}").mkdir()
        (folder / f"cam{k}" / "00001.png").write_bytes((sunny_path / f"cam{k}" / "0001.png").read_bytes())
        poly, inv = cam["poly"], cam["inv_poly"]
        text = "\n".join([
            " ".join(str(x) for x in poly),
            " ".join(str(x) for x in inv),
            " ".join(str(x) for x in cam["center"]),
            " ".join(str(x) for x in cam["affine"]),
            " ".join(str(x) for x in cam["image_size"]),
        ])
        (folder / f"ocam{k}.txt").write_text(text + "\n")
        r, t = cam["pose"][:3], cam["pose"][3:]
        lines.append(" ".join(str(x) for x in r + [round(v * factor, 9) for v in t]))
    (folder / "poses.txt").write_text("\n".join(lines) + "\n")
    return folder


def test_released_layout_pose_unit(sunny_path, tmp_path):
    # The same rig with poses.txt in mm and in cm: read each in its unit, the same lookup
    # table; the mm folder read in the default cm, another one.
    in_mm = _released_sunny(sunny_path, tmp_path / "mm", 1000.0)
    in_cm = _released_sunny(sunny_path, tmp_path / "cm", 100.0)
    size = dict(height=8, width=16, ndepth=4)
    reference = omnimvs.lookup_table(omnimvs.Dataset(in_cm), **size)
    np.testing.assert_array_equal(omnimvs.lookup_table(omnimvs.Dataset(in_mm, pose_unit="mm"), **size), reference)
    assert not np.array_equal(omnimvs.lookup_table(omnimvs.Dataset(in_mm), **size), reference)
    with pytest.raises(ValueError, match="m, cm or mm"):
        omnimvs.Dataset(in_mm, pose_unit="inch")
    with pytest.raises(ValueError, match="metres"):
        omnimvs.Dataset(sunny_path, pose_unit="cm")


EXAMPLES = Path(__file__).resolve().parents[3] / "examples" / "rigs"


def test_rig_from_basalt_and_kalibr_files():
    basalt = omnimvs.Rig.from_file(EXAMPLES / "ds-4cam-compact" / "calibration.json")
    assert basalt.num_cameras == 4
    assert basalt.models == ["ds"] * 4
    assert basalt.image_sizes == [(1216, 1216)] * 4
    assert basalt.min_depth == 0.55
    kalibr = omnimvs.Rig.from_file(EXAMPLES / "eucm-3cam", rig_frame="fitted", min_depth=0.4)
    assert kalibr.models == ["eucm"] * 3
    assert kalibr.min_depth == 0.4
    # Fitted: the optical centres around the origin, level (y = 0).
    centres = np.array([[m[0][3], m[1][3], m[2][3]] for m in kalibr.rig_from_cam])
    assert np.abs(centres.mean(axis=0)).max() < 1e-9
    assert np.abs(centres[:, 1]).max() < 1e-9
    # In Kalibr's own frame camera 1 is at the origin.
    own = omnimvs.Rig.from_file(EXAMPLES / "eucm-3cam")
    assert np.abs(np.array(own.rig_from_cam[0]) - np.eye(4)).max() < 1e-12


def test_bad_rig_frame_and_calibration_name_the_problem(tmp_path):
    with pytest.raises(ValueError, match="rig_frame"):
        omnimvs.Rig.from_file(EXAMPLES / "eucm-3cam", rig_frame="level")
    bad = tmp_path / "calibration.json"
    bad.write_text('{"value0": {"T_imu_cam": [], "intrinsics": [{"camera_type": "fov"}], "resolution": []}}')
    with pytest.raises(ValueError, match="calibration.json"):
        omnimvs.Rig.from_file(bad)
