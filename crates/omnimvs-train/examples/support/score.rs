//! Scoring an index map against the training ground truth the way the reference does (sky,
//! index 0, left out), shared by the cascade examples (included with `#[path]`).

/// Sums over scored pixels: |error|, count, and counts above 1, 3 and 5.
#[derive(Default, Clone, Copy)]
pub struct Score([f64; 5]);

impl Score {
    pub fn add(&mut self, answer: &[f32], truth: &[f32], valid: &[bool]) {
        for ((&n, &t), &v) in answer.iter().zip(truth).zip(valid) {
            if !v || t <= 0.0 {
                continue;
            }
            let e = f64::from((n - t).abs());
            self.0[0] += e;
            self.0[1] += 1.0;
            for (k, th) in [1.0, 3.0, 5.0].into_iter().enumerate() {
                if e > th {
                    self.0[2 + k] += 1.0;
                }
            }
        }
    }

    pub fn line(&self, name: &str) -> String {
        let [sum, n, a, b, c] = self.0;
        let pct = |x: f64| 100.0 * x / n.max(1.0);
        format!(
            "{name:40} >1 {:5.1}%  >3 {:5.1}%  >5 {:5.1}%  MAE {:.2}  ({n} pixels)",
            pct(a),
            pct(b),
            pct(c),
            sum / n.max(1.0)
        )
    }
}
