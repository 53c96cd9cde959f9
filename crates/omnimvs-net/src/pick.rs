//! A learnt pick after the network, at the output grid (stop 39): where a depth edge lies, the
//! cascade's answer is often a blend of the two surfaces (a soft argmax over both), and the
//! right surface is usually one of the extremes of the answers around the pixel (stop 32:
//! the nearest of a pixel's 5 x 5 minimum, maximum and own answer has a third less error).
//! The cameras' colours at those depths and the shape of the answer around say which one.
//!
//! [`PickRefiner`] reads, per output pixel:
//!
//! - the answer `v` (index units of `N`), the coarse stage's spread, and the 5 x 5 minimum
//!   `m` and maximum `M` of the answers around (wrapping in longitude), as `v / 192`,
//!   `spread / 30`, `(M - m) / 32`, `(m - v) / 32`, `(M - v) / 32`;
//! - at each of the depths `v`, `m`, `M`, every camera's gray value there (each image
//!   normalised by its own mean and standard deviation, bilinear, 0 where the camera does not
//!   see the point) and whether it sees it;
//!
//! and a small U-Net (3x3 convolutions wrapping in longitude, three stride-2 levels, bilinear
//! upsampling with skip concatenations, `width`, `2 width`, `3 width`, `4 width` channels)
//! scores seven candidates: `v` and the minimum and maximum over the 3 x 3, 5 x 5 and 9 x 9
//! pixels around. The answer is their softmax-weighted mean.
//!
//! It is trained outside the network, on the network's answers on frames it never trained on
//! (`models/training/pick-1/`, PyTorch; the weights are written as safetensors with the
//! module names of that script), and runs on the host with the convolution kernel of
//! [`crate::hostconv`].

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use omnimvs_data::edges::neighbour_min_max;
use omnimvs_sweep::GrayImage;
use rayon::prelude::*;

use crate::cascade::PixelSampler;
use crate::error::NetError;
use crate::hostconv::{HostConv, Padding};

/// Input channels: five of the answer's neighbourhood, then (gray, sees) per camera at each of
/// the three depths.
pub fn input_channels(cameras: usize) -> usize {
    5 + 3 * 2 * cameras
}

/// Candidates scored: the answer, then the minimum and maximum over these radii.
pub const CANDIDATE_RADII: [usize; 3] = [1, 2, 4];

/// Number of candidates.
pub const CANDIDATES: usize = 1 + 2 * CANDIDATE_RADII.len();

/// The bundled pick, trained on the bundled cascade's answers (`models/omnimvs-cascade-pick.safetensors`).
pub const BUNDLED_PICK: &[u8] = include_bytes!("../../../models/omnimvs-cascade-pick.safetensors");

/// Its label in errors and reports.
pub const BUNDLED_PICK_LABEL: &str = "models/omnimvs-cascade-pick.safetensors";

/// One 3x3 convolution of the U-Net with its ReLU.
#[derive(Clone, Debug)]
struct Layer {
    conv: HostConv,
    relu: bool,
}

impl Layer {
    fn run(
        &self,
        input: &[f32],
        [c, h, w]: [usize; 3],
    ) -> Result<(Vec<f32>, [usize; 3]), NetError> {
        let (out, [oh, ow]) = self.conv.forward(input, [1, c, h, w], None, self.relu)?;
        Ok((out, [self.conv.out_channels(), oh, ow]))
    }
}

/// The learnt pick (module docs).
#[derive(Clone, Debug)]
pub struct PickRefiner {
    cameras: usize,
    /// Encoder levels, two layers each (the first of levels 1-3 at stride 2).
    encoder: [[Layer; 2]; 4],
    /// Decoder layers from the coarsest: `d2`, `d1`, `d0`.
    decoder: [Layer; 3],
    head: Layer,
}

/// Tensors by name: shape and values.
pub type Tensors = HashMap<String, (Vec<usize>, Vec<f32>)>;

