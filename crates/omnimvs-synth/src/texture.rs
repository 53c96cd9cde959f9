//! Procedural solid textures: a pattern evaluated at a 3D point of the
//! object's texture space, mapped to a reflectance between `lo` and `hi`
//! (random brightness and contrast), plus an optional fine noise layer.

use fastnoise_lite::{CellularReturnType, FastNoiseLite, FractalType, NoiseType};
use glam::Vec3A;
use serde::{Deserialize, Serialize};

use crate::rng::Rng;

/// The kind of a texture and its parameters. Frequencies are in cycles per
/// texture-space unit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum Pattern {
    /// One reflectance (`lo`); only the detail layer varies it.
    Flat,
    /// Fractal simplex noise.
    Noise { freq: f32, octaves: u8, seed: i32 },
    /// Parallel stripes along `axis`; `duty` is the fraction of each period
    /// at `hi`, `soft` blends the edges (0 = sharp).
    Stripes {
        freq: f32,
        axis: [f32; 3],
        duty: f32,
        soft: f32,
    },
    /// 3D checkerboard.
    Checker { freq: f32 },
    /// Voronoi cells, each a random reflectance (`value`) or shaded by the
    /// distance to its centre.
    Cells {
        freq: f32,
        seed: i32,
        distance: bool,
    },
    /// Smooth periodic ramps along `axis`.
    Gradient { freq: f32, axis: [f32; 3] },
    /// Stripes distorted by noise (marble, wood).
    Marble {
        freq: f32,
        axis: [f32; 3],
        turbulence: f32,
        seed: i32,
    },
}

/// A texture as stored in `scene.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TextureSpec {
    pub pattern: Pattern,
    /// Reflectance where the pattern is 0, in `[0, 1]`.
    pub lo: f32,
    /// Reflectance where the pattern is 1, in `[0, 1]`.
    pub hi: f32,
    /// Amplitude (reflectance units) of a fine noise layer added on top.
    pub detail: f32,
    /// Frequency of the detail layer.
    pub detail_freq: f32,
    pub detail_seed: i32,
}

impl TextureSpec {
    /// A flat texture without detail.
    pub fn flat(reflectance: f32) -> Self {
        Self {
            pattern: Pattern::Flat,
            lo: reflectance,
            hi: reflectance,
            detail: 0.0,
            detail_freq: 1.0,
            detail_seed: 0,
        }
    }

    /// A random texture. `texture_richness` in `[0, 1]` scales contrast and
    /// detail: 1 for OmniThings-like objects, low for walls and ceilings.
    pub fn random(rng: &mut Rng, texture_richness: f64) -> Self {
        let axis = random_axis(rng);
        let pattern = match rng.below(7) {
            0 => Pattern::Flat,
            1 | 2 => Pattern::Noise {
                freq: rng.log_range(0.5, 8.0) as f32,
                octaves: 1 + rng.below(5) as u8,
                seed: rng.seed_i32(),
            },
            3 => Pattern::Stripes {
                freq: rng.log_range(0.7, 8.0) as f32,
                axis,
                duty: rng.range(0.2, 0.8) as f32,
                soft: rng.range(0.0, 0.3) as f32,
            },
            4 => Pattern::Checker {
                freq: rng.log_range(0.7, 6.0) as f32,
            },
            5 => Pattern::Cells {
                freq: rng.log_range(1.0, 8.0) as f32,
                seed: rng.seed_i32(),
                distance: rng.chance(0.4),
            },
            _ => {
                if rng.chance(0.5) {
                    Pattern::Gradient {
                        freq: rng.log_range(0.3, 3.0) as f32,
                        axis,
                    }
                } else {
                    Pattern::Marble {
                        freq: rng.log_range(0.5, 5.0) as f32,
                        axis,
                        turbulence: rng.range(0.5, 4.0) as f32,
                        seed: rng.seed_i32(),
                    }
                }
            }
        };
        let contrast = (rng.range(0.2, 1.0) * texture_richness) as f32;
        let mid = rng.range(0.25, 0.8) as f32;
        let lo = (mid - contrast / 2.0).clamp(0.02, 1.0);
        let hi = (mid + contrast / 2.0).clamp(0.0, 0.98);
        let (lo, hi) = if matches!(pattern, Pattern::Flat) {
            (mid, mid)
        } else {
            (lo, hi)
        };
        Self {
            pattern,
            lo,
            hi,
            detail: (rng.range(0.0, 0.25) * texture_richness) as f32,
            detail_freq: rng.log_range(4.0, 24.0) as f32,
            detail_seed: rng.seed_i32(),
        }
    }

