//! 2D convolutions on the host (`omnimvs_net::hostconv`): every kind of layer the
//! cascade has (kernels 1, 3 and 5; strides 1 and 2; dilations 1, 2 and 4; zero padding, or
//! columns wrapping around as on the panorama; a residual; a ReLU; several images; maps wide
//! enough to be cut into bands) answers as burn's convolution does, to float rounding; a
//! cascade, and the paper's network, with their convolutions on the host answer as with
//! burn's; bad sizes are refused.
#![allow(clippy::unwrap_used, clippy::expect_used)]

use burn::nn::PaddingConfig2d;
use burn::nn::conv::{Conv2d, Conv2dConfig};
use burn::tensor::activation::relu;
use burn::tensor::{Device, Distribution, Tensor};
use omnimvs_data::Dataset;
use omnimvs_net::cascade::CascadeGeometry;
use omnimvs_net::hostconv::{HostConv, Padding};
use omnimvs_net::tensor::read_values;
use omnimvs_net::{CascadeNet, NetConfig, NetError};

#[path = "../../omnimvs-camera/tests/support/samples.rs"]
mod samples;
use samples::sample as sample_dir;

#[path = "support/micro_cascade.rs"]
mod micro_cascade;
use micro_cascade::{max_difference, micro_config, micro_image_tensors as images};

/// One layer: channels in and out, kernel, stride, dilation, zero padding (rows, columns),
/// wrapped columns, input rows and columns, images, residual, ReLU.
struct Case {
    channels: [usize; 2],
    kernel: usize,
    stride: usize,
    dilation: usize,
    pad: [usize; 2],
    wrap: usize,
    size: [usize; 2],
    batch: usize,
    residual: bool,
    relu: bool,
}

/// Columns `wrap` wide from the other side on both sides of `x` (the tensor path's
/// circular padding).
fn wrap_columns(x: Tensor<4>, wrap: usize) -> Tensor<4> {
    if wrap == 0 {
        return x;
    }
    let w = x.dims()[3];
    let left = x.clone().narrow(3, w - wrap, wrap);
    let right = x.clone().narrow(3, 0, wrap);
    Tensor::cat(vec![left, x, right], 3)
}

fn run_case(case: &Case, device: &Device) -> f32 {
    let [c_in, c_out] = case.channels;
    let conv: Conv2d = Conv2dConfig::new([c_in, c_out], [case.kernel, case.kernel])
        .with_stride([case.stride, case.stride])
        .with_dilation([case.dilation, case.dilation])
        .with_padding(PaddingConfig2d::Explicit(
            case.pad[0],
            case.pad[1],
            case.pad[0],
            case.pad[1],
        ))
        .init(device);
    let [h, w] = case.size;
    let x = Tensor::<4>::random(
        [case.batch, c_in, h, w],
        Distribution::Normal(0.0, 1.0),
        device,
    );
    let expected = conv.forward(wrap_columns(x.clone(), case.wrap));
    let dims = expected.dims();
    let residual = case
        .residual
        .then(|| Tensor::<4>::random(dims, Distribution::Normal(0.0, 1.0), device));
    let expected = match &residual {
        Some(r) => expected + r.clone(),
        None => expected,
    };
    let expected = if case.relu { relu(expected) } else { expected };

    let host = HostConv::from_conv(&conv, case.wrap, case.wrap > 0).expect("a host kernel");
    let input = read_values(x, "input").unwrap();
    let residual = residual.map(|r| read_values(r, "residual").unwrap());
    let (got, [oh, ow]) = host
        .forward(
            &input,
            [case.batch, c_in, h, w],
            residual.as_deref(),
            case.relu,
        )
        .unwrap();
    assert_eq!([oh, ow], [dims[2], dims[3]], "output size");
    let expected = read_values(expected, "expected").unwrap();
    let scale = expected.iter().fold(1f32, |m, v| m.max(v.abs()));
    max_difference(&got, &expected) / scale
}