/// A safetensors file's tensors (`F32` only); `path` labels errors.
///
/// # Errors
/// [`NetError::Weights`] for a file that is not safetensors or holds another dtype.
pub fn read_safetensors(bytes: &[u8], path: &Path) -> Result<Tensors, NetError> {
    let bad = |message: String| NetError::Weights {
        path: path.to_path_buf(),
        message,
    };
    let header_len = bytes
        .get(..8)
        .map(|b| u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]) as usize)
        .ok_or_else(|| bad("shorter than a safetensors header (8 bytes)".into()))?;
    let header = bytes.get(8..8 + header_len).ok_or_else(|| {
        bad(format!(
            "header of {header_len} bytes past the end of the file"
        ))
    })?;
    let data = &bytes[8 + header_len..];
    let header: serde_json::Value =
        serde_json::from_slice(header).map_err(|e| bad(format!("header is not JSON: {e}")))?;
    let entries = header
        .as_object()
        .ok_or_else(|| bad("header is not a JSON object".into()))?;
    let mut out = HashMap::new();
    for (name, entry) in entries {
        if name == "__metadata__" {
            continue;
        }
        let field = |key: &str| {
            entry
                .get(key)
                .ok_or_else(|| bad(format!("tensor `{name}`: no `{key}`")))
        };
        if field("dtype")?.as_str() != Some("F32") {
            return Err(bad(format!("tensor `{name}`: dtype must be F32")));
        }
        let numbers = |key: &str| -> Result<Vec<usize>, NetError> {
            field(key)?
                .as_array()
                .and_then(|a| a.iter().map(|v| v.as_u64().map(|v| v as usize)).collect())
                .ok_or_else(|| {
                    bad(format!(
                        "tensor `{name}`: `{key}` must be a list of integers"
                    ))
                })
        };
        let shape = numbers("shape")?;
        let offsets = numbers("data_offsets")?;
        let (start, end) = match offsets[..] {
            [s, e]
                if s <= e && e <= data.len() && (e - s) == 4 * shape.iter().product::<usize>() =>
            {
                (s, e)
            }
            _ => {
                return Err(bad(format!(
                    "tensor `{name}`: data_offsets {offsets:?} do not hold {shape:?} f32 values within {} bytes",
                    data.len()
                )));
            }
        };
        let values = data[start..end]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect();
        out.insert(name.clone(), (shape, values));
    }
    Ok(out)
}

impl PickRefiner {
    /// The bundled pick (trained on the bundled cascade's answers, four cameras).
    ///
    /// # Errors
    /// [`NetError::Weights`] if the compiled-in file does not match (a build defect).
    pub fn bundled() -> Result<Self, NetError> {
        Self::from_bytes(BUNDLED_PICK, Path::new(BUNDLED_PICK_LABEL))
    }

