# The dataset conventions the pick's data needs, in numpy: a dataset's rig and settings
# (`config.yaml`, or the released layout's `ocamN.txt` + `poses.txt`), the OCamCalib camera model,
# the rays of the equirectangular output grid, bilinear sampling of an image, float32 TIFF reading
# and the reference's ground-truth index. Each follows the Rust implementation it names
# (omnimvs-camera, omnimvs-sweep, omnimvs-data, omnimvs-net's pick) and the conventions chapter of
# the book (docs/book/src/formats.md), so that pick_inputs.py computes what the binary computes.
#
# Conventions in brief:
#   - rig frame: poses are camera-to-rig, X_rig = R(r) X_cam + t, R the Rodrigues rotation of the
#     rotation vector r (radians), t in metres (centimetres in a released poses.txt);
#   - camera frame: x right (columns), y down (rows), z forward (optical axis);
#   - grid of h x w pixels over latitudes +-phi: theta = (col - w/2) / (w/2) pi + pi/2,
#     phi = (row - (h-1)/2) / ((h-1)/2) phi_rad, ray = (-cos phi cos theta, sin phi, cos phi sin theta);
#   - N inverse-depth hypotheses from d_0 = f64 epsilon to 1 / min_depth, index n = (d - d_0) / step.
# Needs numpy, pillow and pyyaml.
import math
import os
import sys

import numpy as np

# d_0, the inverse depth of the farthest sphere (1/m): the reference's max depth is 1 / EPS.
EPS = sys.float_info.epsilon
# Inverse depths below this (farther than 1 km) are "infinite" in the invalid-pixel rule.
FINITE_INV_DEPTH = np.float32(1e-3)
# Width of the published ground-truth panoramas; also the row length of a raw f32 file.
GT_WIDTH = 640
# Where a dataset keeps its ground truth when its config names no gt_fmt, and the extensions tried.
GT_DIRS = ("omnidepth_gt_640", "depth_train_640")
GT_EXTS = ("tiff", "tif", "png", "bin", "raw")
# The released datasets' minimum depth (m; their 16-bit ground truth is relative to 1 / 0.55) and
# field of view (degrees; their text files do not carry it).
RELEASED_MIN_DEPTH = 0.55
RELEASED_MAX_FOV = 220.0
IMAGE_EXTS = ("png", "jpg", "jpeg", "bmp", "tif", "tiff")


def rotation(rvec):
    """The rotation matrix of a rotation vector (axis times angle, radians): Rodrigues' formula
    R = cos a I + (1 - cos a) k k^T + sin a [k]x."""
    r = np.asarray(rvec, dtype=np.float64)
    angle = float(np.sqrt(r @ r))
    if angle == 0.0:
        return np.eye(3)
    k = r / angle
    cross = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return math.cos(angle) * np.eye(3) + (1.0 - math.cos(angle)) * np.outer(k, k) + math.sin(angle) * cross


def polyval(coeffs, x):
    """sum coeffs[i] x^i (ascending powers), by Horner's rule."""
    acc = np.zeros_like(np.asarray(x, dtype=np.float64))
    for a in reversed(coeffs):
        acc = acc * x + a
    return acc


