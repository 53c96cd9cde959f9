#!/usr/bin/env python3
"""Parity fixtures made by the reference implementation's own code.

Takes a checkout of hyu-cvlab/omnimvs-pytorch (GPL-3.0; imported from its path, nothing of
it is copied into this project) and writes, under OUT (default
crates/omnimvs-cli/tests/fixtures/reference/):

  reference_ch8.pt            a checkpoint in the reference's format ({'net_state_dict', 'CH'}),
                              built with the reference's own OmniMVSNet class: random weights
                              (seed 2019), CH 8, batch-norm weights, biases and running
                              statistics randomised, the last layer (cost_computes.deconv5)
                              scaled x100 so that the softargmin is sharp
  <sample>_00001_index.f32    the reference's index map of frame 1 (160x640, N = 192; raw
                              little-endian f32, row major), for sunny_single and itbt_sample
  <sample>_00001_entropy.f32  the reference's entropy map of the same frame
  reference.json              what was run: versions, sizes, seeds, the index spread and, with
                              --omnimvs BIN, `omnimvs lut` against the reference's lookup table

by running the reference's test pipeline (run_test_omnimvs.py's main(): its Dataset, lookup
table, network forward, softargmin and entropy) on the CPU.

With --synth DIR --pred DIR (repeatable, in pairs) it also checks that the reference's Dataset
loads a dataset written by `omnimvs synth` as it is (config, images, invalid masks, the
two-page ground-truth TIFF, the train/test split) and scores the prediction
index maps PRED/%05d_index.tiff (as `omnimvs sgm` or `infer` write them) with the
reference's own loadGTInvdepthIndex + evalError: the figures go to reference.json
(`metrics`), what was scored to OUT/metrics/NAME/ (%05d_gt.tiff: the ground truth's f32
values, %05d_pred.png: the predictions as 16-bit round(index * 64)).

Shims, all for an old code base on new libraries, none changing what the reference computes:
numpy's removed `np.bool` alias is set to `bool`; scipy's
Rotation.as_dcm/from_dcm are its renamed as_matrix/from_matrix; scikit-image's MultiImage is
its ImageCollection (one element per TIFF page, MultiImage's behaviour before 0.19); `.cuda()` of tensors and modules is the
identity (the reference has no CPU switch); matplotlib draws off screen; the reference's
visualisation and thumbnail writers are off (run_test's `vis`/`save_misc` options, and results
written as raw f32, which the reference's own writers support by file extension).

Usage:
  python make_reference_fixture.py REF_CHECKOUT [--samples DIR] [--out DIR]
      [--synth DATASET --pred PREDICTIONS ...] [--skip-network] [--omnimvs BIN]
"""
import argparse
import json
import os
import shutil
import sys
import tempfile
import time

import numpy as np

SEED = 2019
CH = 8
NUM_INVDEPTH = 192
EQUIRECT = (160, 640)
SAMPLES = ["sunny_single", "itbt_sample"]
SCALE_LAST = 100.0
REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