    /// `pattern` between `mid - contrast / 2` and `mid + contrast / 2`, each end kept inside
    /// `[floor, ceiling]`, without detail.
    pub(crate) fn banded(
        pattern: Pattern,
        mid: f32,
        contrast: f32,
        [floor, ceiling]: [f32; 2],
    ) -> Self {
        Self {
            pattern,
            lo: (mid - contrast / 2.0).max(floor),
            hi: (mid + contrast / 2.0).min(ceiling),
            detail: 0.0,
            detail_freq: 1.0,
            detail_seed: 0,
        }
    }

    /// The texture with fine detail drawn from `rng`, in this order: its amplitude uniform in
    /// `amplitude`, its frequency log-uniform in `freq`, its seed.
    pub(crate) fn with_random_detail(
        mut self,
        rng: &mut Rng,
        amplitude: [f64; 2],
        freq: [f64; 2],
    ) -> Self {
        self.detail = rng.range(amplitude[0], amplitude[1]) as f32;
        self.detail_freq = rng.log_range(freq[0], freq[1]) as f32;
        self.detail_seed = rng.seed_i32();
        self
    }

    /// A random texture in the proportions of photographs (the `hard`
    /// difficulty), where stereo matching is hard: about 30% flat or nearly
    /// so (contrast under 0.06, faint detail), 20% repetitive (sharp periodic
    /// stripes or checkers without detail, so that shifted copies match),
    /// the rest as [`Self::random`]; independently, 30% are dark (reflectance
    /// scaled to 5-30%).
    pub fn random_hard(rng: &mut Rng, texture_richness: f64) -> Self {
        let roll = rng.f64();
        let dark = rng.chance(0.3);
        let dimming = rng.range(0.05, 0.3) as f32;
        let mut t = if roll < 0.3 {
            let mid = rng.range(0.2, 0.85) as f32;
            let contrast = rng.range(0.0, 0.06) as f32;
            let pattern = if rng.chance(0.5) {
                Pattern::Flat
            } else {
                Pattern::Noise {
                    freq: rng.log_range(0.2, 2.0) as f32,
                    octaves: 2,
                    seed: rng.seed_i32(),
                }
            };
            let flat = Self::banded(pattern, mid, contrast, [0.0, 1.0]);
            flat.with_random_detail(rng, [0.0, 0.015], [4.0, 24.0])
        } else if roll < 0.5 {
            let freq = rng.log_range(2.0, 10.0) as f32;
            let pattern = if rng.chance(0.5) {
                Pattern::Stripes {
                    freq,
                    axis: random_axis(rng),
                    duty: rng.range(0.3, 0.7) as f32,
                    soft: rng.range(0.0, 0.1) as f32,
                }
            } else {
                Pattern::Checker { freq }
            };
            let mid = rng.range(0.3, 0.7) as f32;
            let contrast = (rng.range(0.3, 0.8) * texture_richness) as f32;
            Self::banded(pattern, mid, contrast, [0.02, 0.98])
        } else {
            Self::random(rng, texture_richness)
        };
        if dark {
            t.lo *= dimming;
            t.hi *= dimming;
            t.detail *= dimming;
        }
        t
    }
}

fn random_axis(rng: &mut Rng) -> [f32; 3] {
    let v = rng.marsaglia();
    [v.x as f32, v.y as f32, v.z as f32]
}

/// A [`TextureSpec`] ready to evaluate (noise generators built once).
/// Not `Clone`/`Debug`: the noise generator type implements neither.
pub struct Texture {
    kind: Kind,
    lo: f32,
    hi: f32,
    detail: f32,
    detail_freq: f32,
    detail_noise: FastNoiseLite,
}