class Camera:
    """One OCamCalib (Scaramuzza) fisheye camera of a rig with its camera-to-rig pose, evaluated
    as the reference does (omnimvs-camera's OcamModel and Camera)."""

    def __init__(self, poly, inv_poly, center, affine, size, max_fov_deg, pose, img_dir):
        self.poly = [float(a) for a in poly]          # z(rho), ascending powers
        self.inv_poly = [float(a) for a in inv_poly]  # rho(theta), theta from the image plane
        self.center_row, self.center_col = (float(v) for v in center)
        self.c, self.d, self.e = (float(v) for v in affine)
        self.height, self.width = (int(v) for v in size)
        self.max_fov_deg = float(max_fov_deg)
        pose = [float(v) for v in pose]
        self.R = rotation(pose[:3])                   # rig from camera
        self.t = np.array(pose[3:6])                  # the camera's centre in the rig, metres
        self.img_dir = img_dir
        if abs(self.c - self.d * self.e) < 1e-12:
            raise ValueError("affine: expected an invertible affine matrix (c - d*e != 0)")

    def half_fov(self):
        """Half the field of view, radians."""
        return math.radians(self.max_fov_deg) / 2.0

    def project_cam(self, P):
        """world2cam of points (3, n) in the camera frame: (col, row, visible), pixels; visible is
        False beyond half the field of view from the optical axis (col and row are computed
        anyway)."""
        X, Y, Z = (np.asarray(a, dtype=np.float64) for a in P)
        norm = np.sqrt(X * X + Y * Y) + EPS
        theta = np.arctan2(-Z, norm)  # from the image plane: -pi/2 looks straight ahead
        rho = polyval(self.inv_poly, theta)
        x, y = Y / norm * rho, X / norm * rho  # OCamCalib's x runs along the rows
        row = self.c * x + self.d * y + self.center_row
        col = self.e * x + y + self.center_col
        return col, row, ~(theta + math.pi / 2 > self.half_fov())

    def project(self, X):
        """Points (3, n) of the rig frame (metres) to (col, row, visible) of this camera's image."""
        X = np.asarray(X, dtype=np.float64)
        return self.project_cam(self.R.T @ (X - self.t[:, None]))

    def unproject(self, col, row):
        """cam2world: the unit rays (3, n), camera frame, of pixels (col, row), and whether each
        lies within the field of view."""
        u = np.asarray(row, dtype=np.float64) - self.center_row
        v = np.asarray(col, dtype=np.float64) - self.center_col
        inv_det = 1.0 / (self.c - self.d * self.e)
        x = inv_det * (u - self.d * v)
        y = inv_det * (-self.e * u + self.c * v)
        rho = np.sqrt(x * x + y * y)
        z = polyval(self.poly, rho)
        ray = np.stack([y, x, -z])
        return ray / np.sqrt((ray * ray).sum(0)), ~(np.arctan2(rho, -z) > self.half_fov())


def counted(values, field):
    """The coefficients of a `[count, a0, a1, ...]` polynomial, the count checked."""
    values = [float(v) for v in values]
    if not values or values[0] != int(values[0]) or values[0] < 1 or int(values[0]) != len(values) - 1:
        raise ValueError(f"{field}: expected [count, a0, a1, ...] with count the number of "
                         f"coefficients that follow, found {values}")
    return values[1:]


def camera_from_config(entry, index):
    """A Camera from one entry of a config.yaml's `cameras:` list."""
    where = f"cameras[{index}]"
    if entry.get("model", "ocam") != "ocam":
        raise ValueError(f"{where}.model: unknown camera model {entry['model']!r}, expected ocam")
    cam_id = int(entry.get("cam_id", index + 1))
    return Camera(counted(entry["poly"], f"{where}.poly"), counted(entry["inv_poly"], f"{where}.inv_poly"),
                  entry["center"], entry["affine"], entry["image_size"], entry["max_fov"], entry["pose"],
                  str(entry.get("img_dir", f"cam{cam_id}")))


def data_lines(path):
    """The numbers of each line of a text file that is neither blank nor a `#` comment."""
    with open(path) as f:
        lines = [line.strip() for line in f]
    return [[float(v) for v in line.split()] for line in lines if line and not line.startswith("#")]


def read_released(ds):
    """The rig and settings of a folder in the released datasets' layout (ocam1.txt ... ocamN.txt,
    poses.txt with translations in centimetres, images cam1/ ... numbered 00001 or 0001), as a
    config.yaml would state them."""
    poses = data_lines(os.path.join(ds, "poses.txt"))
    cameras = []
    while os.path.isfile(os.path.join(ds, f"ocam{len(cameras) + 1}.txt")):
        k = len(cameras)
        lines = data_lines(os.path.join(ds, f"ocam{k + 1}.txt"))
        if len(lines) < 5 or [len(l) for l in lines[2:5]] != [2, 3, 2]:
            raise ValueError(f"ocam{k + 1}.txt: expected 5 data lines (poly, inv_poly, xc yc, c d e, height width)")
        if k >= len(poses) or len(poses[k]) != 6:
            raise ValueError(f"poses.txt: expected a line of 6 numbers (rx ry rz tx ty tz) for camera {k + 1}")
        pose = poses[k][:3] + [v / 100.0 for v in poses[k][3:]]
        cameras.append({"cam_id": k + 1, "img_dir": f"cam{k + 1}", "model": "ocam", "poly": lines[0],
                        "inv_poly": lines[1], "center": lines[2], "affine": lines[3],
                        "image_size": lines[4], "max_fov": RELEASED_MAX_FOV, "pose": pose})
    if len(poses) != len(cameras):
        raise ValueError(f"poses.txt: {len(poses)} lines for {len(cameras)} ocamK.txt files")
    # The naming of cam1/'s images that most of them follow: digits and extension.
    namings = {}
    for name in os.listdir(os.path.join(ds, "cam1")):
        stem, _, ext = name.rpartition(".")
        if stem.isdigit() and ext.lower() in IMAGE_EXTS:
            namings[(len(stem), ext)] = namings.get((len(stem), ext), 0) + 1
    if not namings:
        raise ValueError(f"{ds}/cam1: no numbered images (such as 00001.png)")
    digits, ext = max(sorted(namings), key=lambda k: namings[k])
    return {"config": {"omnimvs_sweep_min_depth": RELEASED_MIN_DEPTH},
            "dataset": {"img_fmt": f"cam%d/%0{digits}d.{ext}"}, "cameras": cameras}