def import_reference(checkout):
    """Puts the checkout on the path with the shims and returns its modules."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    if not hasattr(np, "bool"):
        np.bool = bool  # removed alias of numpy >= 1.24; the reference uses it as `bool`
    import torch
    from scipy.spatial.transform import Rotation

    if not hasattr(Rotation, "as_dcm"):  # renamed in scipy 1.4, the old names removed in 1.6
        Rotation.as_dcm, Rotation.from_dcm = Rotation.as_matrix, Rotation.from_matrix
    import skimage.io

    # scikit-image 0.19 made MultiImage stack a TIFF's pages into one element; the reference
    # (readImageFloat) expects one element per page, the old behaviour, which ImageCollection
    # keeps. Without it the reference cannot read the released sets' two-page TIFFs either.
    skimage.io.MultiImage = skimage.io.ImageCollection
    torch.Tensor.cuda = lambda self, *a, **k: self
    torch.nn.Module.cuda = lambda self, *a, **k: self
    sys.path.insert(0, os.path.abspath(checkout))
    return torch


def make_checkpoint(torch, path):
    from easydict import EasyDict as Edict
    from module.network import OmniMVSNet

    torch.manual_seed(SEED)
    net = OmniMVSNet(Edict(CH=CH, num_invdepth=NUM_INVDEPTH))
    g = torch.Generator().manual_seed(SEED + 1)
    with torch.no_grad():
        for m in net.modules():
            if isinstance(m, (torch.nn.BatchNorm2d, torch.nn.BatchNorm3d)):
                n = m.num_features
                m.weight.copy_(0.5 + torch.rand(n, generator=g))
                m.bias.copy_(0.1 * torch.randn(n, generator=g))
                m.running_mean.copy_(0.1 * torch.randn(n, generator=g))
                m.running_var.copy_(0.5 + torch.rand(n, generator=g))
        last = net.cost_computes.deconv5.conv
        last.weight.mul_(SCALE_LAST)
        last.bias.mul_(SCALE_LAST)
    torch.save({"net_state_dict": net.state_dict(), "CH": CH}, path)


def stage_sample(samples, name, root):
    """A writable copy of a read-only sample: the reference writes the invalid masks and its
    lookup table into the dataset folder. The images are linked, not copied."""
    dst = os.path.join(root, name)
    os.makedirs(dst)
    src = os.path.join(samples, name)
    for entry in os.listdir(src):
        s = os.path.join(src, entry)
        if os.path.isdir(s):
            os.symlink(os.path.abspath(s), os.path.join(dst, entry))
        else:
            shutil.copy(s, dst)


def run_reference_test(torch, ckpt, name, root, result_dir):
    """run_test_omnimvs.py's main() on frame 1 of `name`, CPU; returns (index, entropy)."""
    sys.argv = ["run_test_omnimvs.py", ckpt, name]
    import run_test_omnimvs as rt
    from dataset import Dataset

    rt.opts.snapshot_path = ckpt
    rt.opts.dbname = name
    rt.opts.db_root = root
    rt.opts.data_opts.start, rt.opts.data_opts.end = 1, 1
    rt.opts.vis, rt.opts.save_misc, rt.opts.save_result = False, False, True
    rt.opts.result_dir = result_dir
    rt.opts.out_invdepth_fmt = os.path.join(result_dir, "%05d_invdepth.f32")
    rt.opts.out_entropy_fmt = os.path.join(result_dir, "%05d_entropy.f32")
    seen = []
    original = Dataset.indexToInvdepth

    def capture(self, idx, start_index=0):  # the network's index map, as main() gets it
        seen.append(np.array(idx, dtype=np.float32))
        return original(self, idx, start_index)

    Dataset.indexToInvdepth = capture
    try:
        rt.main()
    finally:
        Dataset.indexToInvdepth = original
    (index,) = seen
    index = index.reshape(EQUIRECT)
    entropy = np.fromfile(os.path.join(result_dir, "00001_entropy.f32"), np.float32)
    invdepth = np.fromfile(os.path.join(result_dir, "00001_invdepth.f32"), np.float32)
    # The written inverse depth is the captured index converted by the reference.
    data = Dataset(name, rt.opts.data_opts, db_root=root, load_lut=False)
    back = data.invdepthToIndex(invdepth.astype(np.float64)).reshape(EQUIRECT)
    assert np.abs(back - index).max() < 1e-3, "captured index != written inverse depth"
    lut = os.path.join(root, name, "lt_(%d,%d,%d).hwd" % (*EQUIRECT, NUM_INVDEPTH))
    return index, entropy.reshape(EQUIRECT), lut