#[test]
fn every_kind_of_layer_answers_as_burns_convolution() {
    let device = Device::flex();
    device.seed(38);
    let case = |channels, kernel, stride, dilation, pad, wrap, size| Case {
        channels,
        kernel,
        stride,
        dilation,
        pad,
        wrap,
        size,
        batch: 1,
        residual: false,
        relu: false,
    };
    let cases = [
        // The feature stem: 5x5, stride 2, one channel, odd input rows.
        Case {
            batch: 2,
            relu: true,
            ..case([1, 4], 5, 2, 1, [2, 2], 0, [23, 26])
        },
        // A residual block at stride 1, and a dilated one (the stride-8 trunk).
        Case {
            residual: true,
            relu: true,
            ..case([6, 6], 3, 1, 1, [1, 1], 0, [9, 11])
        },
        Case {
            residual: true,
            relu: true,
            batch: 3,
            ..case([5, 5], 3, 1, 2, [2, 2], 0, [10, 12])
        },
        case([4, 4], 3, 1, 4, [4, 4], 0, [9, 13]),
        // A stride-2 step down, even and odd sizes.
        case([3, 7], 3, 2, 1, [1, 1], 0, [12, 15]),
        // 1x1 projections and a 1x1 with padding (not the direct path).
        case([8, 8], 1, 1, 1, [0, 0], 0, [7, 9]),
        case([3, 2], 1, 1, 1, [1, 1], 0, [5, 6]),
        // The panorama's 3x3 blocks: rows zero-padded, columns wrapping; strides 1 and 2.
        Case {
            relu: true,
            ..case([9, 5], 3, 1, 1, [1, 0], 1, [6, 16])
        },
        case([4, 6], 3, 2, 1, [1, 0], 1, [8, 20]),
        case([4, 6], 3, 2, 1, [1, 0], 1, [7, 19]),
        // Wide enough that the output is cut into bands of rows (K x columns over 2^18).
        Case {
            relu: true,
            ..case([64, 8], 3, 1, 1, [1, 0], 1, [9, 520])
        },
    ];
    for (i, c) in cases.iter().enumerate() {
        let error = run_case(c, &device);
        assert!(error < 1e-5, "case {i}: relative difference {error}");
    }
}

#[test]
fn a_cascade_with_its_convolutions_on_the_host_answers_as_with_burns() {
    let mut config = micro_config();
    config.cascade.zncc_cue = true;
    config.cascade.convex_upsampling = true;
    config.cascade.stage_gates = true;
    config.cascade.context_pairs = 2;
    config.validate().unwrap();
    let device = Device::flex();
    device.seed(7);
    let net = CascadeNet::new(&config, &device).unwrap().fold_batch_norm();
    let ds = Dataset::open(&sample_dir("sunny_single")).unwrap();
    let hyps = ds.hypotheses(config.num_invdepth).unwrap();
    let geometry = CascadeGeometry::new(&ds.rig, &config, &hyps, &device).unwrap();
    let imgs = images(&config, &device);
    let answer = |net: &CascadeNet| -> Vec<Vec<f32>> {
        let out = net.forward(&imgs, &geometry).unwrap();
        out.stages
            .into_iter()
            .map(|s| read_values(s.index, "index").unwrap())
            .collect()
    };
    let burn = answer(&net);
    let host_net = net.with_host_convs();
    assert!(
        host_net.features.conv0.host.is_some() && host_net.coarse.c0[0].host.is_some(),
        "the folded network's convolutions run on the host"
    );
    let host = answer(&host_net);
    for (stage, (a, b)) in burn.iter().zip(&host).enumerate() {
        let d = max_difference(a, b);
        assert!(d < 1e-3, "stage {stage}: index maps differ by {d}");
    }
    // A network whose batch norms are not folded keeps burn's path.
    let unfolded = CascadeNet::new(&config, &device).unwrap().with_host_convs();
    assert!(unfolded.features.conv0.host.is_none() && unfolded.coarse.c0[0].host.is_none());
}

#[test]
fn bad_sizes_are_refused() {
    let pad = Padding {
        rows: 1,
        cols: 1,
        wrap_cols: false,
    };
    let short = HostConv::new(
        [2, 3],
        [3, 3],
        [1, 1],
        [1, 1],
        pad,
        vec![0.0; 53],
        vec![0.0; 3],
    );
    assert!(matches!(short, Err(NetError::Shape { .. })));
    let no_bias = HostConv::new([2, 3], [3, 3], [1, 1], [1, 1], pad, vec![0.0; 54], vec![]);
    assert!(matches!(no_bias, Err(NetError::Shape { .. })));
    let zero_stride = HostConv::new(
        [2, 3],
        [3, 3],
        [0, 1],
        [1, 1],
        pad,
        vec![0.0; 54],
        vec![0.0; 3],
    );
    assert!(matches!(zero_stride, Err(NetError::Shape { .. })));

    let conv = HostConv::new(
        [2, 3],
        [3, 3],
        [1, 1],
        [1, 1],
        pad,
        vec![0.5; 54],
        vec![0.0; 3],
    )
    .unwrap();
    // Input of the wrong length, residual of the wrong length, a kernel that does not fit.
    assert!(conv.forward(&[0.0; 10], [1, 2, 2, 3], None, false).is_err());
    let ok = vec![1.0; 2 * 4 * 5];
    assert!(
        conv.forward(&ok, [1, 2, 4, 5], Some(&[0.0; 7]), false)
            .is_err()
    );
    let valid = Padding {
        rows: 0,
        cols: 0,
        wrap_cols: false,
    };
    let big = HostConv::new(
        [1, 1],
        [5, 5],
        [1, 1],
        [1, 1],
        valid,
        vec![1.0; 25],
        vec![0.0],
    )
    .unwrap();
    assert!(big.forward(&[0.0; 12], [1, 1, 3, 4], None, false).is_err());
    // A wrap wider than the map.
    let wide = Padding {
        rows: 0,
        cols: 3,
        wrap_cols: true,
    };
    let wrapping = HostConv::new(
        [1, 1],
        [1, 7],
        [1, 1],
        [1, 1],
        wide,
        vec![1.0; 7],
        vec![0.0],
    )
    .unwrap();
    assert!(
        wrapping
            .forward(&[0.0; 4], [1, 1, 2, 2], None, false)
            .is_err()
    );
    // The answer of a valid call: all-ones input, weights 0.5, zero padding: interior
    // outputs 0.5 x 9 x 2 channels.
    let (out, [oh, ow]) = conv.forward(&ok, [1, 2, 4, 5], None, false).unwrap();
    assert_eq!([oh, ow], [4, 5]);
    assert!((out[ow + 1] - 9.0).abs() < 1e-6 && (out[0] - 4.0).abs() < 1e-6);
    // Layers of other kinds keep burn's path.
    let grouped = Conv2dConfig::new([4, 4], [3, 3])
        .with_groups(2)
        .init(&Device::flex());
    assert!(HostConv::from_conv(&grouped, 0, false).is_none());
    let same = Conv2dConfig::new([1, 1], [3, 3])
        .with_padding(PaddingConfig2d::Same)
        .init(&Device::flex());
    assert!(HostConv::from_conv(&same, 0, false).is_none());
}