def load(ds):
    """A dataset folder's settings (the config.yaml as a dict, or the released layout's as one),
    its cameras (Camera, in order) and its minimum depth (m)."""
    path = os.path.join(ds, "config.yaml")
    if not os.path.exists(path) and os.path.isfile(os.path.join(ds, "ocam1.txt")):
        cfg = read_released(ds)
    else:
        import yaml
        with open(path) as f:
            cfg = yaml.safe_load(f)
    cams = [camera_from_config(c, i) for i, c in enumerate(cfg.get("cameras") or [])]
    if not cams:
        raise ValueError(f"{path}: expected at least one camera in cameras:")
    min_depth = float(cfg["config"]["omnimvs_sweep_min_depth"])
    if not (math.isfinite(min_depth) and min_depth > 0):
        raise ValueError(f"{path}: config.omnimvs_sweep_min_depth: expected a positive depth, found {min_depth}")
    return cfg, cams, min_depth


def frame_path(ds, cam_idx, cfg, frame):
    """The image of camera cam_idx (0-based) at frame: dataset.img_fmt (camera 1-based, frame),
    then the same with the frame padded to 4 or 5 digits or not at all (released sets mix
    0001.png and 00001.png). The configured path when none exists."""
    fmt = cfg["dataset"]["img_fmt"]
    tried = [fmt % (cam_idx + 1, frame)]
    at = fmt.rfind("%")
    end = fmt.find("d", at) if at >= 0 else -1
    if end >= 0:
        tried += [(fmt[:at] + alt + fmt[end + 1:]) % (cam_idx + 1, frame) for alt in ("%04d", "%05d", "%d")]
    for p in tried:
        if os.path.isfile(os.path.join(ds, p)):
            return os.path.join(ds, p)
    return os.path.join(ds, tried[0])


def rays(h, w, phi_deg):
    """The unit rays (3, h w), rig frame, of the h x w grid over latitudes +-phi_deg, row-major."""
    rows, cols = np.meshgrid(np.arange(h, dtype=np.float64), np.arange(w, dtype=np.float64), indexing="ij")
    theta = (cols - w / 2.0) / (w / 2.0) * math.pi + math.pi / 2.0
    phi = (rows - (h - 1) / 2.0) / ((h - 1) / 2.0) * math.radians(phi_deg)
    return np.stack([-np.cos(phi) * np.cos(theta), np.sin(phi), np.cos(phi) * np.sin(theta)]).reshape(3, -1)


def bilinear(im, col, row):
    """Bilinear values of the image im (H x W) at (col, row), pixels, and whether the four
    neighbours of each lie inside the image (the value is 0 where they do not)."""
    h, w = im.shape
    col, row = np.asarray(col, dtype=np.float64), np.asarray(row, dtype=np.float64)
    c0, r0 = np.floor(col), np.floor(row)
    ok = (c0 >= 0) & (r0 >= 0) & (c0 + 1 < w) & (r0 + 1 < h)
    fc, fr = np.where(ok, col - c0, 0.0), np.where(ok, row - r0, 0.0)
    ci, ri = np.where(ok, c0, 0).astype(np.intp), np.where(ok, r0, 0).astype(np.intp)
    ci1, ri1 = np.minimum(ci + 1, w - 1), np.minimum(ri + 1, h - 1)
    v = (im[ri, ci] * (1 - fc) * (1 - fr) + im[ri, ci1] * fc * (1 - fr)
         + im[ri1, ci] * (1 - fc) * fr + im[ri1, ci1] * fc * fr)
    return np.where(ok, v, 0.0), ok


def read_f32_tiff(path):
    """The first single-channel 32-bit float page of a TIFF (ground truth holds an 8-bit picture
    first), as float64."""
    from PIL import Image
    with Image.open(path) as im:
        for page in range(getattr(im, "n_frames", 1)):
            im.seek(page)
            if im.mode == "F":
                return np.asarray(im, dtype=np.float64)
    raise ValueError(f"{path}: no single-channel 32-bit float page")


