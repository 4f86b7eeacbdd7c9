use super::*;

fn image(w: usize, h: usize, f: impl Fn(usize, usize) -> [f32; 3]) -> Image {
    let data = (0..h).flat_map(|y| (0..w).flat_map(move |x| [x, y])).collect::<Vec<_>>();
    Image { width: w, height: h, data: data.chunks(2).flat_map(|p| f(p[0], p[1])).collect() }
}

#[test]
fn transfer_functions_invert_and_join() {
    for t in [Transfer::Linear, Transfer::Srgb, Transfer::Pu] {
        for i in 0..=2000 {
            let y = if t == Transfer::Pu { 10f32.powf(i as f32 / 2000.0 * 12.0 - 7.0) } else { i as f32 / 2000.0 };
            let back = t.inverse(t.forward(y));
            assert!((back - y).abs() <= 2e-4 * y.max(1e-3), "{t:?}: {y} -> {back}");
        }
    }
    // The pieces meet where OIDN's thresholds join them.
    let y = srgb::Y0;
    let (a, b) = (srgb::A * y, srgb::B * y.powf(srgb::C) + srgb::D);
    assert!((a - b).abs() < 1e-6, "{a} {b}");
    for (y, x) in [(pu::Y0, pu::X0), (pu::Y1, pu::X1)] {
        assert!((pu::forward(y) - x).abs() < 1e-6 && (pu::inverse(x) - y).abs() < 1e-4 * y, "{y} {x}");
    }
    // 1 up to the rounding of OIDN's reciprocal.
    assert!((Transfer::Pu.forward(Y_MAX) - 1.0).abs() <= f32::EPSILON);
    assert!((Transfer::Srgb.forward(1.0) - 1.0).abs() <= f32::EPSILON);
    // Monotonic, so the network's ordering of values is the light's.
    let pu: Vec<f32> = (0..1000).map(|i| Transfer::Pu.forward(i as f32 * 0.37)).collect();
    assert!(pu.windows(2).all(|w| w[0] < w[1]));
}

#[test]
fn modes_pick_oidns_transfer() {
    assert_eq!([Mode::Ldr, Mode::LdrSrgb, Mode::Hdr].map(Mode::transfer), [Transfer::Srgb, Transfer::Linear, Transfer::Pu]);
}

#[test]
fn autoexposure_is_key_over_the_geometric_mean_of_bins() {
    let grey = |v: f32| image(40, 20, move |_, _| [v; 3]);
    assert!((autoexposure(&grey(0.5)) - 0.36).abs() < 1e-5);
    assert_eq!(autoexposure(&grey(0.0)), 1.0);
    // Bins of 16 columns: 40 wide is 3 bins of 13, 13 and 14 columns, each
    // bin's mean luminance first, then their geometric mean.
    let halves = image(32, 16, |x, _| if x < 16 { [2.0; 3] } else { [0.125; 3] });
    let want = 0.18 / (2.0f32 * 0.125).sqrt();
    assert!((autoexposure(&halves) - want).abs() < 1e-5, "{}", autoexposure(&halves));
    // Luminance weights; NaN and negatives count as 0, infinity as the largest float.
    let red = image(16, 16, |_, _| [1.0, 0.0, 0.0]);
    assert!((autoexposure(&red) - 0.18 / 0.212671).abs() < 1e-4);
    let nan = image(16, 16, |x, _| if x == 0 { [f32::NAN, -5.0, f32::NAN] } else { [1.0; 3] });
    assert!((autoexposure(&nan) - 0.18 / (240.0 / 256.0)).abs() < 1e-4);
}

#[test]
fn input_is_sanitised_transferred_and_padded() {
    let color = image(17, 3, |x, y| [x as f32 * 0.1, y as f32, if x == 1 { f32::NAN } else { f32::INFINITY }]);
    let albedo = image(17, 3, |_, _| [-1.0, 0.5, 2.0]);
    let normal = image(17, 3, |_, _| [-2.0, 0.0, 1.0]);
    let t = input(&color, Some(&albedo), Some(&normal), Mode::Ldr, 1.0, 16);
    assert_eq!((t.width, t.height, t.channels), (32, 16, 9));
    let (px, one) = (t.pixel(3, 2), Transfer::Srgb.forward(1.0));
    assert_eq!(px, [Transfer::Srgb.forward(0.3), one, one, 0.0, 0.5, 1.0, 0.0, 0.5, 1.0]);
    assert_eq!(t.pixel(1, 0)[2], 0.0, "NaN is 0");
    // The padding (right and bottom) is zero.
    assert!(t.pixel(17, 0).iter().chain(t.pixel(0, 3)).chain(t.pixel(31, 15)).all(|v| *v == 0.0));

    // HDR: scaled, through PU, no clamp at 1; colour only.
    let hdr = input(&color, None, None, Mode::Hdr, 2.0, 16);
    assert_eq!(hdr.channels, 3);
    assert_eq!(hdr.pixel(3, 2)[..2], [Transfer::Pu.forward(0.6), Transfer::Pu.forward(4.0)]);
    assert_eq!(hdr.pixel(3, 2)[2], Transfer::Pu.forward(f32::MAX));
    let srgb = input(&color, Some(&albedo), None, Mode::LdrSrgb, 1.0, 16);
    assert_eq!((srgb.channels, srgb.pixel(3, 2)[0]), (6, 0.3));
}

#[test]
fn output_is_cropped_sanitised_and_scaled() {
    let mut t = Tensor::zeros(32, 16, 3);
    t.data.iter_mut().enumerate().for_each(|(i, v)| *v = (i % 7) as f32 * 0.2 - 0.2);
    t.data[0] = f32::NAN;
    let ldr = output(&t, 17, 3, Mode::LdrSrgb, 1.0);
    assert_eq!((ldr.width, ldr.height, ldr.data.len()), (17, 3, 17 * 3 * 3));
    assert_eq!(ldr.pixel(0, 0), [0.0, 0.0, 0.2]);
    assert!(ldr.data.iter().all(|v| (0.0..=1.0).contains(v)));
    let want: Vec<f32> = t.pixel(0, 1).iter().map(|v| v.clamp(0.0, 1.0)).collect();
    assert_eq!(ldr.pixel(0, 1)[..], want[..]);
    let hdr = output(&t, 17, 3, Mode::Hdr, 0.5);
    let v = t.pixel(2, 2)[1];
    assert!((hdr.pixel(2, 2)[1] - Transfer::Pu.inverse(v.max(0.0)) * 2.0).abs() < 1e-6);
    assert!(output(&t, 17, 3, Mode::Hdr, 0.0).data.iter().all(|v| *v == 0.0));
}

#[test]
fn input_scale_defaults_as_oidn() {
    let c = image(16, 16, |_, _| [0.5; 3]);
    assert_eq!(input_scale(Mode::Ldr, None, &c), 1.0);
    assert_eq!(input_scale(Mode::Hdr, Some(3.0), &c), 3.0);
    assert!((input_scale(Mode::Hdr, None, &c) - 0.36).abs() < 1e-5);
}
