use super::*;
use crate::denoise::network::Network;
use crate::denoise::testing::{Rng, archive, small_unet};
use crate::denoise::tza::Archive;

fn random(w: usize, h: usize, c: usize, seed: u64) -> Tensor {
    let mut rng = Rng(seed);
    Tensor { width: w, height: h, channels: c, data: (0..w * h * c).map(|_| rng.signed()).collect() }
}

fn random_conv(ci: usize, co: usize, relu: bool) -> Conv {
    let mut rng = Rng(99);
    let id = super::super::network::TensorId(0);
    Conv {
        name: "c".into(),
        src: id,
        dst: id,
        in_channels: ci,
        out_channels: co,
        relu,
        weight: (0..co * ci * 9).map(|_| rng.signed()).collect(),
        bias: (0..co).map(|_| rng.signed()).collect(),
    }
}

/// The convolution as its definition writes it, planar loops in another
/// order: out[y][x][o] = b[o] + Σ w[o][i][ky][kx] · in[y+ky-1][x+kx-1][i],
/// outside the image 0.
fn conv_by_definition(c: &Conv, t: &Tensor) -> Vec<f32> {
    let (w, h) = (t.width as i64, t.height as i64);
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            for o in 0..c.out_channels {
                let mut sum = c.bias[o] as f64;
                for i in 0..c.in_channels {
                    for ky in 0..3 {
                        for kx in 0..3 {
                            let (sx, sy) = (x + kx - 1, y + ky - 1);
                            if (0..w).contains(&sx) && (0..h).contains(&sy) {
                                let v = t.pixel(sx as usize, sy as usize)[i] as f64;
                                sum += c.weight[((o * c.in_channels + i) * 3 + ky as usize) * 3 + kx as usize] as f64 * v;
                            }
                        }
                    }
                }
                out.push(if c.relu { sum.max(0.0) } else { sum } as f32);
            }
        }
    }
    out
}

#[test]
fn conv_is_the_definition() {
    let t = random(7, 5, 3, 3);
    for relu in [false, true] {
        let c = random_conv(3, 4, relu);
        let got = conv(&c, &t);
        assert_eq!((got.width, got.height, got.channels), (7, 5, 4));
        let want = conv_by_definition(&c, &t);
        for (i, (g, w)) in got.data.iter().zip(&want).enumerate() {
            assert!((g - w).abs() < 1e-5, "element {i}: {g} != {w}");
        }
        assert_eq!(got.data.iter().any(|v| *v < 0.0), !relu);
    }
}

#[test]
fn pool_upsample_and_concat() {
    // 4×2, one channel: [1 5 2 0 / 3 -1 9 4]
    let t = Tensor { width: 4, height: 2, channels: 1, data: vec![1.0, 5.0, 2.0, 0.0, 3.0, -1.0, 9.0, 4.0] };
    assert_eq!(pool(&t), Tensor { width: 2, height: 1, channels: 1, data: vec![5.0, 9.0] });
    let two = Tensor { width: 2, height: 1, channels: 2, data: vec![1.0, 2.0, 3.0, 4.0] };
    let up = upsample(&two);
    assert_eq!((up.width, up.height), (4, 2));
    assert_eq!(up.data, [1.0, 2.0, 1.0, 2.0, 3.0, 4.0, 3.0, 4.0, 1.0, 2.0, 1.0, 2.0, 3.0, 4.0, 3.0, 4.0]);
    let one = Tensor { width: 2, height: 1, channels: 1, data: vec![7.0, 8.0] };
    assert_eq!(concat(&two, &one).data, [1.0, 2.0, 7.0, 3.0, 4.0, 8.0]);
    assert_eq!(concat(&one, &two).data, [7.0, 1.0, 2.0, 8.0, 3.0, 4.0]);
}

#[test]
fn walks_the_network() {
    let net = Network::from_archive(&Archive::parse(archive(&small_unet(9), 5)).unwrap()).unwrap();
    let input = random(32, 48, 9, 11).store(Precision::F32);
    let all = run_all(&net, input.clone(), Precision::F32);
    assert_eq!(all.len(), net.tensors.len());
    for (desc, t) in net.tensors.iter().zip(&all) {
        assert_eq!((t.width, t.height, t.channels), (32 >> desc.level, 48 >> desc.level, desc.channels), "{}", desc.name);
    }
    let out = run(&net, input.clone(), Precision::F32);
    assert_eq!(out, all[net.output.0]);
    assert!(out.data.iter().any(|v| *v < 0.0), "the last convolution has no ReLU");

    // f16 storage: every tensor holds f16 values, and the output stays
    // close to f32's.
    let half = run_all(&net, input, Precision::F16);
    for t in &half {
        assert!(t.data.iter().all(|v| half::f16::from_f32(*v).to_f32() == *v));
    }
    let err = half[net.output.0].data.iter().zip(&out.data).map(|(a, b)| (a - b).abs()).fold(0.0, f32::max);
    assert!(err > 0.0 && err < 0.05, "f16 against f32: {err}");
}

#[test]
#[should_panic(expected = "padded to a multiple of 16")]
fn refuses_an_unpadded_input() {
    let net = Network::from_archive(&Archive::parse(archive(&small_unet(3), 5)).unwrap()).unwrap();
    run(&net, random(20, 16, 3, 1), Precision::F32);
}
