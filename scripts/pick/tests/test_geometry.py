"""geometry.py, the dataset conventions of the pick's data: checks of its own (camera model, grid
rays, bilinear sampling, ground-truth index and readers), and agreement with omni_np.py, an
independent numpy implementation kept beside the repository (`../shared/tools/`), on the real
samples (`../shared/data/omnimvs-samples/`) and on a small `omnimvs synth` dataset.

Tolerances against omni_np: grid rays, bilinear values (at the same positions), ground truth,
its index and validity, image paths and visibility must be equal; projections agree to 1e-9
relative (the two rotate points with rotation matrices computed in another order, which differ
in the last bits), and pick_inputs.features to 1e-9 absolute.
"""
import importlib.util
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import geometry as g
import pick_inputs as pi

ROOT = Path(__file__).resolve().parents[3]
OMNI_NP = ROOT / ".." / "shared" / "tools" / "omni_np.py"
SAMPLES = ROOT / ".." / "shared" / "data" / "omnimvs-samples"
BINARY = ROOT / "target" / "release" / "omnimvs"
REAL = ["itbt_sample", "sunny_single"]


@pytest.fixture(scope="module")
def omni_np():
    if not OMNI_NP.is_file():
        pytest.skip(f"omni_np.py is not beside the repository ({OMNI_NP.resolve()}): nothing to compare with")
    spec = importlib.util.spec_from_file_location("omni_np", OMNI_NP)
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except ImportError as e:
        pytest.skip(f"omni_np.py cannot be imported here ({e})")
    return module


def sample(name):
    path = SAMPLES / name
    if not (path / "config.yaml").is_file():
        pytest.skip(f"the real sample {name} is not beside the repository ({path.resolve()})")
    return str(path)


@pytest.fixture(scope="module")
def synth(tmp_path_factory):
    """A small generated dataset (2 frames of 192 x 200 images, ground truth 320 x 640)."""
    if not os.access(BINARY, os.X_OK):
        pytest.skip(f"no release binary at {BINARY} to generate a dataset with")
    out = tmp_path_factory.mktemp("synth") / "things"
    subprocess.run([str(BINARY), "synth", "--kind", "things", "--frames", "1..2", "--size", "192x200",
                    "--seed", "3", "--out", str(out)], check=True, capture_output=True)
    return str(out)


@pytest.fixture(params=REAL + ["synth"])
def ds(request):
    if request.param == "synth":
        return request.getfixturevalue("synth")
    return sample(request.param)


def rig_points():
    """Rig points at many depths and directions, near and behind every camera."""
    rng = np.random.default_rng(11)
    R = g.rays(24, 96, 90.0)
    return np.concatenate([R * d for d in (0.2, 0.55, 1.0, 3.0, 30.0, 1e4)] + [rng.normal(size=(3, 500)) * 2], 1)


# --- against omni_np -------------------------------------------------------------------------

def test_rays_equal_omni_np(omni_np):
    for h, w, phi in [(160, 640, 45.0), (320, 640, 90.0), (7, 10, 30.0)]:
        np.testing.assert_array_equal(g.rays(h, w, phi), omni_np.rays(h, w, phi))


