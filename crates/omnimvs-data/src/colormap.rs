//! Colour maps for inverse depth, error and uncertainty pictures.

use colorous::Gradient;

/// The colour maps used for pictures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Colormap {
    /// Inverse depth (near = warm).
    Turbo,
    /// Uncertainty (entropy).
    Inferno,
    /// Errors.
    Viridis,
    /// Gray ramp.
    Gray,
}

impl Colormap {
    fn gradient(self) -> Option<Gradient> {
        match self {
            Self::Turbo => Some(colorous::TURBO),
            Self::Inferno => Some(colorous::INFERNO),
            Self::Viridis => Some(colorous::VIRIDIS),
            Self::Gray => None,
        }
    }

    /// The colour of `t` in `[0, 1]` (clamped).
    pub fn color(self, t: f64) -> [u8; 3] {
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            0.0
        };
        match self.gradient() {
            Some(g) => {
                let c = g.eval_continuous(t);
                [c.r, c.g, c.b]
            }
            None => {
                let v = (t * 255.0).round() as u8;
                [v, v, v]
            }
        }
    }
}

/// RGB8 pixels of `values` mapped linearly from `[min, max]` to the colour
/// map; non-finite values and those where `valid` is false are black.
pub fn colorize(
    values: &[f32],
    min: f64,
    max: f64,
    map: Colormap,
    valid: Option<&[bool]>,
) -> Vec<u8> {
    let span = if max > min { max - min } else { 1.0 };
    let mut out = Vec::with_capacity(values.len() * 3);
    for (i, &v) in values.iter().enumerate() {
        let ok = v.is_finite() && valid.is_none_or(|m| m[i]);
        let c = if ok {
            map.color((f64::from(v) - min) / span)
        } else {
            [0, 0, 0]
        };
        out.extend_from_slice(&c);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ends_of_the_ramp() {
        assert_eq!(Colormap::Gray.color(0.0), [0, 0, 0]);
        assert_eq!(Colormap::Gray.color(2.0), [255, 255, 255]);
        let px = colorize(&[0.0, f32::NAN], 0.0, 1.0, Colormap::Turbo, None);
        assert_eq!(&px[3..], &[0, 0, 0]);
    }
}