def read_inv_depth(path):
    """An inverse-depth map (1/m, float32) by its extension: .tif/.tiff the float page, .png the
    released 16-bit encoding (v / 65500 / 0.55), anything else raw little-endian f32 rows of 640."""
    ext = os.path.splitext(path)[1].lower()
    if ext in (".tif", ".tiff"):
        return read_f32_tiff(path).astype(np.float32)
    if ext == ".png":
        from PIL import Image
        with Image.open(path) as im:
            mode, v = im.mode, np.asarray(im)
        if mode not in ("I;16", "I;16B", "I") or v.ndim != 2:
            raise ValueError(f"{path}: expected a 16-bit gray PNG (released inverse-depth encoding)")
        return (v.astype(np.float64) / 65500.0 * (1.0 / RELEASED_MIN_DEPTH)).astype(np.float32)
    raw = np.fromfile(path, dtype="<f4")
    if raw.size == 0 or raw.size % GT_WIDTH:
        raise ValueError(f"{path}: raw f32 file of {raw.size * 4} bytes: expected whole rows of {GT_WIDTH} floats")
    return raw.reshape(-1, GT_WIDTH).astype(np.float32)


def gt_path(ds, frame, cfg=None):
    """The ground-truth file of frame: dataset.gt_fmt when the config names one, else
    omnidepth_gt_640/ or depth_train_640/ with the frame in 5 or 4 digits; None if there is none."""
    fmt = ((cfg or {}).get("dataset") or {}).get("gt_fmt")
    if fmt:
        p = os.path.join(ds, fmt % frame)
        return p if os.path.isfile(p) else None
    for folder in GT_DIRS:
        for digits in (5, 4):
            for ext in GT_EXTS:
                p = os.path.join(ds, folder, f"{frame:0{digits}d}.{ext}")
                if os.path.isfile(p):
                    return p
    return None


def gt_reference(ds, frame, h, w, phi_deg, cfg=None):
    """The ground-truth inverse depth (float32) for an h x w output over +-phi_deg, as the
    reference's loadGTInvdepthIndex takes it: the middle h rows of the map (start row
    round((H - h) / 2), ties to even). Only for a grid of the map's width with square pixels
    (phi_deg = 180 h / w, e.g. 160 x 640 at 45 degrees), the grid of the pick's data."""
    p = gt_path(ds, frame, cfg if cfg is not None else load(ds)[0])
    if p is None:
        raise FileNotFoundError(f"{ds}: no ground truth for frame {frame}")
    gt = read_inv_depth(p)
    gh, gw = gt.shape
    if gw != w or abs(phi_deg - 180.0 * h / w) > 1e-9 or h > gh:
        raise ValueError(f"{p}: a {gh}x{gw} map gives the reference's crop only for a grid of its "
                         f"width with square pixels, not {h}x{w} over +-{phi_deg} degrees")
    start = int(round((gh - h) / 2.0))
    return gt[start:start + h]


def _closing_pass(m, axis, dilate):
    """One 5-wide pass of a dilation (any) or erosion (all) along axis, outside pixels False."""
    pad = [(0, 0), (0, 0)]
    pad[axis] = (2, 2)
    p = np.pad(m, pad, constant_values=False)
    n = m.shape[axis]
    parts = [np.take(p, np.arange(k, k + n), axis=axis) for k in range(5)]
    return np.logical_or.reduce(parts) if dilate else np.logical_and.reduce(parts)


def binary_closing_5x5(mask):
    """The 5 x 5 binary closing of mask (dilation then erosion), pixels outside the image False."""
    d = _closing_pass(_closing_pass(mask, 1, True), 0, True)
    return _closing_pass(_closing_pass(d, 1, False), 0, False)


def reference_gt_index(gt_inv, min_depth, n=192):
    """The reference's ground-truth index of an inverse-depth map (1/m) for n hypotheses, and
    which pixels it scores (its evalError's 0 <= n* <= n), with d_0 and the step (1/m):
    index (d - d_0) / step, so that sky (inverse depth 0) is just below 0 and not scored; a pixel
    nearer than 1 km nowhere but inside a hole that a 5 x 5 closing of the finite mask fills
    (noise, not sky) is -1. Returns (index float64, valid, d_0, step)."""
    min_inv, max_inv = EPS, 1.0 / min_depth
    step = (max_inv - min_inv) / (n - 1.0)
    gt = np.asarray(gt_inv)
    index = (gt.astype(np.float64) - min_inv) / step
    finite = gt.astype(np.float32) >= FINITE_INV_DEPTH
    index[~finite & binary_closing_5x5(finite)] = -1.0
    return index, (index >= 0) & (index <= n), min_inv, step