def compare_lut(omnimvs, sample_dir, reference_lut, tmp):
    """`omnimvs lut` against the lookup table the reference built: the largest difference in
    pixels of the camera image over entries valid in both, and the entries valid in one only."""
    import subprocess

    ours_path = os.path.join(tmp, "ours.hwd")
    subprocess.run([omnimvs, "lut", sample_dir, "--out", ours_path], check=True,
                   env=dict(os.environ, OMNIMVS_CACHE_DIR=os.path.join(tmp, "cache")),
                   stdout=subprocess.DEVNULL)
    ours = np.fromfile(ours_path, np.float32).reshape(4, NUM_INVDEPTH // 2, *EQUIRECT, 2)
    theirs = np.fromfile(reference_lut, np.float32).reshape(ours.shape)
    valid_o = (np.abs(ours) <= 1).all(-1)
    valid_t = (np.abs(theirs) <= 1).all(-1)
    both = valid_o & valid_t
    import yaml
    cams = yaml.safe_load(open(os.path.join(sample_dir, "config.yaml")))["cameras"]
    worst = 0.0
    for c in range(4):
        h, w = cams[c]["image_size"]
        scale = np.array([(w - 1) / 2.0, (h - 1) / 2.0])
        d = np.abs(ours[c] - theirs[c])[both[c]] * scale
        worst = max(worst, float(d.max()))
    return {"valid_entries": int(both.sum()), "valid_in_one_only": int((valid_o ^ valid_t).sum()),
            "max_difference_px": worst}


PRED_SCALE = 64  # predictions are stored as 16-bit PNG of round(index * PRED_SCALE)


def check_synth(torch, dataset_dir, pred_dir, out_dir, report):
    """The reference's Dataset on a folder written by `omnimvs synth`, unchanged (read-only:
    it has its masks), and the reference's evalError of predictions.

    The predictions PRED/%05d_index.tiff are quantised to 1/PRED_SCALE of a step and stored as
    16-bit PNG, the ground truth's f32 page is stored deflated behind a small thumbnail (the
    released two-page layout); both sides of the test score exactly those values."""
    from dataset import Dataset
    import tifffile
    import skimage.io
    import skimage.transform
    from easydict import EasyDict as Edict
    from utils.image import readImageFloat

    dataset_dir = os.path.abspath(dataset_dir)
    root, name = os.path.split(dataset_dir)
    before = sorted(os.listdir(dataset_dir))
    opts = Edict(equirect_size=list(EQUIRECT), num_invdepth=NUM_INVDEPTH, phi_deg=45.0)
    data = Dataset(name, opts, db_root=root, load_lut=False)
    assert data.dbname == name, "the reference lower-cases dataset names; name it in lower case"
    assert sorted(os.listdir(dataset_dir)) == before, "the reference had to write into it"
    assert data.dtype == "gt", "config.yaml does not say the dataset has ground truth"
    assert data.train_size + data.test_size > 0, "config.yaml has no train/test split"
    assert set(data.train_idx + data.test_idx) == set(data.frame_idx), "split != frames"
    assert not set(data.train_idx) & set(data.test_idx), "a frame both train and test"
    for i, ocam in enumerate(data.ocams):
        assert ocam.invalid_mask.any() and not ocam.invalid_mask.all(), f"mask{i + 1}"
    frames = []
    mdir = os.path.join(out_dir, "metrics", name)
    os.makedirs(mdir, exist_ok=True)
    for fidx in data.frame_idx:
        imgs, gt, valid, raw = data.loadSample(fidx)
        assert len(imgs) == 4 and imgs[0].ndim == 3, "images"
        assert gt.shape == EQUIRECT and valid.any(), "ground truth"
        # The reference's training sample too (what its trainer's DataLoader calls).
        if fidx in data.train_idx:
            data.loadTrainSample(data.train_idx.index(fidx))
        else:
            data.loadTestSample(data.test_idx.index(fidx))
        pred_path = os.path.join(pred_dir, "%05d_index.tiff" % fidx)
        pred = tifffile.imread(pred_path).astype(np.float32)
        assert pred.shape == EQUIRECT, pred_path
        q = np.clip(np.round(pred * PRED_SCALE), 0, 65535).astype(np.uint16)
        pred = q.astype(np.float32) / np.float32(PRED_SCALE)
        e = data.evalError(pred, gt, valid)
        frames.append({"frame": fidx, "errors": [float(x) for x in e]})
        # Fixture copies: the ground truth's f32 values, bit for bit, and the predictions.
        gt_src = os.path.join(dataset_dir, data.gt_depth_fmt % (EQUIRECT[1], fidx))
        gt_f32 = readImageFloat(gt_src)
        thumb = np.zeros((8, 16, 3), np.uint8)
        gt_dst = os.path.join(mdir, "%05d_gt.tiff" % fidx)
        with tifffile.TiffWriter(gt_dst) as tif:
            tif.write(thumb, photometric="rgb")
            tif.write(gt_f32.astype(np.float32), photometric="minisblack",
                      compression="zlib", compressionargs={"level": 9})
        assert np.array_equal(readImageFloat(gt_dst), gt_f32), gt_dst
        skimage.io.imsave(os.path.join(mdir, "%05d_pred.png" % fidx), q, check_contrast=False)
    mean = np.mean([f["errors"] for f in frames], axis=0)
    report["metrics"].append({
        "dataset": name,
        "min_depth_m": data.min_depth,
        "pred_scale": PRED_SCALE,
        "train_idx": data.train_idx,
        "test_idx": data.test_idx,
        "gt_phi": data.gt_phi,
        "frames": frames,
        "mean": [float(x) for x in mean],
    })


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("checkout", help="a checkout of hyu-cvlab/omnimvs-pytorch")
    ap.add_argument("--samples", default=os.path.join(REPO, "..", "shared", "data", "omnimvs-samples"))
    ap.add_argument("--out", default=os.path.join(REPO, "crates", "omnimvs-cli", "tests", "fixtures", "reference"))
    ap.add_argument("--synth", action="append", default=[], help="a dataset written by omnimvs synth")
    ap.add_argument("--pred", action="append", default=[], help="its predictions (%%05d_index.tiff)")
    ap.add_argument("--skip-network", action="store_true", help="only the --synth checks")
    ap.add_argument("--omnimvs", help="an omnimvs binary: compare its lookup table with the reference's")
    args = ap.parse_args()
    assert len(args.synth) == len(args.pred), "--synth and --pred go in pairs"
    torch = import_reference(args.checkout)
    torch.set_num_threads(max(1, os.cpu_count() or 1))
    os.makedirs(args.out, exist_ok=True)
    commit = os.popen(f"git -C {args.checkout} rev-parse HEAD 2>/dev/null").read().strip()
    report_path = os.path.join(args.out, "reference.json")
    report = json.load(open(report_path)) if os.path.exists(report_path) else {}
    report.update({
        "reference": "hyu-cvlab/omnimvs-pytorch",
        "reference_commit": commit,
        "torch": torch.__version__,
        "numpy": np.__version__,
    })
    if not args.skip_network:
        ckpt = os.path.join(args.out, "reference_ch8.pt")
        make_checkpoint(torch, ckpt)
        report.update({"checkpoint": "reference_ch8.pt", "CH": CH, "seed": SEED,
                       "last_layer_scale": SCALE_LAST, "num_invdepth": NUM_INVDEPTH,
                       "equirect_size": list(EQUIRECT), "frame": 1, "samples": {}})
        with tempfile.TemporaryDirectory() as tmp:
            for name in SAMPLES:
                root = os.path.join(tmp, "data")
                stage_sample(args.samples, name, root)
                t = time.time()
                index, entropy, lut = run_reference_test(
                    torch, ckpt, name, root, os.path.join(tmp, "results", name))
                secs = time.time() - t
                index.astype("<f4").tofile(os.path.join(args.out, f"{name}_00001_index.f32"))
                entropy.astype("<f4").tofile(os.path.join(args.out, f"{name}_00001_entropy.f32"))
                frac = np.abs(index - np.round(index))
                report["samples"][name] = {
                    "index_min": float(index.min()), "index_max": float(index.max()),
                    "index_std": float(index.std()),
                    "mean_distance_to_integer": float(frac.mean()),
                    "entropy_mean": float(entropy.mean()), "entropy_max": float(entropy.max()),
                    "seconds": round(secs, 1),
                }
                if args.omnimvs:
                    report["samples"][name]["lut_vs_omnimvs"] = compare_lut(
                        args.omnimvs, os.path.join(args.samples, name), lut, tmp)
                print(name, report["samples"][name], flush=True)
    if args.synth:
        report["metrics"] = []
        for d, p in zip(args.synth, args.pred):
            check_synth(torch, d, p, args.out, report)
            print(report["metrics"][-1]["dataset"], report["metrics"][-1]["mean"], flush=True)
    with open(report_path, "w") as f:
        json.dump(report, f, indent=1)
        f.write("\n")


if __name__ == "__main__":
    main()
