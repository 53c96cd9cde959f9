//! Depth edges without blends: where a method answers between the two surfaces of a depth
//! edge (a soft argmax that hedges, a window that straddles it), the point floats in the free
//! space between them, a phantom obstacle of a point cloud. [`snap_edges`] moves such answers
//! onto one of the two surfaces (a toggle filter).
//!
//! Measured on the bundled cascade's things and house validation frames
//! (`research/errors.md`): it lowers the
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
    let (low, high) = neighbour_min_max(index, [height, width], true, 1);
    let mut changed = 0;
    for ((v, lo), hi) in index.iter_mut().zip(low).zip(high) {
        // A finite value is in its own neighbourhood: lo <= v <= hi.
        if v.is_finite() && hi - lo > threshold {
            let snapped = if *v - lo < hi - *v { lo } else { hi };
            if snapped != *v {
                *v = snapped;
                changed += 1;
            }
        }
    }
    changed
}

/// The lowest and highest finite value of a row-major `[rows, cols]` map over the
/// `(2 radius + 1)^2` pixels around each pixel (infinity and minus infinity where there is
/// none). Columns wrap around when `wrap` (a whole panorama), else the neighbourhood stops at
/// the first and last column (a window of columns); rows stop at the first and last row.
/// Separable: along each row, then along each column of the row results.
///
/// # Panics
/// Never for consistent sizes; `map.len() != rows * cols` is a caller's bug and panics.
pub fn neighbour_min_max(
    map: &[f32],
    [rows, cols]: [usize; 2],
    wrap: bool,
    radius: usize,
) -> (Vec<f32>, Vec<f32>) {
    use rayon::prelude::*;
    let pixels = rows * cols;
    assert_eq!(map.len(), pixels, "map of {rows}x{cols}");
    let mut row_min = vec![0f32; pixels];
    let mut row_max = vec![0f32; pixels];
    let window = 2 * radius + 1;
    row_min
        .par_chunks_mut(cols.max(1))
        .zip(row_max.par_chunks_mut(cols.max(1)))
        .enumerate()
        .for_each(|(y, (lo_row, hi_row))| {
            let line = &map[y * cols..(y + 1) * cols];
            // The row extended by `radius` on each side: wrapped, or nothing (`fill`, an
            // infinity) past the ends; non-finite values are not extremes.
            let extended = |fill: f32| -> Vec<f32> {
                let mut e = vec![fill; cols + 2 * radius];
                if !wrap {
                    e[radius..radius + cols].copy_from_slice(line);
                } else if radius < cols {
                    e[..radius].copy_from_slice(&line[cols - radius..]);
                    e[radius..radius + cols].copy_from_slice(line);
                    e[radius + cols..].copy_from_slice(&line[..radius]);
                } else {
                    for (i, v) in e.iter_mut().enumerate() {
                        *v = line[(i + cols * (radius / cols + 1) - radius) % cols];
                    }
                }
                e.iter_mut()
                    .filter(|v| !v.is_finite())
                    .for_each(|v| *v = fill);
                e
            };
            let (lows, highs) = (extended(f32::INFINITY), extended(f32::NEG_INFINITY));
            sliding_extreme(&lows, window, f32::min, lo_row);
            sliding_extreme(&highs, window, f32::max, hi_row);
        });
    // Along columns (rows stop at the first and last), a whole row at a time.
    let mut low = vec![0f32; pixels];
    let mut high = vec![0f32; pixels];
    low.par_chunks_mut(cols.max(1))
        .zip(high.par_chunks_mut(cols.max(1)))
        .enumerate()
        .for_each(|(y, (lo, hi))| {
            lo.fill(f32::INFINITY);
            hi.fill(f32::NEG_INFINITY);
            for yy in y.saturating_sub(radius)..=(y + radius).min(rows - 1) {
                let (rmin, rmax) = (
                    &row_min[yy * cols..(yy + 1) * cols],
                    &row_max[yy * cols..(yy + 1) * cols],
                );
                lo.iter_mut().zip(rmin).for_each(|(a, &b)| *a = a.min(b));
                hi.iter_mut().zip(rmax).for_each(|(a, &b)| *a = a.max(b));
            }
        });
    (low, high)
}

