use super::*;
use crate::denoise::testing::{Layer, archive, small_unet, weights};
use crate::denoise::tza;

fn build(layers: &[Layer]) -> Result<Network, NetworkError> {
    Network::from_archive(&Archive::parse(archive(layers, 7)).unwrap())
}

fn names(n: &Network) -> Vec<&str> {
    n.tensors.iter().map(|t| t.name.as_str()).collect()
}

fn set(layers: &mut [Layer], name: &str, out: u32, inp: u32) {
    let l = layers.iter_mut().find(|l| l.0 == name).unwrap();
    (l.1, l.2) = (out, inp);
}

const BASE_TENSORS: [&str; 29] = [
    "input",
    "enc_conv0",
    "enc_conv1",
    "pool1",
    "enc_conv2",
    "pool2",
    "enc_conv3",
    "pool3",
    "enc_conv4",
    "pool4",
    "enc_conv5a",
    "enc_conv5b",
    "upsample4",
    "concat4",
    "dec_conv4a",
    "dec_conv4b",
    "upsample3",
    "concat3",
    "dec_conv3a",
    "dec_conv3b",
    "upsample2",
    "concat2",
    "dec_conv2a",
    "dec_conv2b",
    "upsample1",
    "concat1",
    "dec_conv1a",
    "dec_conv1b",
    "dec_conv0",
];

#[test]
fn builds_oidn_base_network() {
    let a = tza::read(&weights("rt_ldr_alb_nrm.tza"), "rt_ldr_alb_nrm.tza").unwrap();
    let n = Network::from_archive(&a).unwrap();
    assert_eq!(names(&n), BASE_TENSORS);
    assert_eq!((n.inputs, n.pools, n.alignment()), (Inputs::ColorAlbedoNormal, 4, 16));
    let channels = |name: &str| n.tensors.iter().find(|t| t.name == name).unwrap().channels;
    let levels = |name: &str| n.tensors.iter().find(|t| t.name == name).unwrap().level;
    assert_eq!(
        ["input", "enc_conv1", "pool2", "enc_conv5b", "concat4", "dec_conv4b", "concat1", "dec_conv0"].map(channels),
        [9, 32, 48, 96, 160, 112, 73, 3]
    );
    assert_eq!(["input", "pool1", "pool4", "enc_conv5b", "upsample4", "concat1"].map(levels), [0, 1, 4, 4, 3, 0]);
    let skips: Vec<&str> = n.tensors.iter().filter(|t| t.skip).map(|t| t.name.as_str()).collect();
    assert_eq!(skips, ["input", "pool1", "pool2", "pool3"]);
    let no_relu: Vec<&str> =
        n.ops.iter().filter_map(|op| if let Op::Conv(c) = op { (!c.relu).then_some(c.name.as_str()) } else { None }).collect();
    assert_eq!(no_relu, ["dec_conv0"]);
    assert_eq!(n.tensor(n.output).name, "dec_conv0");
    // The input is kept from the first op to concat1.
    let concat1 = n.ops.iter().position(|op| n.tensor(op.dst()).name == "concat1").unwrap();
    assert_eq!(n.tensor(n.input).last_use, concat1);
    assert_eq!(n.tensor(n.output).last_use, n.ops.len());
    let Op::Concat { first, second, .. } = &n.ops[concat1] else { panic!() };
    assert_eq!((n.tensor(*first).name.as_str(), n.tensor(*second).name.as_str()), ("upsample1", "input"));
    let rt_ldr = tza::read(&weights("rt_ldr.tza"), "rt_ldr.tza").unwrap();
    assert_eq!(Network::from_archive(&rt_ldr).unwrap().inputs, Inputs::Color);
}

#[test]
fn channel_counts_come_from_the_weights() {
    for input in [3, 6, 9] {
        let n = build(&small_unet(input)).unwrap();
        assert_eq!(names(&n), BASE_TENSORS);
        assert_eq!(n.tensor(n.input).channels, input as usize);
        let concat4 = n.tensors.iter().find(|t| t.name == "concat4").unwrap();
        assert_eq!(concat4.channels, 8 + 6);
    }
    let n = build(&small_unet(3)).unwrap();
    let Op::Conv(c) = &n.ops[0] else { panic!() };
    assert_eq!((c.in_channels, c.out_channels, c.weight.len(), c.bias.len()), (3, 4, 4 * 3 * 9, 4));
}

/// OIDN's large network: two convolutions per level, no level 0, three at
/// the last decoder level.
#[test]
fn builds_the_large_topology() {
    let (ic, e, d) = (3, [4, 5, 6, 7, 8], [7, 6, 5, 4]);
    let mut layers: Vec<Layer> = Vec::new();
    let mut prev = ic;
    for (l, &c) in e.iter().enumerate() {
        layers.push((format!("enc_conv{}a", l + 1), c, prev));
        layers.push((format!("enc_conv{}b", l + 1), c, c));
        prev = c;
    }
    let skip = [ic, e[0], e[1], e[2]];
    for (k, &c) in d.iter().enumerate() {
        let level = 4 - k;
        layers.push((format!("dec_conv{level}a"), c, prev + skip[level - 1]));
        layers.push((format!("dec_conv{level}b"), c, c));
        prev = c;
    }
    layers.push(("dec_conv1c".into(), 3, prev));
    let n = build(&layers).unwrap();
    let names = names(&n);
    assert_eq!(names[..5], ["input", "enc_conv1a", "enc_conv1b", "pool1", "enc_conv2a"]);
    assert_eq!(names[names.len() - 5..], ["upsample1", "concat1", "dec_conv1a", "dec_conv1b", "dec_conv1c"]);
    assert_eq!(n.tensor(n.output).name, "dec_conv1c");
    assert_eq!(n.pools, 4);
}

