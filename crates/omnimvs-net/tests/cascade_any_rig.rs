//! The cascade network on rigs of any number of cameras: what it computes across cameras (the
//! mean over camera pairs of the features' products, the share of cameras that see a sample)
//! depends neither on their number nor on their order. Runs of 2, 3, 4 and 6 cameras, the same
//! answer for the cameras in another order, and counts outside 2 to 8 refused. Uses the
//! published rig of `sunny_single` from `../shared/data/omnimvs-samples`.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use burn::tensor::{Device, Tensor};
use omnimvs_camera::nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use omnimvs_camera::{Camera, Pose, Rig};
use omnimvs_data::Dataset;
use omnimvs_net::cascade::CascadeGeometry;
use omnimvs_net::tensor::read_values;
use omnimvs_net::{CascadeNet, NetConfig, NetError};
use omnimvs_sweep::InvDepthHypotheses;

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::{max_difference, micro_config, micro_image_tensors};

fn sunny() -> (Rig, InvDepthHypotheses) {
    let ds = Dataset::open(&samples::sample("sunny_single")).unwrap();
    let hyps = ds.hypotheses(32).unwrap();
    (ds.rig, hyps)
}

/// `count` copies of the published rig's first camera on a ring of 0.6 m, facing outwards.
fn ring(count: usize) -> Rig {
    let (rig, _) = sunny();
    let model = rig.cameras[0].model.clone();
    let cameras = (0..count)
        .map(|i| {
            let heading = 2.0 * std::f64::consts::PI * i as f64 / count as f64;
            let rotation = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), heading);
            let centre = rotation * Vector3::new(0.0, 0.0, 0.6);
            let pose = Isometry3::from_parts(Translation3::from(centre), rotation);
            Camera::new(
                i as u32 + 1,
                format!("cam{}", i + 1),
                model.clone(),
                Pose::from_isometry(&pose),
                None,
            )
        })
        .collect();
    Rig::new(cameras)
}

/// The micro images of `count` cameras as `[1, 1, H, W]` tensors.
fn images(config: &NetConfig, count: usize, device: &Device) -> Vec<Tensor<4>> {
    let config = NetConfig {
        num_cameras: count,
        ..config.clone()
    };
    micro_image_tensors(&config, device)
}

/// The final stage's answer of the micro cascade (random weights) on `rig` and `images`.
fn answer(net: &CascadeNet, config: &NetConfig, rig: &Rig, images: &[Tensor<4>]) -> Vec<f32> {
    let (_, hyps) = sunny();
    let device = Device::flex();
    let geometry = CascadeGeometry::new(rig, config, &hyps, &device).unwrap();
    let out = net.forward(images, &geometry).unwrap();
    let last = out.stages.last().unwrap();
    read_values(last.index.clone(), "index").unwrap()
}

#[test]
fn the_cascade_runs_on_two_to_six_cameras() {
    let config = micro_config();
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let [h, w] = config.cascade_sizes()[2];
    let mut answers = Vec::new();
    for count in [2, 3, 4, 6] {
        let index = answer(
            &net,
            &config,
            &ring(count),
            &images(&config, count, &device),
        );
        assert_eq!(index.len(), h * w, "{count} cameras");
        assert!(index.iter().all(|&n| (0.0..=31.0 + 1e-3).contains(&n)));
        answers.push(index);
    }
    // Different rigs give different answers (the cameras are used, not ignored).
    assert!(max_difference(&answers[0], &answers[3]) > 1e-3);
}

#[test]
fn the_answer_does_not_depend_on_the_order_of_the_cameras() {
    let config = micro_config();
    let device = Device::flex();
    let net = CascadeNet::new(&config, &device).unwrap();
    let (rig, _) = sunny();
    let imgs = images(&config, 4, &device);
    let want = answer(&net, &config, &rig, &imgs);
    for order in [[2, 0, 3, 1], [3, 2, 1, 0]] {
        let permuted = Rig::new(order.iter().map(|&i| rig.cameras[i].clone()).collect());
        let permuted_images: Vec<_> = order.iter().map(|&i| imgs[i].clone()).collect();
        let got = answer(&net, &config, &permuted, &permuted_images);
        let diff = max_difference(&got, &want);
        println!("order {order:?}: largest difference {diff:e} (index units)");
        assert!(diff < 1e-3, "order {order:?}: {diff}");
    }
}

#[test]
fn camera_counts_outside_two_to_eight_are_refused() {
    let config = micro_config();
    let (_, hyps) = sunny();
    let device = Device::flex();
    for count in [1, 9] {
        let Err(err) = CascadeGeometry::new(&ring(count), &config, &hyps, &device) else {
            panic!("{count} cameras accepted");
        };
        assert!(matches!(err, NetError::Cameras { .. }), "{err}");
        let text = err.to_string();
        assert!(text.contains(&format!("{count} cameras")), "{text}");
        assert!(text.contains("2 to 8"), "{text}");
    }
    // The paper's network concatenates its cameras: exactly its count.
    let paper = NetConfig::default();
    assert!(paper.check_cameras(4, "rig").is_ok());
    let err = paper.check_cameras(3, "rig").unwrap_err().to_string();
    assert!(err.contains("exactly 4"), "{err}");
}