/// `out[x]` = the extreme (`pick`: `f32::min` or `f32::max`) of `values[x..x + window]`, in
/// constant time per value (van Herk / Gil-Werman: running extremes forward and backward within
/// blocks of `window`).
fn sliding_extreme(values: &[f32], window: usize, pick: fn(f32, f32) -> f32, out: &mut [f32]) {
    let len = values.len();
    let mut forward = values.to_vec();
    let mut backward = values.to_vec();
    for i in 1..len {
        if i % window != 0 {
            forward[i] = pick(forward[i - 1], values[i]);
        }
    }
    for i in (0..len.saturating_sub(1)).rev() {
        if (i + 1) % window != 0 {
            backward[i] = pick(backward[i + 1], values[i]);
        }
    }
    for (x, o) in out.iter_mut().enumerate() {
        *o = pick(backward[x], forward[x + window - 1]);
    }
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

    /// Radius 2 without wrapping stops at the first and last column; non-finite values are
    /// not extremes, and a neighbourhood without a finite value has none.
    #[test]
    fn neighbourhood_extremes_skip_non_finite_values() {
        let map = [1.0, f32::NAN, 5.0, f32::INFINITY, 3.0, f32::NAN];
        let (low, high) = neighbour_min_max(&map, [1, 6], false, 2);
        assert_eq!(low, [1.0, 1.0, 1.0, 3.0, 3.0, 3.0]);
        assert_eq!(high, [5.0, 5.0, 5.0, 5.0, 5.0, 3.0]);
        let (low, high) = neighbour_min_max(&[f32::NAN; 3], [3, 1], true, 1);
        assert!(low.iter().all(|&v| v == f32::INFINITY));
        assert!(high.iter().all(|&v| v == f32::NEG_INFINITY));
    }

    /// The extremes by their definition, one neighbourhood at a time.
    fn naive_min_max(
        map: &[f32],
        [rows, cols]: [usize; 2],
        wrap: bool,
        radius: usize,
    ) -> (Vec<f32>, Vec<f32>) {
        let r = radius as isize;
        let mut low = vec![f32::INFINITY; rows * cols];
        let mut high = vec![f32::NEG_INFINITY; rows * cols];
        for y in 0..rows as isize {
            for x in 0..cols as isize {
                let p = (y * cols as isize + x) as usize;
                for dy in -r..=r {
                    for dx in -r..=r {
                        let (yy, mut xx) = (y + dy, x + dx);
                        if !(0..rows as isize).contains(&yy) {
                            continue;
                        }
                        if wrap {
                            xx = xx.rem_euclid(cols as isize);
                        } else if !(0..cols as isize).contains(&xx) {
                            continue;
                        }
                        let v = map[(yy * cols as isize + xx) as usize];
                        if v.is_finite() {
                            low[p] = low[p].min(v);
                            high[p] = high[p].max(v);
                        }
                    }
                }
            }
        }
        (low, high)
    }

    /// The separable, constant-time-per-pixel extremes equal the definition on random maps
    /// (with non-finite values), wrapping or not, for radii below, at and above the width.
    #[test]
    fn extremes_equal_their_definition() {
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) as f32 / (1u64 << 31) as f32
        };
        for &(rows, cols) in &[(1usize, 1usize), (3, 7), (9, 16), (5, 40)] {
            let map: Vec<f32> = (0..rows * cols)
                .map(|_| {
                    let v = next();
                    if v < 0.05 {
                        f32::NAN
                    } else if v < 0.08 {
                        f32::INFINITY
                    } else {
                        200.0 * v
                    }
                })
                .collect();
            for radius in [0, 1, 2, 4, 7, 12, 20] {
                for wrap in [true, false] {
                    let fast = neighbour_min_max(&map, [rows, cols], wrap, radius);
                    let slow = naive_min_max(&map, [rows, cols], wrap, radius);
                    assert_eq!(fast, slow, "{rows}x{cols} radius {radius} wrap {wrap}");
                }
            }
        }
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