#[test]
fn shapes_that_do_not_chain_name_the_tensor() {
    let mut layers = small_unet(9);
    set(&mut layers, "dec_conv4a", 6, 13);
    let bytes = archive(&layers, 7);
    let a = Archive::parse(bytes).unwrap();
    let e = Network::from_archive(&a).unwrap_err();
    assert_eq!(e.at, a.get("dec_conv4a.weight").unwrap().entry_at);
    assert_eq!(e.message, "`dec_conv4a.weight` takes 13 input channels, but `concat4` before it has 14 (upsample4: 8 + pool3: 6)");
    let d = e.diagnostic("w.tza");
    assert_eq!(d.code, crate::diag::Code::Weights);
    assert!(d.message.starts_with(&format!("at byte {}: `dec_conv4a.weight`", e.at)), "{}", d.message);

    set(&mut layers, "dec_conv4a", 6, 15);
    assert!(build(&layers).unwrap_err().message.starts_with("`dec_conv4a.weight` takes 15 input channels"));

    let mut layers = small_unet(3);
    set(&mut layers, "enc_conv2", 5, 3);
    let e = build(&layers).unwrap_err();
    assert!(e.message.starts_with("`enc_conv2.weight` takes 3 input channels, but `pool1` before it has 4"), "{}", e.message);
}

#[test]
fn refuses_bad_biases_kernels_and_channel_counts() {
    let good = archive(&small_unet(3), 1);
    let a = Archive::parse(good).unwrap();
    // A bias of the wrong length, rebuilt from the good archive's tensors.
    let rebuild = |edit: &dyn Fn(&str, &mut Vec<u32>)| {
        let mut data: Vec<(String, Vec<u32>, String, Vec<u8>)> = Vec::new();
        for t in a.tensors() {
            let mut dims = t.dims.clone();
            edit(&t.name, &mut dims);
            let n: u32 = dims.iter().product();
            let bytes = vec![0u8; 2 * n as usize];
            let layout = if dims.len() == 4 { "oihw" } else { "x" }.to_owned();
            data.push((t.name.clone(), dims, layout, bytes));
        }
        let entries: Vec<_> = data.iter().map(|(n, d, l, b)| (n.as_str(), d.as_slice(), l.as_str(), b'h', b.as_slice())).collect();
        let a = Archive::parse(tza::write(&entries)).unwrap();
        Network::from_archive(&a).map(|_| ()).unwrap_err().message
    };
    let m = rebuild(&|name, dims| {
        if name == "enc_conv3.bias" {
            dims[0] = 5;
        }
    });
    assert_eq!(m, "tensor `enc_conv3.bias` has shape [5] (x): expected [6] (x): one bias per output channel of `enc_conv3.weight`");
    let m = rebuild(&|name, dims| {
        if name == "enc_conv1.weight" {
            dims[2..].copy_from_slice(&[5, 5]);
        }
    });
    assert!(m.starts_with("tensor `enc_conv1.weight` has shape [4, 4, 5, 5] (oihw): expected [out, in, 3, 3]"), "{m}");

    let mut layers = small_unet(4);
    set(&mut layers, "dec_conv1a", 5, 8);
    assert_eq!(
        build(&layers).unwrap_err().message,
        "the first layer `enc_conv0` takes 4 input channels: expected 3 (colour), 6 (+ albedo) or 9 (+ normal)"
    );
    let mut layers = small_unet(3);
    set(&mut layers, "dec_conv0", 4, 3);
    assert_eq!(build(&layers).unwrap_err().message, "the last layer `dec_conv0` has 4 output channels: expected 3 (RGB)");
}

#[test]
fn refuses_missing_and_unknown_layers() {
    let without = |skip: &[&str]| {
        let layers: Vec<Layer> = small_unet(3).into_iter().filter(|l| !skip.contains(&l.0.as_str())).collect();
        let a = Archive::parse(archive(&layers, 1)).unwrap();
        (a.table_at(), Network::from_archive(&a).unwrap_err())
    };
    let (table, e) = without(&["enc_conv3"]);
    assert_eq!((e.at, e.message.as_str()), (table, "the tensor table has no layer `enc_conv3` (no `enc_conv3.weight`)"));
    let (table, e) = without(&["dec_conv3a", "dec_conv3b"]);
    assert_eq!((e.at, e.message.as_str()), (table, "the tensor table has no layer `dec_conv3` (no `dec_conv3.weight`)"));

    let mut layers = small_unet(3);
    layers.push(("dec_conv7".into(), 3, 3));
    let e = build(&layers).unwrap_err();
    assert!(e.message.starts_with("layer `dec_conv7` is at decoder level 7, but the encoder pools 4 times"), "{}", e.message);

    for bad in ["enc_conv", "enc_conv1ab", "enc_conv01", "conv1", "enc_conv1x.weight"] {
        let mut layers = small_unet(3);
        layers.push((bad.into(), 3, 3));
        let e = build(&layers).unwrap_err();
        assert!(e.message.contains("is not part of a U-Net"), "{bad}: {}", e.message);
    }
    let only_bias = tza::write(&[("enc_conv0.bias", &[1], "x", b'h', &[0, 0])]);
    let e = Network::from_archive(&Archive::parse(only_bias).unwrap()).unwrap_err();
    assert_eq!(e.message, "layer `enc_conv0` has a bias but no `enc_conv0.weight`");
}