/// The paper's network (tiny preset, both layouts) with its 2D convolutions on the host
/// (features, transference) answers as with burn's: cost volumes and index maps.
#[test]
fn the_papers_network_with_its_2d_convolutions_on_the_host_answers_as_with_burns() {
    use omnimvs_net::{Layout, OmniMvsNet, SweepGrid, SweepTaps};
    let device = Device::flex();
    for layout in [Layout::Published, Layout::Iccv] {
        let config = NetConfig::tiny().with_layout(layout);
        let net = OmniMvsNet::new(&config, &device).unwrap().fold_batch_norm();
        let [fh, fw] = config.feature_size();
        let (n2, h, w) = (config.num_spheres(), config.out_height, config.out_width);
        // Every sphere pixel looks at a point of a circle in the feature map.
        let coords: Vec<f32> = (0..n2 * h * w)
            .flat_map(|i| {
                let a = std::f32::consts::TAU * (i % w) as f32 / w as f32;
                let r = 0.2 + 0.7 * ((i / w) % h) as f32 / h as f32 + 0.01 * (i / (h * w)) as f32;
                [r * a.cos(), r * a.sin()]
            })
            .collect();
        let grid = SweepGrid::new(n2, h, w, coords).unwrap();
        let taps = SweepTaps::new(&grid, [fh, fw], &device);
        let image = Tensor::<4>::random(
            [1, 1, config.input_height, config.input_width],
            Distribution::Normal(0.0, 1.0),
            &device,
        );
        let images = vec![image; config.num_cameras];
        let all_taps = vec![taps; config.num_cameras];
        let order: Vec<usize> = (0..config.num_cameras).collect();
        let burn = net.forward(&images, &all_taps, &order).unwrap();
        let host_net = net.with_host_convs();
        assert!(host_net.feature_layers.layers[0].host.is_some());
        assert!(host_net.spherical_sweep.transfer_conv.host.is_some());
        let host = host_net.forward(&images, &all_taps, &order).unwrap();
        let cost = |t: Tensor<4>| read_values(t, "cost").unwrap();
        let (a, b) = (cost(burn.cost), cost(host.cost));
        let scale = a.iter().fold(1f32, |m, v| m.max(v.abs()));
        let d = max_difference(&a, &b) / scale;
        assert!(
            d < 1e-4,
            "{layout:?}: cost volumes differ by {d} (relative)"
        );
        let index = |t: Tensor<3>| read_values(t, "index").unwrap();
        let d = max_difference(&index(burn.index), &index(host.index));
        assert!(d < 1e-2, "{layout:?}: index maps differ by {d}");
    }
}