enum Kind {
    Flat,
    Noise {
        freq: f32,
        noise: FastNoiseLite,
    },
    Stripes {
        freq: f32,
        axis: Vec3A,
        duty: f32,
        soft: f32,
    },
    Checker {
        freq: f32,
    },
    Cells {
        freq: f32,
        noise: FastNoiseLite,
    },
    Gradient {
        freq: f32,
        axis: Vec3A,
    },
    Marble {
        freq: f32,
        axis: Vec3A,
        turbulence: f32,
        noise: FastNoiseLite,
    },
}

fn fbm(seed: i32, octaves: u8) -> FastNoiseLite {
    let mut n = FastNoiseLite::with_seed(seed);
    n.set_noise_type(Some(NoiseType::OpenSimplex2));
    n.set_frequency(Some(1.0));
    if octaves > 1 {
        n.set_fractal_type(Some(FractalType::FBm));
        n.set_fractal_octaves(Some(i32::from(octaves)));
    }
    n
}

fn unit_axis(a: [f32; 3]) -> Vec3A {
    Vec3A::from_array(a).try_normalize().unwrap_or(Vec3A::X)
}

impl Texture {
    pub fn new(spec: &TextureSpec) -> Self {
        let kind = match &spec.pattern {
            Pattern::Flat => Kind::Flat,
            Pattern::Noise {
                freq,
                octaves,
                seed,
            } => Kind::Noise {
                freq: *freq,
                noise: fbm(*seed, (*octaves).clamp(1, 8)),
            },
            Pattern::Stripes {
                freq,
                axis,
                duty,
                soft,
            } => Kind::Stripes {
                freq: *freq,
                axis: unit_axis(*axis),
                duty: duty.clamp(0.0, 1.0),
                soft: soft.clamp(0.0, 0.5),
            },
            Pattern::Checker { freq } => Kind::Checker { freq: *freq },
            Pattern::Cells {
                freq,
                seed,
                distance,
            } => {
                let mut n = FastNoiseLite::with_seed(*seed);
                n.set_noise_type(Some(NoiseType::Cellular));
                n.set_frequency(Some(1.0));
                n.set_cellular_return_type(Some(if *distance {
                    CellularReturnType::Distance
                } else {
                    CellularReturnType::CellValue
                }));
                Kind::Cells {
                    freq: *freq,
                    noise: n,
                }
            }
            Pattern::Gradient { freq, axis } => Kind::Gradient {
                freq: *freq,
                axis: unit_axis(*axis),
            },
            Pattern::Marble {
                freq,
                axis,
                turbulence,
                seed,
            } => Kind::Marble {
                freq: *freq,
                axis: unit_axis(*axis),
                turbulence: *turbulence,
                noise: fbm(*seed, 3),
            },
        };
        Self {
            kind,
            lo: spec.lo,
            hi: spec.hi,
            detail: spec.detail,
            detail_freq: spec.detail_freq,
            detail_noise: fbm(spec.detail_seed, 2),
        }
    }

    /// The reflectance at a point of texture space, in `[0, 1]`.
    #[inline]
    pub fn reflectance(&self, p: Vec3A) -> f32 {
        let v = match &self.kind {
            Kind::Flat => 0.0,
            Kind::Noise { freq, noise } => {
                let q = p * *freq;
                (noise.get_noise_3d(q.x, q.y, q.z) * 0.5 + 0.5).clamp(0.0, 1.0)
            }
            Kind::Stripes {
                freq,
                axis,
                duty,
                soft,
            } => {
                let f = (p.dot(*axis) * freq).rem_euclid(1.0);
                stripe(f, *duty, *soft)
            }
            Kind::Checker { freq } => {
                let q = (p * *freq).floor();
                ((q.x + q.y + q.z) as i64).rem_euclid(2) as f32
            }
            Kind::Cells { freq, noise } => {
                let q = p * *freq;
                (noise.get_noise_3d(q.x, q.y, q.z) * 0.5 + 0.5).clamp(0.0, 1.0)
            }
            Kind::Gradient { freq, axis } => {
                0.5 + 0.5 * (p.dot(*axis) * freq * std::f32::consts::TAU).sin()
            }
            Kind::Marble {
                freq,
                axis,
                turbulence,
                noise,
            } => {
                let q = p * *freq;
                let n = noise.get_noise_3d(q.x, q.y, q.z);
                0.5 + 0.5 * ((p.dot(*axis) * freq + turbulence * n) * std::f32::consts::TAU).sin()
            }
        };
        let mut r = self.lo + (self.hi - self.lo) * v;
        if self.detail > 0.0 {
            let q = p * self.detail_freq;
            r += self.detail * self.detail_noise.get_noise_3d(q.x, q.y, q.z);
        }
        r.clamp(0.0, 1.0)
    }
}

