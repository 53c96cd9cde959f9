"""The candidates a pick chooses among: the answer and the minimum / maximum of the answers over
windows around each pixel, columns wrapping in longitude and rows stopping at the border."""
import numpy as np
import pytest

from pick_common import candidates
import pick_inputs as pi


def brute_extremes(v, r):
    """Minimum and maximum over the (2 r + 1)^2 window, by looping over the pixels."""
    h, w = v.shape
    mn, mx = np.empty_like(v), np.empty_like(v)
    for y in range(h):
        rows = list(range(max(0, y - r), min(h, y + r + 1)))
        for x in range(w):
            cols = [(x + d) % w for d in range(-r, r + 1)]
            win = v[np.ix_(rows, cols)]
            mn[y, x], mx[y, x] = win.min(), win.max()
    return mn, mx


def test_a_spike_reaches_across_the_seam():
    v = np.zeros((1, 3, 8), np.float32)
    v[0, 1, 0] = 5.0  # middle row, first column
    c = candidates(v, (1,))
    assert c.shape == (1, 3, 3, 8)
    np.testing.assert_array_equal(c[0, 0], v[0])
    # The 3 x 3 maximum holds the spike at columns 7 (across the seam), 0 and 1, on every row.
    expected = np.zeros((3, 8), np.float32)
    expected[:, [7, 0, 1]] = 5.0
    np.testing.assert_array_equal(c[0, 2], expected)
    np.testing.assert_array_equal(c[0, 1], np.zeros((3, 8), np.float32))


@pytest.mark.parametrize("radii", [(1, 2, 4), (1, 2, 4, 7, 12), (3,)])
def test_candidates_against_brute_force(radii):
    rng = np.random.default_rng(1)
    v = rng.uniform(0, 191, size=(2, 20, 40)).astype(np.float32)
    c = candidates(v, radii)
    assert c.shape == (2, 1 + 2 * len(radii), 20, 40)
    for b in range(2):
        np.testing.assert_array_equal(c[b, 0], v[b])
        for i, r in enumerate(radii):
            mn, mx = brute_extremes(v[b], r)
            np.testing.assert_array_equal(c[b, 1 + 2 * i], mn)
            np.testing.assert_array_equal(c[b, 2 + 2 * i], mx)


def test_candidates_bracket_the_answer_and_widen_with_the_radius():
    rng = np.random.default_rng(2)
    v = rng.uniform(0, 191, size=(1, 16, 32)).astype(np.float32)
    c = candidates(v, (1, 2, 4))[0]
    for i in range(3):
        assert (c[1 + 2 * i] <= v[0]).all() and (c[2 + 2 * i] >= v[0]).all()
    for i in range(2):
        assert (c[3 + 2 * i] <= c[1 + 2 * i]).all() and (c[4 + 2 * i] >= c[2 + 2 * i]).all()


@pytest.mark.parametrize("k", [3, 5, 25])
def test_inputs_minmax_against_brute_force(k):
    rng = np.random.default_rng(3)
    v = rng.uniform(0, 191, size=(30, 64))
    mn, mx = pi.minmax(v, k)
    emn, emx = brute_extremes(v, k // 2)
    np.testing.assert_array_equal(mn, emn)
    np.testing.assert_array_equal(mx, emx)