/// 3D convolutions (the paper's cost regularisation: 3x3x3, strides 1 and 2, padding 1; and a
/// 1x1x1 and an uneven one) answer as burn's.
#[test]
fn three_d_convolutions_answer_as_burns() {
    use burn::nn::PaddingConfig3d;
    use burn::nn::conv::Conv3dConfig;
    let device = Device::flex();
    device.seed(83);
    // channels, kernel, stride, padding (d, h, w), input (d, h, w), batch, residual, relu
    let cases = [
        ([4, 6], [3, 3, 3], 1, [1, 1, 1], [5, 6, 7], 1, true, true),
        ([6, 8], [3, 3, 3], 2, [1, 1, 1], [6, 7, 9], 2, false, true),
        ([5, 3], [1, 1, 1], 1, [0, 0, 0], [3, 4, 5], 1, false, false),
        ([3, 4], [2, 3, 1], 1, [1, 0, 2], [4, 5, 6], 1, false, false),
        // Wide enough to be cut into bands.
        (
            [32, 4],
            [3, 3, 3],
            1,
            [1, 1, 1],
            [4, 6, 300],
            1,
            true,
            false,
        ),
    ];
    for (i, (channels, kernel, stride, pad, size, batch, residual, relu)) in
        cases.into_iter().enumerate()
    {
        let conv = Conv3dConfig::new(channels, kernel)
            .with_stride([stride; 3])
            .with_padding(PaddingConfig3d::Explicit(pad[0], pad[1], pad[2]))
            .init(&device);
        let [d, h, w] = size;
        let x = Tensor::<5>::random(
            [batch, channels[0], d, h, w],
            Distribution::Normal(0.0, 1.0),
            &device,
        );
        let expected = conv.forward(x.clone());
        let dims = expected.dims();
        let res =
            residual.then(|| Tensor::<5>::random(dims, Distribution::Normal(0.0, 1.0), &device));
        let expected = match &res {
            Some(r) => expected + r.clone(),
            None => expected,
        };
        let expected = if relu { relu_5(expected) } else { expected };
        let host = HostConv::from_conv3d(&conv).expect("a host kernel");
        let input = read_values(x, "input").unwrap();
        let res = res.map(|r| read_values(r, "residual").unwrap());
        let (got, out) = host
            .forward3d(&input, [batch, channels[0], d, h, w], res.as_deref(), relu)
            .unwrap();
        assert_eq!(out, [dims[2], dims[3], dims[4]], "case {i}: output size");
        let expected = read_values(expected, "expected").unwrap();
        let scale = expected.iter().fold(1f32, |m, v| m.max(v.abs()));
        let error = max_difference(&got, &expected) / scale;
        assert!(error < 1e-5, "case {i}: relative difference {error}");
    }
}

fn relu_5(x: Tensor<5>) -> Tensor<5> {
    burn::tensor::activation::relu(x)
}

/// `host_forward` takes its tensors by value (a clone kept for burn's path made burn
/// copy every input twice). A tensor the kernel does not fit comes back as it was, with its
/// residual, for burn's path; one that fits answers the same whether or not the caller still
/// shares its values.
#[test]
fn host_forward_hands_back_what_it_declines_and_answers_alike_shared_or_not() {
    use omnimvs_net::hostconv::host_forward;
    let device = Device::flex();
    device.seed(45);
    let conv: Conv2d = Conv2dConfig::new([3, 4], [3, 3])
        .with_padding(PaddingConfig2d::Explicit(1, 1, 1, 1))
        .init(&device);
    let host = HostConv::from_conv(&conv, 0, false).expect("a host kernel");

    // Two channels where the kernel takes three: declined, both tensors handed back unchanged.
    let wrong = Tensor::<4>::random([1, 2, 5, 6], Distribution::Normal(0.0, 1.0), &device);
    let residual = Tensor::<4>::random([1, 4, 5, 6], Distribution::Normal(0.0, 1.0), &device);
    let (wrong_values, residual_values) = (
        read_values(wrong.clone(), "input").unwrap(),
        read_values(residual.clone(), "residual").unwrap(),
    );
    let Err(declined) = host_forward(&host, wrong, Some(residual), true) else {
        panic!("a 2-channel input is not the 3-channel kernel's");
    };
    let (back, back_residual) = *declined;
    assert_eq!(back.dims(), [1, 2, 5, 6]);
    assert_eq!(read_values(back, "back").unwrap(), wrong_values);
    let back_residual = back_residual.expect("the residual handed back");
    assert_eq!(read_values(back_residual, "back").unwrap(), residual_values);

    // A fitting input: shared with a clone the caller keeps, then alone; both as burn's.
    let x = Tensor::<4>::random([1, 3, 5, 6], Distribution::Normal(0.0, 1.0), &device);
    let expected = read_values(conv.forward(x.clone()), "burn").unwrap();
    let kept = x.clone();
    let shared = host_forward(&host, x, None, false).expect("the kernel fits");
    let alone = host_forward(&host, kept, None, false).expect("the kernel fits");
    let [shared, alone] = [shared, alone].map(|t| read_values(t, "out").unwrap());
    assert_eq!(shared, alone);
    let scale = expected.iter().fold(1f32, |m, v| m.max(v.abs()));
    assert!(max_difference(&shared, &expected) / scale < 1e-5);
}