/// A square wave of duty `duty` (`f` in `[0, 1)`), its edges blended over
/// `soft` of a period.
fn stripe(f: f32, duty: f32, soft: f32) -> f32 {
    // Signed distance to the nearest edge, positive inside the "on" part.
    let s = if f < duty {
        f.min(duty - f)
    } else {
        -(f - duty).min(1.0 - f)
    };
    if soft <= 0.0 {
        if s >= 0.0 { 1.0 } else { 0.0 }
    } else {
        (0.5 + s / soft).clamp(0.0, 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_random_texture_stays_in_unit_range() {
        let mut rng = Rng::new(3);
        for _ in 0..200 {
            let spec = TextureSpec::random(&mut rng, 1.0);
            let tex = Texture::new(&spec);
            for i in 0..50 {
                let p = Vec3A::new(i as f32 * 0.37, (i * i) as f32 * 0.011, -(i as f32) * 0.23);
                let r = tex.reflectance(p);
                assert!((0.0..=1.0).contains(&r), "{spec:?} gave {r}");
            }
        }
    }

    #[test]
    fn hard_textures_are_often_flat_repetitive_or_dark() {
        let mut rng = Rng::new(4);
        let n = 2000;
        let (mut flat, mut repetitive, mut dark) = (0, 0, 0);
        for _ in 0..n {
            let t = TextureSpec::random_hard(&mut rng, 1.0);
            assert!(0.0 <= t.lo && t.lo <= t.hi && t.hi <= 1.0, "{t:?}");
            if t.hi - t.lo < 0.061 && t.detail < 0.016 {
                flat += 1;
            }
            if t.detail == 0.0
                && matches!(t.pattern, Pattern::Stripes { .. } | Pattern::Checker { .. })
            {
                repetitive += 1;
            }
            if t.hi < 0.3 {
                dark += 1;
            }
        }
        let share = |k: i32| f64::from(k) / f64::from(n);
        assert!((0.28..0.42).contains(&share(flat)), "flat {}", share(flat));
        assert!(
            (0.18..0.25).contains(&share(repetitive)),
            "repetitive {}",
            share(repetitive)
        );
        assert!((0.25..0.45).contains(&share(dark)), "dark {}", share(dark));
    }

    #[test]
    fn checker_alternates_and_flat_is_constant() {
        let spec = TextureSpec {
            pattern: Pattern::Checker { freq: 1.0 },
            lo: 0.1,
            hi: 0.9,
            detail: 0.0,
            detail_freq: 1.0,
            detail_seed: 0,
        };
        let t = Texture::new(&spec);
        assert!((t.reflectance(Vec3A::new(0.5, 0.5, 0.5)) - 0.1).abs() < 1e-6);
        assert!((t.reflectance(Vec3A::new(1.5, 0.5, 0.5)) - 0.9).abs() < 1e-6);
        let flat = Texture::new(&TextureSpec::flat(0.4));
        assert_eq!(flat.reflectance(Vec3A::new(3.0, -1.0, 2.0)), 0.4);
    }

    #[test]
    fn sharp_stripes_follow_duty() {
        assert_eq!(stripe(0.1, 0.5, 0.0), 1.0);
        assert_eq!(stripe(0.7, 0.5, 0.0), 0.0);
        assert!(stripe(0.25, 0.5, 0.1) > 0.99);
        assert!(stripe(0.75, 0.5, 0.1) < 0.01);
    }
}
