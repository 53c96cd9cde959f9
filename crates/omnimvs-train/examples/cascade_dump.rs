//! Writes what every stage of the cascade answered on a dataset's frames, for studies in numpy:
//! per frame, `FRAME_<name>.f32` raw little-endian `f32` files and one `FRAME.json` with their
//! shapes: the coarse, half- and full-resolution index maps (`coarse`, `half`, `full`), the full
//! stage's hypotheses and its distribution over them (`full_hyp`, `full_prob`, `[K, H, W]`), and
//! the coarse stage's spheres and distribution (`coarse_hyp`, `coarse_prob`, `[K, H, W]`, stop 41),
//! the ground truth on the output grid (`gt`, with `valid` as 0 / 1); `full_even` in the JSON is
//! how many of the full stage's hypotheses are evenly spaced (the first ones).
//!
//! `cargo run --release -p omnimvs-train --example cascade_dump -- WEIGHTS DATASET A B OUT [HALF,FULL]`
//!
//! The optional last argument sets `neighbour_extremes` (radii of the stretch of each refinement
//! stage's outermost hypotheses) instead of the weights' own.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use std::path::{Path, PathBuf};

use burn::tensor::Device;
use omnimvs_camera::fs::write_atomic;
use omnimvs_data::Dataset;
use omnimvs_net::cascade::CascadeGeometry;
use omnimvs_net::tensor::read_values;
use omnimvs_net::weights::load_cascade;
use omnimvs_train::SampleSource;
use omnimvs_train::augment::RotationSet;

fn write_f32(dir: &Path, name: &str, values: &[f32]) {
    let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
    write_atomic(&dir.join(name), &bytes).unwrap();
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: cascade_dump WEIGHTS DATASET FIRST LAST OUT [HALF,FULL]";
    let weights = PathBuf::from(args.get(1).expect(usage));
    let path = PathBuf::from(args.get(2).expect(usage));
    let first: u32 = args.get(3).expect(usage).parse().unwrap();
    let last: u32 = args.get(4).expect(usage).parse().unwrap();
    let out = PathBuf::from(args.get(5).expect(usage));
    std::fs::create_dir_all(&out).unwrap();
    let device = Device::flex();
    let mut net = load_cascade(&weights, &device).unwrap();
    if let Some(radii) = args.get(6) {
        let r: Vec<usize> = radii.split(',').map(|v| v.parse().unwrap()).collect();
        net.config.cascade.neighbour_extremes = [r[0], r[1]];
    }
    let config = net.config.clone();
    let ds = Dataset::open(&path).unwrap();
    let source = SampleSource::open(&path, &config, RotationSet::new(1, 0.0, 0)).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &config, &source.hypotheses, &device).unwrap();
    for frame in first..=last {
        let sample = source.load(0, frame, 0, None).unwrap();
        let images = sample.image_tensors([config.input_height, config.input_width], &device);
        let result = net.forward(&images, &geometry).unwrap();
        let [coarse, half, full] = &result.stages;
        let mut shapes = serde_json::Map::new();
        let mut put = |name: &str, values: Vec<f32>, shape: Vec<usize>| {
            write_f32(&out, &format!("{frame:05}_{name}.f32"), &values);
            shapes.insert(name.into(), serde_json::json!(shape));
        };
        for (name, stage) in [("coarse", coarse), ("half", half), ("full", full)] {
            let [_, h, w] = stage.index.dims();
            put(
                name,
                read_values(stage.index.clone(), name).unwrap(),
                vec![h, w],
            );
        }
        for (name, stage) in [("coarse", coarse), ("full", full)] {
            let [_, k, h, w] = stage.prob.dims();
            put(
                &format!("{name}_hyp"),
                read_values(stage.hypotheses.clone(), "hyp").unwrap(),
                vec![k, h, w],
            );
            put(
                &format!("{name}_prob"),
                read_values(stage.prob.clone(), "prob").unwrap(),
                vec![k, h, w],
            );
        }
        let gt = &sample.gt;
        put("gt", gt.index.clone(), vec![gt.height, gt.width]);
        put(
            "valid",
            gt.valid.iter().map(|&v| f32::from(u8::from(v))).collect(),
            vec![gt.height, gt.width],
        );
        // How many of the full stage's hypotheses are the evenly spaced ones (the rest are
        // the neighbours' extremes, `neighbour_hypotheses`).
        shapes.insert(
            "full_even".into(),
            serde_json::json!(config.cascade.stage_hypotheses[1]),
        );
        let json = serde_json::to_string_pretty(&serde_json::Value::Object(shapes)).unwrap();
        write_atomic(&out.join(format!("{frame:05}.json")), json.as_bytes()).unwrap();
        println!("frame {frame} written");
    }
}
