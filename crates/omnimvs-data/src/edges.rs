//! Depth edges without blends: where a method answers between the two surfaces of a depth
//! edge (a soft argmax that hedges, a window that straddles it), the point floats in the free
//! space between them, a phantom obstacle of a point cloud. [`snap_edges`] moves such answers
//! onto one of the two surfaces (a toggle filter).
//!
//! Measured on the bundled cascade's things and house validation frames
//! (`models/training/cascade-25/edge_post.py`, the README of `omnimvs-net`): it lowers the
//! share of pixels more than 1, 3 and 5 % of the range off, leaves the mean error as it was and
//! raises the RMS, because a pixel snapped to the wrong side is off by the whole step, so it
//! is an option (`infer --snap-edges`), not the default.

/// Per pixel of a row-major `height x width` index map on a full-circle equirectangular grid
/// (longitude wraps, rows are clamped): where the 3x3 neighbourhood's values span more than
/// `threshold` (index units), the pixel takes whichever of the neighbourhood's minimum and
/// maximum is nearer its own value (the maximum on a tie). All pixels read the map as it was
/// before the pass. Returns how many pixels changed; non-finite values are left as they are
/// and are not candidates.
///
/// # Panics
/// Never for consistent sizes; `index.len() != height * width` is a caller's bug and panics.
pub fn snap_edges(index: &mut [f32], height: usize, width: usize, threshold: f32) -> usize {
    assert_eq!(index.len(), height * width, "index map of {height}x{width}");
    let before = index.to_vec();
    let mut changed = 0;
    for r in 0..height {
        let rows = [r.saturating_sub(1), r, (r + 1).min(height - 1)];
        for c in 0..width {
            let v = before[r * width + c];
            if !v.is_finite() {
                continue;
            }
            let cols = [(c + width - 1) % width, c, (c + 1) % width];
            let (mut lo, mut hi) = (v, v);
            for &rr in &rows {
                for &cc in &cols {
                    let x = before[rr * width + cc];
                    if x.is_finite() {
                        lo = lo.min(x);
                        hi = hi.max(x);
                    }
                }
            }
            if hi - lo > threshold {
                let snapped = if v - lo < hi - v { lo } else { hi };
                if snapped != v {
                    index[r * width + c] = snapped;
                    changed += 1;
                }
            }
        }
    }
    changed
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step from 150 to 20 along a row, with a blended ramp between: every ramp pixel goes to
    /// the surface it is nearer, the flat parts stay.
    #[test]
    fn a_blended_step_becomes_a_step() {
        let row = [150.0, 150.0, 120.0, 60.0, 20.0, 20.0, 20.0, 150.0];
        let mut map: Vec<f32> = row.iter().chain(row.iter()).copied().collect();
        let changed = snap_edges(&mut map, 2, 8, 16.0);
        let want = [150.0, 150.0, 150.0, 20.0, 20.0, 20.0, 20.0, 150.0];
        assert_eq!(&map[..8], &want);
        assert_eq!(&map[8..], &want);
        assert_eq!(changed, 4);
    }

    /// The first column's neighbourhood holds the last column (longitude wraps), and a slope
    /// whose 3x3 spread stays under the threshold is left alone.
    #[test]
    fn longitude_wraps_and_gentle_slopes_stay() {
        let mut map = vec![100.0, 10.0, 10.0, 10.0, 120.0];
        snap_edges(&mut map, 1, 5, 16.0);
        // 100 sits between 10 (its right) and 120 (its left, across the seam): nearer 120.
        assert_eq!(map, vec![120.0, 10.0, 10.0, 10.0, 120.0]);
        // Up and down again, 5 per pixel: every 3x3 spread is 10, the seam's too.
        let mut slope: Vec<f32> = (0..12)
            .map(|i: i32| 50.0 + 5.0 * i.min(12 - i) as f32)
            .collect();
        let original = slope.clone();
        assert_eq!(snap_edges(&mut slope, 1, 12, 16.0), 0);
        assert_eq!(slope, original);
    }

    #[test]
    fn non_finite_values_are_neither_moved_nor_candidates() {
        // 100's neighbours are NaN and 70: it is the maximum and stays; 20's are 70 and NaN
        // (across the seam): it is the minimum and stays; 70 is nearer 100 than 20.
        let mut map = vec![f32::NAN, 100.0, 70.0, 20.0];
        assert_eq!(snap_edges(&mut map, 1, 4, 16.0), 1);
        assert!(map[0].is_nan());
        assert_eq!(&map[1..], &[100.0, 100.0, 20.0]);
    }
}
