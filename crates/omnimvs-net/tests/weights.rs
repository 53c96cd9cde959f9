//! Our own weight files: safetensors + configuration JSON, round trip and errors.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::disallowed_methods)] // test helpers

use burn::tensor::{Device, Distribution, Tensor};
use omnimvs_net::synthetic::synthetic_grids;
use omnimvs_net::weights::{config_path, load, load_any, save};
use omnimvs_net::{Layout, NetConfig, OmniMvsNet};

fn small_config(layout: Layout) -> NetConfig {
    NetConfig {
        channels: 2,
        num_invdepth: 32,
        out_height: 32,
        out_width: 32,
        num_cameras: 2,
        input_height: 24,
        input_width: 30,
        ..NetConfig::tiny()
    }
    .with_layout(layout)
}

fn outputs(net: &OmniMvsNet, device: &Device) -> Vec<f32> {
    let c = &net.config;
    device.seed(7);
    let images: Vec<Tensor<4>> = (0..c.num_cameras)
        .map(|_| {
            Tensor::random(
                [1, 1, c.input_height, c.input_width],
                Distribution::Normal(0.0, 1.0),
                device,
            )
        })
        .collect();
    let out = net
        .infer(&images, &synthetic_grids(c), &net.identity_order())
        .unwrap();
    out.cost.into_data().try_into_vec_as::<f32>().unwrap()
}

#[test]
fn saved_weights_load_back_identically() {
    let device = Device::flex();
    let dir = tempfile::tempdir().unwrap();
    for layout in [Layout::Iccv, Layout::Published] {
        let config = small_config(layout);
        let net = OmniMvsNet::new(&config, &device).unwrap();
        let path = dir.path().join(format!("{layout:?}/model.safetensors"));
        save(&net, &path).unwrap();
        assert!(config_path(&path).is_file());
        let back = load(&path, &device).unwrap();
        assert_eq!(back.config, config);
        assert_eq!(outputs(&net, &device), outputs(&back, &device));
        let any = load_any(&path, &NetConfig::paper(), &device).unwrap();
        assert_eq!(any.config, config);
    }
}

#[test]
fn mismatched_or_missing_files_are_reported() {
    let device = Device::flex();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("model.safetensors");
    let err = load(&path, &device).unwrap_err().to_string();
    assert!(err.contains("model.json"), "{err}");

    let net = OmniMvsNet::new(&small_config(Layout::Published), &device).unwrap();
    save(&net, &path).unwrap();
    // A configuration that does not match the weights: the ICCV layout lacks layer 17.
    let iccv = serde_json::to_string(&small_config(Layout::Iccv)).unwrap();
    std::fs::write(config_path(&path), iccv).unwrap();
    let err = load(&path, &device).unwrap_err().to_string();
    assert!(err.contains("layers.17"), "{err}");
    // More channels than stored.
    let wider = serde_json::to_string(&NetConfig {
        channels: 4,
        ..small_config(Layout::Published)
    })
    .unwrap();
    std::fs::write(config_path(&path), wider).unwrap();
    assert!(load(&path, &device).is_err());
}
