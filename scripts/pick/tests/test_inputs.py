"""pick_inputs.py's numpy parts: box sums, the cameras' ZNCC, image normalisation, the channel
count and order of the inputs (against a stand-in for geometry.py)."""
import types

import numpy as np
import pytest

import pick_inputs as pi


def window(h, w, y, x, p):
    """Rows and columns of the (2 p + 1)^2 window at (y, x): rows cut, columns wrapping."""
    rows = list(range(max(0, y - p), min(h, y + p + 1)))
    cols = [(x + d) % w for d in range(-p, p + 1)]
    return np.ix_(rows, cols)


@pytest.mark.parametrize("k", [1, 3, 5, 7])
def test_box_sum_against_brute_force(k):
    rng = np.random.default_rng(4)
    a = rng.normal(size=(9, 14))
    s = pi.box_sum(a, k)
    assert s.shape == a.shape
    for y in range(9):
        for x in range(14):
            assert s[y, x] == pytest.approx(a[window(9, 14, y, x, k // 2)].sum(), abs=1e-9)


def brute_zncc(grays, sees, k):
    """The ZNCC inputs pixel by pixel: mean over the pairs that count, fraction that count."""
    h, w = grays[0].shape
    p, pairs = k // 2, []
    for i in range(len(grays)):
        for j in range(i + 1, len(grays)):
            pairs.append((i, j))
    mean, frac = np.zeros((h, w)), np.zeros((h, w))
    for y in range(h):
        for x in range(w):
            win = window(h, w, y, x, p)
            zs = []
            for i, j in pairs:
                m = sees[i][win] * sees[j][win]
                a, b, n = grays[i][win], grays[j][win], m.sum()
                if not (sees[i][y, x] * sees[j][y, x] > 0 and 2 * n >= k * k):
                    continue
                sa, sb = (m * a).sum(), (m * b).sum()
                cov = (m * a * b).sum() - sa * sb / n
                va, vb = (m * a * a).sum() - sa * sa / n, (m * b * b).sum() - sb * sb / n
                zs.append(cov / np.sqrt(max(va, 0) * max(vb, 0) + (0.01 * n) ** 2 + 1e-12))
            mean[y, x] = np.mean(zs) if zs else 0.0
            frac[y, x] = len(zs) / len(pairs)
    return mean, frac


def test_zncc_against_brute_force():
    rng = np.random.default_rng(5)
    h, w, k = 8, 12, 5
    grays = [rng.normal(size=(h, w)) for _ in range(3)]
    sees = [(rng.uniform(size=(h, w)) > 0.3).astype(np.float64) for _ in range(3)]
    z, f = pi.zncc(grays, sees, k)
    ez, ef = brute_zncc(grays, sees, k)
    np.testing.assert_allclose(z, ez, atol=1e-9)
    np.testing.assert_allclose(f, ef, atol=1e-12)


def test_zncc_of_equal_and_opposite_images():
    rng = np.random.default_rng(6)
    a = rng.normal(size=(10, 20))
    ones = np.ones_like(a)
    z, f = pi.zncc([a, a], [ones, ones], 5)
    assert (z > 0.99).all() and (z <= 1).all() and (f == 1).all()
    z, f = pi.zncc([a, -a], [ones, ones], 5)
    assert (z < -0.99).all() and (f == 1).all()
    # A camera that sees nothing: its pairs never count.
    z, f = pi.zncc([a, a, a], [ones, ones, np.zeros_like(a)], 5)
    np.testing.assert_allclose(f, 1 / 3)
    assert (z > 0.99).all()
    z, f = pi.zncc([a, a], [ones, np.zeros_like(a)], 5)
    assert (z == 0).all() and (f == 0).all()


def test_normalise():
    rng = np.random.default_rng(7)
    rgb = rng.integers(0, 256, size=(6, 9, 3)).astype(np.uint8)
    n = pi.normalise(rgb)
    gray = rgb.astype(np.float64).mean(-1)
    np.testing.assert_allclose(n, (gray - gray.mean()) / gray.std(), atol=1e-9)
    assert n.mean() == pytest.approx(0, abs=1e-12) and n.std() == pytest.approx(1, abs=1e-9)
    np.testing.assert_array_equal(pi.normalise(np.full((4, 4), 7.0)), np.zeros((4, 4)))


def test_channel_counts_match_the_rust_layout():
    # PickLayout::input_channels: the bundled picks read 29 channels for four cameras; the wider
    # layout (depth radii 2, 12 and a 5 x 5 ZNCC) 58; one camera with it 28.
    assert pi.channels(4, (2,), 0) == 29
    assert pi.channels(4, (2, 12), 5) == 58
    assert pi.channels(1, (2, 12), 5) == 28


class StubCam:
    """A camera of the stand-in geometry: a point at depth scale s = 1 / X[2] of pixel (row, col)
    lands on (row, col + dx) of its image, seen where s < limit."""

    def __init__(self, dx, limit):
        self.dx, self.limit = dx, limit

    def project(self, X):
        s = 1.0 / X[2]
        return X[0] * s + self.dx, X[1] * s, s < self.limit


def stub_geometry(h, w):
    def rays(hh, ww, phi):
        assert (hh, ww) == (h, w)
        rows, cols = np.meshgrid(np.arange(h, dtype=np.float64), np.arange(w, dtype=np.float64), indexing="ij")
        return np.stack([cols.ravel(), rows.ravel(), np.ones(h * w)])

    def bilinear(im, col, row):  # integer positions only, in the stand-in
        c, r = np.round(col).astype(int), np.round(row).astype(int)
        ok = (c >= 0) & (c < im.shape[1]) & (r >= 0) & (r < im.shape[0])
        return im[np.clip(r, 0, im.shape[0] - 1), np.clip(c, 0, im.shape[1] - 1)], ok

    return types.SimpleNamespace(rays=rays, bilinear=bilinear)


@pytest.mark.parametrize("depth_radii,zncc_k", [((2,), 0), ((2, 12), 5)])
def test_features_layout(monkeypatch, depth_radii, zncc_k):
    h, w = 12, 40
    monkeypatch.setattr(pi, "geometry", stub_geometry(h, w))
    rng = np.random.default_rng(8)
    v = rng.uniform(0, 191, size=(h, w))
    spread = rng.uniform(0, 40, size=(h, w))
    min_inv, step = 0.0, 0.01
    cams = [StubCam(0, 1.2), StubCam(1, 0.8)]
    ims = [rng.normal(size=(h, w + 1)) for _ in cams]
    x = pi.features(ims, cams, v, spread, min_inv, step, depth_radii=depth_radii, zncc_k=zncc_k)
    assert x.shape == (pi.channels(len(cams), depth_radii, zncc_k), h, w)
    np.testing.assert_allclose(x[0], v / 192)
    np.testing.assert_allclose(x[1], spread / 30)
    depths, at = [v], 2
    for r in depth_radii:
        mn, mx = pi.minmax(v, 2 * r + 1)
        np.testing.assert_allclose(x[at], (mx - mn) / 32)
        np.testing.assert_allclose(x[at + 1], (mn - v) / 32)
        np.testing.assert_allclose(x[at + 2], (mx - v) / 32)
        depths += [mn, mx]
        at += 3
    rows, cols = np.meshgrid(np.arange(h), np.arange(w), indexing="ij")
    for c in depths:  # each depth: every camera's gray value and whether it sees the point
        s = np.maximum(min_inv + c * step, 1e-6)
        for cam, im in zip(cams, ims):
            sees = (s < cam.limit).astype(np.float64)
            np.testing.assert_allclose(x[at + 1], sees)
            np.testing.assert_allclose(x[at], im[rows, cols + cam.dx] * sees)
            at += 2
    if zncc_k:
        assert at + 2 * len(depths) == x.shape[0]
        z, f = pi.zncc([x[2 + 3 * len(depth_radii)], x[2 + 3 * len(depth_radii) + 2]],
                       [x[3 + 3 * len(depth_radii)], x[3 + 3 * len(depth_radii) + 2]], zncc_k)
        np.testing.assert_allclose(x[at], z)
        np.testing.assert_allclose(x[at + 1], f)
    else:
        assert at == x.shape[0]
