//! Post-processing of the index map against outliers: a median filter that
//! removes isolated wrong answers, and confidence-based invalidation that leaves ambiguous
//! pixels without an answer (NaN; `eval` reports the share that keeps one as coverage).

use rayon::prelude::*;

use crate::IndexMap;

/// The median of the `size x size` window around every pixel (longitude wraps round, rows
/// are clipped at the top and bottom); `size` 0 or 1 leaves the map as it is. Non-finite
/// values (invalidated pixels) take no part, and a pixel whose window holds none stays NaN.
pub fn median_filter(map: &IndexMap, size: usize) -> Vec<f32> {
    if size <= 1 {
        return map.index.clone();
    }
    let (w, h) = (map.width, map.height);
    let r = size / 2;
    let src = &map.index;
    // The window's columns round the ring, per output column (no division per pixel).
    let k = 2 * r + 1;
    let cols: Vec<usize> = (0..w)
        .flat_map(|x| (0..k).map(move |dx| (x + w * (r / w + 1) + dx - r) % w))
        .collect();
    let mut out = vec![0f32; w * h];
    out.par_chunks_mut(w).enumerate().for_each_init(
        || Vec::with_capacity(size * size),
        |window, (row, dst)| {
            let (r0, r1) = (row.saturating_sub(r), (row + r + 1).min(h));
            for (x, o) in dst.iter_mut().enumerate() {
                window.clear();
                for y in r0..r1 {
                    for &c in &cols[x * k..(x + 1) * k] {
                        let v = src[y * w + c];
                        if v.is_finite() {
                            window.push(v);
                        }
                    }
                }
                *o = if window.is_empty() {
                    f32::NAN
                } else {
                    let k = window.len() / 2;
                    let (_, m, _) = window.select_nth_unstable_by(k, f32::total_cmp);
                    *m
                };
            }
        },
    );
    out
}

/// Sets the index of every pixel whose confidence is below `min_confidence` to NaN; returns
/// how many were invalidated.
pub fn invalidate_below(map: &mut IndexMap, min_confidence: f32) -> usize {
    let mut count = 0;
    for (n, &c) in map.index.iter_mut().zip(&map.confidence) {
        if c < min_confidence {
            *n = f32::NAN;
            count += 1;
        }
    }
    count
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(width: usize, height: usize, index: Vec<f32>) -> IndexMap {
        IndexMap {
            height,
            width,
            confidence: vec![1.0; index.len()],
            index,
        }
    }

    #[test]
    fn median_removes_an_isolated_outlier_and_keeps_a_step() {
        // 3 rows x 6 columns: a step between columns 2 and 3, one outlier at (1, 1).
        let mut v = vec![];
        for _ in 0..3 {
            v.extend([10.0, 10.0, 10.0, 50.0, 50.0, 50.0]);
        }
        v[7] = 180.0;
        let m = map(6, 3, v);
        let out = median_filter(&m, 3);
        assert_eq!(out[7], 10.0);
        // Columns 1 and 4 keep their side of the step.
        assert_eq!(out[6 + 4], 50.0);
        assert_eq!(out[1], 10.0);
        // Longitude wraps: column 0's window holds column 5.
        let ring = map(4, 1, vec![1.0, 2.0, 9.0, 3.0]);
        assert_eq!(median_filter(&ring, 3), vec![2.0, 2.0, 3.0, 3.0]);
        assert_eq!(median_filter(&ring, 1), ring.index);
    }

    #[test]
    fn invalidated_pixels_take_no_part() {
        let mut m = map(3, 1, vec![5.0, 7.0, 100.0]);
        m.confidence = vec![0.5, 0.01, 0.5];
        assert_eq!(invalidate_below(&mut m, 0.05), 1);
        assert!(m.index[1].is_nan());
        let out = median_filter(&m, 3);
        // Windows {100, 5, NaN}, {5, NaN, 100}, {NaN, 100, 5}: medians of two values.
        assert!(out.iter().all(|v| *v == 5.0 || *v == 100.0));
        let mut none = map(2, 1, vec![1.0, 2.0]);
        none.confidence = vec![0.0, 0.0];
        invalidate_below(&mut none, 0.1);
        assert!(median_filter(&none, 3).iter().all(|v| v.is_nan()));
    }
}
