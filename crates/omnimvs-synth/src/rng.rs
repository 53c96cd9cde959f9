//! The scene generators' random draws: distributions (ranges, Marsaglia's
//! sphere points, rotations) over the workspace's one SplitMix64
//! ([`omnimvs_core::rng`]).

use nalgebra::{UnitQuaternion, Vector3};
use omnimvs_core::rng::{GAMMA, SplitMix64, mix64};

/// A SplitMix64 stream seeded through [`mix64`], with the draws the scene
/// generators need (one stream per scene, forked per sub-task).
#[derive(Debug, Clone)]
pub struct Rng {
    core: SplitMix64,
}

impl Rng {
    pub fn new(seed: u64) -> Self {
        Self {
            core: SplitMix64::new(mix64(seed ^ GAMMA)),
        }
    }

    /// The stream of one frame of one dataset: independent of every other
    /// frame, so frames can be rendered in any order or on any machine.
    pub fn for_frame(seed: u64, salt: &str, frame: u32) -> Self {
        let mut h = mix64(seed.wrapping_add(GAMMA));
        for b in salt.bytes() {
            h = mix64(h ^ u64::from(b));
        }
        Self::new(h ^ mix64(u64::from(frame).wrapping_mul(GAMMA)))
    }

    pub fn next_u64(&mut self) -> u64 {
        self.core.next_u64()
    }

    /// A child generator with its own stream.
    pub fn fork(&mut self) -> Self {
        Self::new(self.next_u64())
    }

    /// Uniform in `[0, 1)`.
    pub fn f64(&mut self) -> f64 {
        self.core.next_f64()
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.f64()
    }

    /// Log-uniform in `[lo, hi)` (both positive).
    pub fn log_range(&mut self, lo: f64, hi: f64) -> f64 {
        (self.range(lo.ln(), hi.ln())).exp()
    }

    /// Uniform integer in `0..n` (`n > 0`), from the high 32 bits (not
    /// [`SplitMix64::below`]: every dataset's scenes depend on this mapping).
    pub fn below(&mut self, n: usize) -> usize {
        debug_assert!(n > 0);
        ((self.next_u64() >> 32).wrapping_mul(n as u64) >> 32) as usize
    }

    /// `true` with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.f64() < p
    }

    /// A 32-bit seed for noise generators.
    pub fn seed_i32(&mut self) -> i32 {
        (self.next_u64() >> 33) as i32
    }

    /// A point of the unit sphere, uniformly distributed, by Marsaglia's
    /// method (1972), as the OmniThings supplement places its objects: draw
    /// `V1, V2` in `(-1, 1)` until `S = V1^2 + V2^2 < 1`, then
    /// `P = (2 V1 sqrt(1-S), 2 V2 sqrt(1-S), 1 - 2 S)`.
    pub fn marsaglia(&mut self) -> Vector3<f64> {
        loop {
            let v1 = self.range(-1.0, 1.0);
            let v2 = self.range(-1.0, 1.0);
            let s = v1 * v1 + v2 * v2;
            if s < 1.0 {
                let k = 2.0 * (1.0 - s).sqrt();
                return Vector3::new(v1 * k, v2 * k, 1.0 - 2.0 * s);
            }
        }
    }

    /// A uniformly distributed rotation (Shoemake's method).
    pub fn rotation(&mut self) -> UnitQuaternion<f64> {
        let (u1, u2, u3) = (self.f64(), self.f64(), self.f64());
        let tau = std::f64::consts::TAU;
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        let q = nalgebra::Quaternion::new(
            a * (tau * u2).sin(),
            a * (tau * u2).cos(),
            b * (tau * u3).sin(),
            b * (tau * u3).cos(),
        );
        UnitQuaternion::from_quaternion(q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn same_seed_same_stream_and_frames_differ() {
        let a: Vec<u64> = (0..4)
            .map(|_| Rng::for_frame(7, "things", 3).next_u64())
            .collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(
            Rng::for_frame(7, "things", 3).next_u64(),
            Rng::for_frame(7, "things", 4).next_u64()
        );
        assert_ne!(
            Rng::for_frame(7, "things", 3).next_u64(),
            Rng::for_frame(7, "house", 3).next_u64()
        );
    }

    #[test]
    fn marsaglia_points_are_unit_and_cover_the_sphere_evenly() {
        let mut rng = Rng::new(1);
        let n = 20_000;
        let mut mean = Vector3::zeros();
        let mut upper = 0;
        for _ in 0..n {
            let p = rng.marsaglia();
            assert!((p.norm() - 1.0).abs() < 1e-12);
            mean += p;
            if p.y < 0.0 {
                upper += 1;
            }
        }
        mean /= n as f64;
        assert!(mean.norm() < 0.02, "mean {mean:?}");
        assert!((f64::from(upper) / n as f64 - 0.5).abs() < 0.02);
    }

    #[test]
    fn below_and_range_stay_in_bounds() {
        let mut rng = Rng::new(2);
        for _ in 0..1000 {
            assert!(rng.below(5) < 5);
            let x = rng.range(-2.0, 3.0);
            assert!((-2.0..3.0).contains(&x));
        }
    }
}