def test_cameras_and_projections_agree_with_omni_np(omni_np, ds):
    cfg, cams, md = g.load(ds)
    ocfg, ocams, omd = omni_np.load(ds)
    assert md == omd and len(cams) == len(ocams)
    X = rig_points()
    for i, (cam, ocam) in enumerate(zip(cams, ocams)):
        assert (cam.height, cam.width) == (ocam.h, ocam.w)
        np.testing.assert_allclose(cam.R, ocam.R, rtol=0, atol=1e-15)
        np.testing.assert_array_equal(cam.t, ocam.t)
        col, row, vis = cam.project(X)
        ocol, orow, ovis = ocam.project(X)
        np.testing.assert_array_equal(vis, ovis)
        assert 0.2 < vis.mean() < 0.8
        np.testing.assert_allclose(col, ocol, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(row, orow, rtol=1e-9, atol=1e-9)
        assert g.frame_path(ds, i, cfg, 1) == omni_np.frame_path(ds, i, ocfg, 1)


def test_bilinear_equals_omni_np(omni_np, ds):
    cfg, cams, _ = g.load(ds)
    im = pi.normalise(Image.open(g.frame_path(ds, 0, cfg, 1)))
    col, row, _ = cams[0].project(rig_points())
    # Also positions on and just off the borders, and the last pixel's own position.
    h, w = im.shape
    col = np.concatenate([col, [0, w - 1, w - 1.5, w - 2, -1e-9, 0.5, 3.25]])
    row = np.concatenate([row, [0, h - 1, h - 1.5, 0.5, 3.0, -0.5, h - 2]])
    val, ok = g.bilinear(im, col, row)
    oval, ook = omni_np.bilinear(im, col, row)
    np.testing.assert_array_equal(ok, ook)
    assert ok.any() and not ok.all()
    np.testing.assert_array_equal(val[ok], oval[ok])
    assert (val[~ok] == 0).all()


def test_ground_truth_equals_omni_np(omni_np, synth):
    cfg, _, md = g.load(synth)
    for f in (1, 2):
        gt = g.gt_reference(synth, f, 160, 640, 45.0, cfg)
        ogt = omni_np.gt_reference(synth, f, 160, 640, 45.0)
        assert gt.shape == (160, 640)
        np.testing.assert_array_equal(gt, ogt)
        full = g.read_inv_depth(g.gt_path(synth, f, cfg))
        np.testing.assert_array_equal(full, omni_np.read_f32_tiff(g.gt_path(synth, f, cfg)))
        for a, b in zip(g.reference_gt_index(gt, md), omni_np.reference_gt_index(ogt, md)):
            np.testing.assert_array_equal(a, b)


def test_reference_index_of_holes_and_sky_equals_omni_np(omni_np):
    rng = np.random.default_rng(12)
    m = rng.uniform(0, 2.5, size=(60, 90)).astype(np.float32)
    m[rng.uniform(size=m.shape) < 0.15] = 0      # scattered holes
    m[5:25, 10:40] = 0                           # a patch of sky
    m[40:44, 50:53] = 5e-4                       # farther than 1 km, inside
    m[:, -3:] = np.nan
    for md in (0.5, 1.65):
        ours, theirs = g.reference_gt_index(m, md), omni_np.reference_gt_index(m, md)
        for a, b in zip(ours, theirs):
            np.testing.assert_array_equal(a, b)
        assert (ours[0] == -1).sum() > 100


def test_features_equal_the_omni_np_ones(omni_np, monkeypatch):
    """pick_inputs.features with geometry.py, against the same with omni_np (as it was before)."""
    ds = sample("itbt_sample")
    cfg, cams, md = g.load(ds)
    ocfg, ocams, _ = omni_np.load(ds)
    ims = pi.normalised_images(ds, 1, cfg, cams)
    rng = np.random.default_rng(13)
    rows, cols = np.meshgrid(np.arange(160), np.arange(640), indexing="ij")
    v = np.clip(60 + 40 * np.sin(cols / 640 * 6 * np.pi) + 20 * ((cols // 40) % 2) + rng.normal(size=(160, 640)), 0, 191)
    spread = rng.uniform(0, 40, size=v.shape)
    step = (1 / md - g.EPS) / 191
    ours = pi.features(ims, cams, v, spread, g.EPS, step, depth_radii=(2,), zncc_k=5)
    monkeypatch.setattr(pi, "geometry", omni_np)
    theirs = pi.features(ims, ocams, v, spread, g.EPS, step, depth_radii=(2,), zncc_k=5)
    assert ours.shape == (pi.channels(4, (2,), 5), 160, 640)
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(ours.astype(np.float16), theirs.astype(np.float16))


# --- checks of its own -----------------------------------------------------------------------

def test_optical_axis_projects_to_the_principal_point(ds):
    _, cams, _ = g.load(ds)
    for cam in cams:
        col, row, vis = cam.project_cam(np.array([[0.0, 0.0], [0.0, 0.0], [0.5, 7.0]]))
        assert vis.all()
        np.testing.assert_array_equal(col, cam.center_col)
        np.testing.assert_array_equal(row, cam.center_row)
        # The same through the pose: the camera's centre plus its optical axis in the rig.
        X = cam.t[:, None] + cam.R @ np.array([[0.0], [0.0], [10.0]])
        col, row, vis = cam.project(X)
        assert vis.all() and abs(col[0] - cam.center_col) < 0.5 and abs(row[0] - cam.center_row) < 0.5


def test_axes_and_field_of_view():
    _, cams, _ = g.load(sample("sunny_single"))
    cam = cams[0]
    col, row, _ = cam.project_cam(np.array([[1.0, 0.0], [0.0, 1.0], [2.0, 2.0]]))
    assert col[0] > cam.center_col + 10 and abs(row[0] - cam.center_row) < 1e-9  # +x: right
    assert row[1] > cam.center_row + 10 and abs(col[1] - cam.center_col) < 1e-9  # +y: down
    a = np.radians([109.0, 111.0, 180.0])
    _, _, vis = cam.project_cam(np.stack([np.sin(a), np.zeros(3), np.cos(a)]))
    np.testing.assert_array_equal(vis, [True, False, False])


def test_unproject_then_project_round_trip():
    # poly and inv_poly are separate fits of one lens: sunny's agree to a hundredth of a pixel.
    _, cams, _ = g.load(sample("sunny_single"))
    for cam in cams:
        rows, cols = np.meshgrid(np.arange(0, cam.height, 5.0), np.arange(0, cam.width, 5.0), indexing="ij")
        ray, vis = cam.unproject(cols.ravel(), rows.ravel())
        assert 0.5 < vis.mean() < 0.9
        np.testing.assert_allclose((ray * ray).sum(0), 1.0, atol=1e-12)
        col, row, seen = cam.project_cam(ray[:, vis] * 4.0)
        assert seen.all()
        assert np.hypot(col - cols.ravel()[vis], row - rows.ravel()[vis]).max() < 0.01
        # The principal point looks along the optical axis.
        ray, vis = cam.unproject([cam.center_col], [cam.center_row])
        np.testing.assert_allclose(ray[:, 0], [0, 0, 1], atol=1e-12)


def test_rotation_is_rodrigues():
    np.testing.assert_array_equal(g.rotation([0, 0, 0]), np.eye(3))
    R = g.rotation([0, math.pi / 2, 0])  # camera z to rig x
    np.testing.assert_allclose(R @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    r = np.array([0.3, -1.1, 0.7])
    R = g.rotation(r)
    np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(R @ r, r, atol=1e-15)  # the axis stays
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    assert math.acos((np.trace(R) - 1) / 2) == pytest.approx(np.linalg.norm(r), abs=1e-12)


def test_rays_are_unit_with_known_latitudes_and_longitudes():
    h, w, phi = 161, 640, 45.0
    R = g.rays(h, w, phi).reshape(3, h, w)
    np.testing.assert_allclose((R * R).sum(0), 1.0, atol=1e-15)
    np.testing.assert_allclose(R[:, 80, 320], [0, 0, 1], atol=1e-15)    # middle: +z
    np.testing.assert_allclose(R[:, 80, 0], [0, 0, -1], atol=1e-15)     # column 0: -z
    np.testing.assert_allclose(R[:, 80, 160], [-1, 0, 0], atol=1e-15)   # a quarter: -x
    np.testing.assert_allclose(R[:, 80, 480], [1, 0, 0], atol=1e-15)
    lat = np.degrees(np.arcsin(R[1]))
    lon = np.degrees(np.arctan2(R[2], -R[0]))  # 0 at column w/4, 90 at the middle
    np.testing.assert_allclose(lat[0], -45.0, atol=1e-12)   # row 0 is the top: y points down
    np.testing.assert_allclose(lat[-1], 45.0, atol=1e-12)
    np.testing.assert_allclose(lat[:, 7], np.linspace(-45, 45, h), atol=1e-12)
    expect = (np.arange(w) - w / 4) / w * 360.0
    np.testing.assert_allclose((lon[5] - expect + 180) % 360 - 180, 0, atol=1e-9)  # modulo 360


def test_bilinear_values():
    im = np.arange(12.0).reshape(3, 4)  # value = 4 row + col: bilinear is exact
    col = np.array([0.0, 1.5, 2.25, 2.999, 3.0, -0.1, 1.0, 0.5])
    row = np.array([0.0, 0.5, 1.75, 1.999, 0.0, 1.0, 2.0, np.nan])
    val, ok = g.bilinear(im, col, row)
    np.testing.assert_array_equal(ok, [True, True, True, True, False, False, False, False])
    np.testing.assert_allclose(val[ok], 4 * row[ok] + col[ok], atol=1e-12)
    assert (val[~ok] == 0).all()


def test_reference_index_of_known_values():
    md, n = 0.5, 192
    step = (1 / md - g.EPS) / (n - 1)
    known = np.arange(0, 200, 0.5)
    m = np.zeros((30, 60), np.float32)
    m[10:20, :] = 1.0                      # 1 m: index (1 - EPS) / step
    m[13:16, 20:24] = 0.0                  # a hole inside, that a 5 x 5 closing fills: -1
    m[11:19, 40:46] = 0.0                  # a wider one, that it does not: sky
    m[14, 30] = 5e-4                       # a single "infinite" pixel inside: -1
    m[0:5, 0:60] = 0.0                     # sky (touches the border: no hole)
    m[25, :] = 1 / md                      # the nearest sphere: index N - 1
    m[27, :] = 2.0 * 1.04                  # nearer than the nearest sphere, past N
    index, valid, d0, s = g.reference_gt_index(m, md, n)
    assert d0 == g.EPS and s == step
    assert index[11, 5] == pytest.approx((1.0 - g.EPS) / step, rel=1e-15) and valid[11, 5]
    assert (index[13:16, 20:24] == -1).all() and not valid[13:16, 20:24].any()
    assert (index[11:19, 40:46] < 0).all() and (index[11:19, 40:46] > -1e-10).all()
    assert index[14, 30] == -1 and not valid[14, 30]
    assert (index[0:5] < 0).all() and (index[0:5] > -1e-10).all() and not valid[0:5].any()
    assert index[25, 7] == pytest.approx(n - 1, rel=1e-12) and valid[25].all()
    assert index[27, 7] > n and not valid[27].any()
    # Indices are (d - d_0) / step exactly, for any inverse depth.
    flat = (g.EPS + known * step).astype(np.float32).reshape(1, -1)
    index, valid, _, _ = g.reference_gt_index(np.repeat(flat, 3, 0), md, n)
    np.testing.assert_array_equal(index[1], (flat[0].astype(np.float64) - g.EPS) / step)
    np.testing.assert_allclose(index[1], known, atol=1e-4)
    np.testing.assert_array_equal(valid[1], (index[1] >= 0) & (index[1] <= n))


def test_closing_is_scipy_closing():
    from scipy import ndimage
    rng = np.random.default_rng(14)
    for p in (0.3, 0.7, 0.9):
        m = rng.uniform(size=(23, 37)) < p
        np.testing.assert_array_equal(g.binary_closing_5x5(m), ndimage.binary_closing(m, np.ones((5, 5))))


def test_ground_truth_files_and_crop(tmp_path):
    gt = np.random.default_rng(15).uniform(0, 2, size=(320, 640)).astype(np.float32)
    (tmp_path / "omnidepth_gt_640").mkdir()
    gt.astype("<f4").tofile(tmp_path / "omnidepth_gt_640" / "0003.bin")  # raw, 4 digits
    cfg = {"dataset": {"img_fmt": "cam%d/%05d.png"}}
    assert g.gt_path(str(tmp_path), 3, cfg).endswith("0003.bin")
    assert g.gt_path(str(tmp_path), 4, cfg) is None
    np.testing.assert_array_equal(g.gt_reference(str(tmp_path), 3, 160, 640, 45.0, cfg), gt[80:240])
    np.testing.assert_array_equal(g.gt_reference(str(tmp_path), 3, 318, 640, 89.4375, cfg), gt[1:319])
    np.testing.assert_array_equal(g.gt_reference(str(tmp_path), 3, 2, 640, 0.5625, cfg), gt[159:161])
    with pytest.raises(ValueError):
        g.gt_reference(str(tmp_path), 3, 40, 160, 45.0, cfg)
    # The released 16-bit PNG encoding.
    v = np.array([[0, 1, 65500, 32750]], np.uint16).repeat(2, 0)
    Image.fromarray(v).save(tmp_path / "d.png")
    np.testing.assert_allclose(g.read_inv_depth(str(tmp_path / "d.png"))[0],
                               np.float32([0, 1 / 65500 / 0.55, 1 / 0.55, 0.5 / 0.55]), rtol=1e-7)
    # A two-page TIFF (a picture, then the float page) and a one-page one.
    pages = [Image.fromarray(np.zeros((320, 640, 3), np.uint8)), Image.fromarray(gt, mode="F")]
    pages[0].save(tmp_path / "two.tiff", save_all=True, append_images=pages[1:], compression="tiff_deflate")
    np.testing.assert_array_equal(g.read_f32_tiff(str(tmp_path / "two.tiff")), gt)
    pages[1].save(tmp_path / "one.tiff")
    assert g.read_f32_tiff(str(tmp_path / "one.tiff")).dtype == np.float64
    pages[0].save(tmp_path / "rgb.tiff")
    with pytest.raises(ValueError):
        g.read_f32_tiff(str(tmp_path / "rgb.tiff"))


def test_frame_paths_accept_four_and_five_digits(tmp_path):
    (tmp_path / "cam2").mkdir()
    (tmp_path / "cam2" / "0007.png").write_bytes(b"")
    (tmp_path / "cam2" / "00008.png").write_bytes(b"")
    cfg = {"dataset": {"img_fmt": "cam%d/%05d.png"}}
    assert g.frame_path(str(tmp_path), 1, cfg, 7) == str(tmp_path / "cam2" / "0007.png")
    assert g.frame_path(str(tmp_path), 1, cfg, 8) == str(tmp_path / "cam2" / "00008.png")
    assert g.frame_path(str(tmp_path), 0, cfg, 8) == str(tmp_path / "cam1" / "00008.png")


def test_released_layout_reads_as_its_config(tmp_path):
    """ocamN.txt + poses.txt (centimetres) give the cameras of the equivalent config.yaml."""
    ds = sample("itbt_sample")
    cfg, cams, _ = g.load(ds)
    poses = "# rx ry rz tx ty tz (camera to rig; rad, cm)\n"
    for k, c in enumerate(cfg["cameras"]):
        nums = lambda v: " ".join(repr(float(x)) for x in v)
        (tmp_path / f"ocam{k + 1}.txt").write_text(
            f"#polynomial coefficients for the DIRECT mapping function\n\n{nums(c['poly'])}\n\n"
            f"#inverse\n{nums(c['inv_poly'])}\n#center\n{nums(c['center'])}\n\n{nums(c['affine'])}\n"
            f"#image size\n{c['image_size'][0]} {c['image_size'][1]}\n")
        p = c["pose"]
        poses += nums(p[:3] + [t * 100 for t in p[3:]]) + "\n"
    (tmp_path / "poses.txt").write_text(poses)
    (tmp_path / "cam1").mkdir()
    for name in ("0001.png", "0002.png", "notes.txt"):
        (tmp_path / "cam1" / name).write_bytes(b"")
    rcfg, rcams, rmd = g.load(str(tmp_path))
    assert rmd == g.RELEASED_MIN_DEPTH and rcfg["dataset"]["img_fmt"] == "cam%d/%04d.png"
    X = rig_points()
    for cam, rcam in zip(cams, rcams):
        assert rcam.poly == cam.poly and rcam.inv_poly == cam.inv_poly and rcam.max_fov_deg == 220.0
        a, b = cam.project(X), rcam.project(X)
        np.testing.assert_array_equal(a[2], b[2])
        np.testing.assert_allclose(a[0], b[0], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(a[1], b[1], rtol=1e-9, atol=1e-9)


def test_bad_configurations_are_refused(tmp_path):
    with pytest.raises(ValueError, match="count"):
        g.counted([3, 1.0, 2.0], "poly")
    entry = {"poly": [1, -1.0], "inv_poly": [1, 1.0], "center": [1, 1], "affine": [1, 0, 0],
             "image_size": [2, 2], "max_fov": 220, "pose": [0] * 6, "model": "fisheye"}
    with pytest.raises(ValueError, match="model"):
        g.camera_from_config(entry, 0)
    (tmp_path / "config.yaml").write_text("config: {omnimvs_sweep_min_depth: 0.5}\n"
                                          "dataset: {img_fmt: cam%d/%05d.png}\ncameras: []\n")
    with pytest.raises(ValueError, match="camera"):
        g.load(str(tmp_path))
