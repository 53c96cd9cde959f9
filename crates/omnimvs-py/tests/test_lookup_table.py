"""omnimvs.lookup_table against `omnimvs lut` and an independent numpy computation of
FORMATS.md's conventions."""

import math
import sys

import numpy as np
import pytest
import yaml

import omnimvs

EPS = sys.float_info.epsilon
H, W, N = 24, 96, 8


def rodrigues(r):
    r = np.asarray(r, dtype=np.float64)
    angle = np.linalg.norm(r)
    if angle < 1e-15:
        return np.eye(3)
    k = r / angle
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def numpy_lut(config_path, h, w, n, phi_deg=45.0):
    """FORMATS.md, written from the document: equirectangular rays, spheres at the inverse
    depths linspace(eps, 1/min_depth, n), every other one, projected by OCamCalib's world2cam
    and normalised for grid_sample(align_corners=True); -1e5 pixels outside the FOV."""
    config = yaml.safe_load(config_path.read_text())
    inv = np.linspace(EPS, 1.0 / config["config"]["omnimvs_sweep_min_depth"], n)
    cols, rows = np.meshgrid(np.arange(w), np.arange(h))
    theta = (cols - w / 2) / (w / 2) * np.pi + np.pi / 2
    phi = (rows - (h - 1) / 2) / ((h - 1) / 2) * np.deg2rad(phi_deg)
    rays = np.stack([-np.cos(phi) * np.cos(theta), np.sin(phi), np.cos(phi) * np.sin(theta)]).reshape(3, -1)
    out = np.zeros((len(config["cameras"]), n // 2, h, w, 2), np.float32)
    for i, cam in enumerate(config["cameras"]):
        p = np.array(cam["inv_poly"][1:], dtype=np.float64)
        xc, yc = cam["center"]
        c, d, e = cam["affine"]
        height, width = cam["image_size"]
        R, t = rodrigues(cam["pose"][:3]), np.array(cam["pose"][3:6], dtype=np.float64)
        for k in range(n // 2):
            P = R.T @ (rays / inv[2 * k] - t[:, None])
            norm = np.sqrt(P[0] ** 2 + P[1] ** 2) + EPS
            th = np.arctan2(-P[2], norm)
            rho = sum(coef * th**j for j, coef in enumerate(p))
            x, y = P[1] / norm * rho, P[0] / norm * rho
            row, col = c * x + d * y + xc, e * x + y + yc
            inside = th + np.pi / 2 <= math.radians(cam["max_fov"]) / 2
            col, row = np.where(inside, col, -1e5), np.where(inside, row, -1e5)
            out[i, k, :, :, 0] = (col / (width - 1) * 2 - 1).reshape(h, w)
            out[i, k, :, :, 1] = (row / (height - 1) * 2 - 1).reshape(h, w)
    return out


@pytest.mark.parametrize("sample", ["sunny_path", "itbt_path"])
def test_equals_the_hwd_of_the_command_line(sample, request, cli, tmp_path):
    path = request.getfixturevalue(sample)
    hwd = tmp_path / f"lt_({H},{W},{N}).hwd"
    cli("lut", path, "--size", f"{H}x{W}", "--ndepth", N, "--out", hwd)
    lut = omnimvs.lookup_table(omnimvs.Dataset(path), height=H, width=W, ndepth=N)
    assert lut.dtype == np.float32
    assert lut.shape == (4, N // 2, H, W, 2)
    np.testing.assert_array_equal(lut, np.fromfile(hwd, dtype="<f4").reshape(lut.shape))


@pytest.mark.parametrize("sample", ["sunny_path", "itbt_path"])
def test_matches_an_independent_numpy_computation(sample, request):
    path = request.getfixturevalue(sample)
    lut = omnimvs.lookup_table(omnimvs.Rig.from_config(path / "config.yaml"), H, W, N)
    expected = numpy_lut(path / "config.yaml", H, W, N)
    valid = (expected > -2).all(axis=-1)
    agree = valid == (lut > -2).all(axis=-1)
    # Rays exactly on the FOV boundary may fall either way.
    assert agree.mean() > 0.9999
    both = valid & agree
    assert both.mean() > 0.3
    np.testing.assert_allclose(lut[both], expected[both], atol=2e-5)


def test_cache_gives_the_same_table(sunny_path):
    ds = omnimvs.Dataset(sunny_path)
    first = omnimvs.lookup_table(ds, H, W, N)
    again = omnimvs.lookup_table(ds.rig, H, W, N)
    np.testing.assert_array_equal(first, again)


def test_bad_arguments_name_them(sunny_path):
    ds = omnimvs.Dataset(sunny_path)
    with pytest.raises(ValueError, match="ndepth"):
        omnimvs.lookup_table(ds, H, W, 7)
    with pytest.raises(TypeError, match="source"):
        omnimvs.lookup_table("not a dataset", H, W, N)
