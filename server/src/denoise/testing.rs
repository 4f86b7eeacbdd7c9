//! Test fixtures of the denoiser, for its tests and the renderer's: OIDN's
//! weights as the repository ships them, and small U-Nets with random weights.

use std::path::PathBuf;

/// One of OIDN's weights files in `server/assets/weights/oidn/`, the files
/// `bundled` embeds.
pub fn weights(name: &str) -> PathBuf {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("assets/weights/oidn").join(name);
    assert!(path.is_file(), "OIDN's weights file {} is missing from the repository", path.display());
    path
}

/// A convolution: (layer name, output channels, input channels).
pub type Layer = (String, u32, u32);

/// OIDN's base U-Net's layers with `input` channels and small, distinct
/// widths (the real ones are 32..112).
pub fn small_unet(input: u32) -> Vec<Layer> {
    let (e1, e2, e3, e4, e5, d4, d3, d2a, d2b, d1a, d1b) = (4, 5, 6, 7, 8, 6, 5, 4, 4, 5, 3);
    [
        ("enc_conv0", e1, input),
        ("enc_conv1", e1, e1),
        ("enc_conv2", e2, e1),
        ("enc_conv3", e3, e2),
        ("enc_conv4", e4, e3),
        ("enc_conv5a", e5, e4),
        ("enc_conv5b", e5, e5),
        ("dec_conv4a", d4, e5 + e3),
        ("dec_conv4b", d4, d4),
        ("dec_conv3a", d3, d4 + e2),
        ("dec_conv3b", d3, d3),
        ("dec_conv2a", d2a, d3 + e1),
        ("dec_conv2b", d2b, d2a),
        ("dec_conv1a", d1a, d2b + input),
        ("dec_conv1b", d1b, d1a),
        ("dec_conv0", 3, d1b),
    ]
    .map(|(n, o, i)| (n.to_owned(), o, i))
    .to_vec()
}

/// A .tza of `layers` with fp16 weights drawn from `seed`, scaled so that
/// activations keep their magnitude through the network (He init), and
/// small biases.
pub fn archive(layers: &[Layer], seed: u64) -> Vec<u8> {
    let mut rng = Rng(seed | 1);
    let mut data: Vec<(String, Vec<u32>, &str, Vec<u8>)> = Vec::new();
    for (name, o, i) in layers {
        let scale = (2.0 / (9.0 * *i as f32)).sqrt() * 3f32.sqrt();
        let w: Vec<u8> = (0..o * i * 9).flat_map(|_| half::f16::from_f32(rng.signed() * scale).to_le_bytes()).collect();
        let b: Vec<u8> = (0..*o).flat_map(|_| half::f16::from_f32(rng.signed() * 0.1).to_le_bytes()).collect();
        data.push((format!("{name}.weight"), vec![*o, *i, 3, 3], "oihw", w));
        data.push((format!("{name}.bias"), vec![*o], "x", b));
    }
    let entries: Vec<_> = data.iter().map(|(n, d, l, b)| (n.as_str(), d.as_slice(), *l, b'h', b.as_slice())).collect();
    super::tza::write(&entries)
}

/// The network of `archive(layers, seed)`.
pub fn network(layers: &[Layer], seed: u64) -> super::network::Network {
    let archive = super::tza::Archive::parse(archive(layers, seed)).expect("a well-formed archive");
    super::network::Network::from_archive(&archive).expect("a U-Net")
}

/// xorshift64*: reproducible numbers without a dependency.
pub struct Rng(pub u64);

impl Rng {
    /// Uniform in [-1, 1).
    pub fn signed(&mut self) -> f32 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 40;
        bits as f32 / (1u64 << 23) as f32 - 1.0
    }
}