    /// Reads a pick from a safetensors file.
    ///
    /// # Errors
    /// [`NetError::Io`] when the file cannot be read, [`NetError::Weights`] when it is not a
    /// pick's weights.
    pub fn load(path: &Path) -> Result<Self, NetError> {
        let bytes = std::fs::read(path).map_err(|source| NetError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_bytes(&bytes, path)
    }

    /// A pick from safetensors bytes; `path` labels errors. The sizes (cameras, width) are
    /// read from the tensors.
    ///
    /// # Errors
    /// [`NetError::Weights`] for a tensor missing, of another size, or a file that is not
    /// safetensors.
    pub fn from_bytes(bytes: &[u8], path: &Path) -> Result<Self, NetError> {
        let mut tensors = read_safetensors(bytes, path)?;
        let bad = |message: String| NetError::Weights {
            path: PathBuf::from(path),
            message,
        };
        let inputs = tensors
            .get("e0.0.0.weight")
            .map(|(shape, _)| shape.get(1).copied().unwrap_or(0))
            .ok_or_else(|| bad("no tensor `e0.0.0.weight`: not a pick's weights".into()))?;
        if inputs < 5 || (inputs - 5) % 6 != 0 {
            return Err(bad(format!(
                "`e0.0.0.weight` reads {inputs} channels: expected 5 + 6 per camera"
            )));
        }
        let cameras = (inputs - 5) / 6;
        let width = tensors["e0.0.0.weight"].0[0];
        let mut layer = |name: &str, c_in: usize, c_out: usize, stride: usize, relu: bool| {
            let (wshape, weight) = tensors
                .remove(&format!("{name}.weight"))
                .ok_or_else(|| bad(format!("no tensor `{name}.weight`")))?;
            let (bshape, bias) = tensors
                .remove(&format!("{name}.bias"))
                .ok_or_else(|| bad(format!("no tensor `{name}.bias`")))?;
            if wshape != [c_out, c_in, 3, 3] || bshape != [c_out] {
                return Err(bad(format!(
                    "`{name}`: weight {wshape:?} and bias {bshape:?}, expected [{c_out}, {c_in}, 3, 3] and [{c_out}]"
                )));
            }
            let conv = HostConv::new(
                [c_in, c_out],
                [3, 3],
                [stride, stride],
                [1, 1],
                Padding {
                    rows: 1,
                    cols: 1,
                    wrap_cols: true,
                },
                weight,
                bias,
            )?;
            Ok(Layer { conv, relu })
        };
        let w = width;
        let encoder = [
            [
                layer("e0.0.0", inputs, w, 1, true)?,
                layer("e0.1.0", w, w, 1, true)?,
            ],
            [
                layer("e1.0.0", w, 2 * w, 2, true)?,
                layer("e1.1.0", 2 * w, 2 * w, 1, true)?,
            ],
            [
                layer("e2.0.0", 2 * w, 3 * w, 2, true)?,
                layer("e2.1.0", 3 * w, 3 * w, 1, true)?,
            ],
            [
                layer("e3.0.0", 3 * w, 4 * w, 2, true)?,
                layer("e3.1.0", 4 * w, 4 * w, 1, true)?,
            ],
        ];
        let decoder = [
            layer("d2.0", 7 * w, 3 * w, 1, true)?,
            layer("d1.0", 5 * w, 2 * w, 1, true)?,
            layer("d0.0", 3 * w, w, 1, true)?,
        ];
        let head = layer("head", w, CANDIDATES, 1, false)?;
        if let Some(name) = tensors.keys().next() {
            return Err(bad(format!("tensor `{name}` is not a pick's")));
        }
        Ok(Self {
            cameras,
            encoder,
            decoder,
            head,
        })
    }

    /// Cameras it was trained for.
    pub fn cameras(&self) -> usize {
        self.cameras
    }

    /// The picked answer for `index` (index units of the sampler's hypotheses, row-major on
    /// its grid: the cascade's full-resolution [`PixelSampler`], which projects the output
    /// grid into the rig's cameras), with the coarse `spread` on the same grid, from the
    /// frame's `images` (rig order, the cameras' own sizes).
    ///
    /// # Errors
    /// [`NetError::Shape`] for maps of other sizes, or another number of cameras.
    pub fn refine(
        &self,
        index: &[f32],
        spread: &[f32],
        sampler: &PixelSampler,
        images: &[GrayImage],
    ) -> Result<Vec<f32>, NetError> {
        let size = [sampler.grid().height, sampler.grid().width];
        let inputs = self.inputs(index, spread, sampler, images)?;
        let logits = self.scores(&inputs, size)?;
        Ok(combine(&logits, index, size))
    }

    /// The input channels `[channels, h, w]` (module docs).
    ///
    /// # Errors
    /// [`NetError::Shape`] for maps or images of other sizes, or another number of cameras.
    pub fn inputs(
        &self,
        index: &[f32],
        spread: &[f32],
        sampler: &PixelSampler,
        images: &[GrayImage],
    ) -> Result<Vec<f32>, NetError> {
        let (h, w) = (sampler.grid().height, sampler.grid().width);
        let plane = h * w;
        if index.len() != plane || spread.len() != plane {
            return Err(NetError::Shape {
                what: "pick: index and spread maps".into(),
                expected: vec![h, w],
                actual: vec![index.len(), spread.len()],
            });
        }
        let cameras = sampler.num_cameras();
        if cameras != self.cameras || images.len() != self.cameras {
            return Err(NetError::Shape {
                what: "pick: cameras of the rig and images".into(),
                expected: vec![self.cameras],
                actual: vec![cameras, images.len()],
            });
        }
        for (camera, image) in images.iter().enumerate() {
            let (width, height) = sampler.image_size(camera);
            let size = [height as usize, width as usize];
            if size != [image.height, image.width] {
                return Err(NetError::Shape {
                    what: "pick: an image of its camera's size".into(),
                    expected: size.to_vec(),
                    actual: vec![image.height, image.width],
                });
            }
        }
        let (low, high) = neighbour_min_max(index, [h, w], true, 2);
        let mut out = vec![0f32; input_channels(self.cameras) * plane];
        for p in 0..plane {
            let (v, m, big_m) = (index[p], low[p], high[p]);
            out[p] = v / 192.0;
            out[plane + p] = spread[p] / 30.0;
            out[2 * plane + p] = (big_m - m) / 32.0;
            out[3 * plane + p] = (m - v) / 32.0;
            out[4 * plane + p] = (big_m - v) / 32.0;
        }
        let normalised: Vec<(f64, f64)> = images.iter().map(mean_and_std).collect();
        let hypotheses = sampler.hypotheses();
        for (d, map) in [index, &low, &high].into_iter().enumerate() {
            // The depth's inverse depth per pixel, once for every camera.
            let inv: Vec<f32> = map
                .iter()
                .map(|&n| hypotheses.inv_depth(f64::from(n)).max(1e-6) as f32)
                .collect();
            for (c, image) in images.iter().enumerate() {
                let channel = 5 + 2 * (d * self.cameras + c);
                let (gray, sees) = out[channel * plane..(channel + 2) * plane].split_at_mut(plane);
                let (mean, std) = normalised[c];
                gray.par_chunks_mut(w)
                    .zip(sees.par_chunks_mut(w))
                    .enumerate()
                    .for_each(|(row, (gray, sees))| {
                        for col in 0..w {
                            let p = row * w + col;
                            if let Some((x, y)) = sampler.project(c, p, inv[p])
                                && let Some(value) = bilinear(image, f64::from(x), f64::from(y))
                            {
                                gray[col] = ((value - mean) / (std + 1e-9)) as f32;
                                sees[col] = 1.0;
                            }
                        }
                    });
            }
        }
        Ok(out)
    }

    /// The candidates' logits `[CANDIDATES, h, w]` for `inputs` `[channels, h, w]`.
    ///
    /// # Errors
    /// [`NetError::Shape`] for inputs of another size.
    pub fn scores(&self, inputs: &[f32], [h, w]: [usize; 2]) -> Result<Vec<f32>, NetError> {
        let [first, second] = &self.encoder[0];
        let x = first.run(inputs, [input_channels(self.cameras), h, w])?;
        let mut x = second.run(&x.0, x.1)?;
        // The output of every level but the coarsest, for the decoder's skips.
        let mut skips: Vec<(Vec<f32>, [usize; 3])> = Vec::with_capacity(3);
        for level in &self.encoder[1..] {
            let out = level[0].run(&x.0, x.1)?;
            skips.push(std::mem::replace(&mut x, out));
            x = level[1].run(&x.0, x.1)?;
        }
        for (layer, skip) in self.decoder.iter().zip(skips.iter().rev()) {
            let mut joined = upsample_bilinear(&x.0, x.1, [skip.1[1], skip.1[2]]);
            joined.extend_from_slice(&skip.0);
            x = layer.run(&joined, [x.1[0] + skip.1[0], skip.1[1], skip.1[2]])?;
        }
        Ok(self.head.run(&x.0, x.1)?.0)
    }
}

/// The answer: each pixel's candidates ([`candidates`] of `index`) weighted by the softmax of
/// their `logits` `[CANDIDATES, h, w]`.
pub fn combine(logits: &[f32], index: &[f32], [h, w]: [usize; 2]) -> Vec<f32> {
    let plane = h * w;
    let candidates = candidates(index, [h, w]);
    (0..plane)
        .map(|p| {
            let mut best = f32::NEG_INFINITY;
            for k in 0..CANDIDATES {
                best = best.max(logits[k * plane + p]);
            }
            let (mut num, mut den) = (0f32, 0f32);
            for k in 0..CANDIDATES {
                let e = (logits[k * plane + p] - best).exp();
                num += e * candidates[k * plane + p];
                den += e;
            }
            num / den
        })
        .collect()
}

/// The candidates `[CANDIDATES, h, w]`: the answer, then the minimum and maximum over each of
/// [`CANDIDATE_RADII`] (wrapping in longitude).
pub fn candidates(index: &[f32], [h, w]: [usize; 2]) -> Vec<f32> {
    let mut out = Vec::with_capacity(CANDIDATES * h * w);
    out.extend_from_slice(index);
    for radius in CANDIDATE_RADII {
        let (low, high) = neighbour_min_max(index, [h, w], true, radius);
        out.extend(low);
        out.extend(high);
    }
    out
}

/// Mean and (population) standard deviation of an image's values.
fn mean_and_std(image: &GrayImage) -> (f64, f64) {
    let n = image.data.len().max(1) as f64;
    let mean = image.data.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
    let var = image
        .data
        .iter()
        .map(|&v| (f64::from(v) - mean).powi(2))
        .sum::<f64>()
        / n;
    (mean, var.sqrt())
}

/// Bilinear value at `(col, row)` (pixels), `None` unless the four neighbours are inside.
fn bilinear(image: &GrayImage, col: f64, row: f64) -> Option<f64> {
    let (c0, r0) = (col.floor(), row.floor());
    if c0 < 0.0 || r0 < 0.0 || c0 + 1.0 >= image.width as f64 || r0 + 1.0 >= image.height as f64 {
        return None;
    }
    let (fc, fr) = (col - c0, row - r0);
    let (c0, r0) = (c0 as usize, r0 as usize);
    let at = |r: usize, c: usize| f64::from(image.data[r * image.width + c]);
    Some(
        at(r0, c0) * (1.0 - fc) * (1.0 - fr)
            + at(r0, c0 + 1) * fc * (1.0 - fr)
            + at(r0 + 1, c0) * (1.0 - fc) * fr
            + at(r0 + 1, c0 + 1) * fc * fr,
    )
}

/// PyTorch's `interpolate(mode="bilinear", align_corners=False)` of `[c, h, w]` to `[c, oh,
/// ow]` (source positions clamped at the borders, no wrap).
pub fn upsample_bilinear(input: &[f32], [c, h, w]: [usize; 3], [oh, ow]: [usize; 2]) -> Vec<f32> {
    let taps = |out: usize, len: usize| -> Vec<(usize, usize, f32)> {
        let scale = len as f64 / out as f64;
        (0..out)
            .map(|o| {
                let src = ((o as f64 + 0.5) * scale - 0.5).max(0.0);
                let i0 = (src.floor() as usize).min(len - 1);
                let i1 = (i0 + 1).min(len - 1);
                (i0, i1, (src - i0 as f64) as f32)
            })
            .collect()
    };
    let (rows, cols) = (taps(oh, h), taps(ow, w));
    let mut out = vec![0f32; c * oh * ow];
    out.par_chunks_mut(oh * ow)
        .enumerate()
        .for_each(|(ch, plane)| {
            let src = &input[ch * h * w..(ch + 1) * h * w];
            for (y, &(r0, r1, fr)) in rows.iter().enumerate() {
                for (x, &(c0, c1, fc)) in cols.iter().enumerate() {
                    let top = src[r0 * w + c0] * (1.0 - fc) + src[r0 * w + c1] * fc;
                    let bottom = src[r1 * w + c0] * (1.0 - fc) + src[r1 * w + c1] * fc;
                    plane[y * ow + x] = top * (1.0 - fr) + bottom * fr;
                }
            }
        });
    out
}
