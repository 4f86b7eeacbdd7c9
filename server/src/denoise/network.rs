//! The U-Net a weights file describes, as an ordered list of ops over named
//! tensors: what the CPU reference and a GPU backend both walk.
//!
//! The topology is OIDN's (`core/unet_filter.cpp`, `addUNet` and
//! `addUNetLarge`; `training/model.py`), read from the tensor names rather
//! than fixed: layers are `enc_conv<L><s>` and `dec_conv<L><s>` (level `L`,
//! an optional letter `s` ordering the convolutions of a level). Encoder
//! levels 1..=P each end in a 2×2 max-pool (`pool<L>`); level P+1 is the
//! bottleneck; OIDN's base and small networks also have a level 0
//! (`enc_conv0`) before level 1. Decoder levels P..=1 each start with a 2×
//! nearest upsample (`upsample<L>`) and the concatenation (`concat<L>`,
//! upsampled channels first) with the encoder's `pool<L-1>`, or with the
//! input at level 1; base and small end with a level 0 (`dec_conv0`).
//! Every convolution is 3×3 with zero padding 1 and a bias, followed by a
//! ReLU except the last: that is the training model. OIDN's inference
//! graph also puts a ReLU on the last one, which its output processing's
//! clamp to [0, ∞) makes the same; here the last tensor shows the
//! network's raw output.
//!
//! Channel counts come from the weights' shapes (OIDN's small, base and
//! large networks differ) and must chain: a convolution takes as many
//! channels as the tensor before it has, its bias has one value per output
//! channel. Every tensor gets the name the inspector shows.

use std::collections::BTreeMap;

use super::tza::{Archive, Layout, TensorInfo};

/// What the network takes, from its first convolution's input channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Inputs {
    Color,
    ColorAlbedo,
    ColorAlbedoNormal,
}

impl Inputs {
    pub fn channels(self) -> usize {
        match self {
            Inputs::Color => 3,
            Inputs::ColorAlbedo => 6,
            Inputs::ColorAlbedoNormal => 9,
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            Inputs::Color => "colour",
            Inputs::ColorAlbedo => "colour and albedo",
            Inputs::ColorAlbedoNormal => "colour, albedo and normal",
        }
    }
}

/// An index into `Network::tensors`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct TensorId(pub usize);

/// A tensor between ops. Its size is the padded image's divided by
/// 2^`level`.
#[derive(Debug, Clone, PartialEq)]
pub struct Tensor {
    /// The name the inspector shows: `input`, a layer's name for its
    /// output, `pool<L>`, `upsample<L>`, `concat<L>`.
    pub name: String,
    pub channels: usize,
    pub level: u32,
    /// The index of the last op that reads it (`ops.len()` for the output):
    /// after that op its memory can be reused.
    pub last_use: usize,
    /// Read again after the ops that directly follow it: a skip connection
    /// (`pool<L>`, and `input`), kept until its concatenation.
    pub skip: bool,
}

/// A 3×3 convolution, stride 1, zero padding 1, with bias.
#[derive(Debug, Clone, PartialEq)]
pub struct Conv {
    /// The layer's name in the weights file (`enc_conv0`).
    pub name: String,
    pub src: TensorId,
    pub dst: TensorId,
    pub in_channels: usize,
    pub out_channels: usize,
    /// ReLU after the bias: every convolution but the last.
    pub relu: bool,
    /// `out_channels × in_channels × 3 × 3`, row-major (OIHW), as in the file.
    pub weight: Vec<f32>,
    pub bias: Vec<f32>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Op {
    Conv(Conv),
    /// 2×2 max-pool, stride 2.
    Pool {
        src: TensorId,
        dst: TensorId,
    },
    /// 2× nearest-neighbour upsample.
    Upsample {
        src: TensorId,
        dst: TensorId,
    },
    /// Channels of `first`, then of `second`.
    Concat {
        first: TensorId,
        second: TensorId,
        dst: TensorId,
    },
}

impl Op {
    pub fn dst(&self) -> TensorId {
        match self {
            Op::Conv(c) => c.dst,
            Op::Pool { dst, .. } | Op::Upsample { dst, .. } | Op::Concat { dst, .. } => *dst,
        }
    }

    pub fn srcs(&self) -> Vec<TensorId> {
        match self {
            Op::Conv(c) => vec![c.src],
            Op::Pool { src, .. } | Op::Upsample { src, .. } => vec![*src],
            Op::Concat { first, second, .. } => vec![*first, *second],
        }
    }
}

/// The whole network: `ops` in execution order, each writing one new tensor.
#[derive(Debug, Clone, PartialEq)]
pub struct Network {
    pub inputs: Inputs,
    /// Every tensor, `input` first, in the order the ops make them.
    pub tensors: Vec<Tensor>,
    pub ops: Vec<Op>,
    pub input: TensorId,
    /// The last convolution's output: 3 channels, before output processing.
    pub output: TensorId,
    /// How many times the image is halved: its sides must be padded to a
    /// multiple of 2^`pools` (16 for OIDN's networks).
    pub pools: u32,
}

/// Why an archive is not a U-Net: the byte of the tensor entry at fault
/// (or of the table, when the tensor is missing) and what is wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("at byte {at}: {message}")]
pub struct NetworkError {
    pub at: u64,
    pub message: String,
}

impl NetworkError {
    pub fn diagnostic(&self, display: &str) -> crate::diag::Diagnostic {
        super::weights_error(display, self.at, self.message.clone()).with_note(
            "loupe runs OIDN's U-Nets: layers enc_conv<level>[a-z] and dec_conv<level>[a-z], each a .weight (oihw, 3×3) and a .bias (x)",
        )
    }
}

impl Network {
    pub fn tensor(&self, id: TensorId) -> &Tensor {
        &self.tensors[id.0]
    }

    /// The multiple of which the image's sides are padded.
    pub fn alignment(&self) -> usize {
        1 << self.pools
    }

    pub fn from_archive(archive: &Archive) -> Result<Network, NetworkError> {
        let layers = Layers::read(archive)?;
        let (first, pools) = layers.encoder_levels(archive)?;
        let decoder_levels = layers.decoder_levels(archive, pools)?;
        let inputs = layers.inputs(first)?;
        let last = layers.last().0.clone();

        let mut b = Builder { archive, tensors: Vec::new(), ops: Vec::new() };
        let input = b.tensor("input", inputs.channels(), 0);
        let mut x = input;
        let mut skips = BTreeMap::from([(0, input)]);
        for (&level, convs) in &layers.encoder {
            for conv in convs {
                x = b.conv(conv, x, conv.0 != last)?;
            }
            if (1..=pools).contains(&level) {
                let t = b.tensors[x.0].clone();
                let dst = b.tensor(&format!("pool{level}"), t.channels, t.level + 1);
                b.ops.push(Op::Pool { src: x, dst });
                x = dst;
                skips.insert(level, x);
            }
        }
        for level in decoder_levels {
            if level > 0 {
                let (t, skip) = (b.tensors[x.0].clone(), skips[&(level - 1)]);
                let up = b.tensor(&format!("upsample{level}"), t.channels, t.level - 1);
                b.ops.push(Op::Upsample { src: x, dst: up });
                let channels = t.channels + b.tensors[skip.0].channels;
                let cat = b.tensor(&format!("concat{level}"), channels, t.level - 1);
                b.ops.push(Op::Concat { first: up, second: skip, dst: cat });
                x = cat;
            }
            for conv in &layers.decoder[&level] {
                x = b.conv(conv, x, conv.0 != last)?;
            }
        }
        let out = &b.tensors[x.0];
        if out.channels != 3 {
            let (name, t) = layers.last();
            let message = format!("the last layer `{name}` has {} output channels: expected 3 (RGB)", out.channels);
            return Err(NetworkError { at: t.entry_at, message });
        }
        let Builder { mut tensors, ops, .. } = b;
        let mut readers = vec![0; tensors.len()];
        for (i, op) in ops.iter().enumerate() {
            for src in op.srcs() {
                tensors[src.0].last_use = i;
                readers[src.0] += 1;
            }
        }
        for (t, n) in tensors.iter_mut().zip(readers) {
            t.skip = n > 1;
        }
        tensors[x.0].last_use = ops.len();
        Ok(Network { inputs, tensors, ops, input, output: x, pools })
    }
}

/// The layers of an archive, by side and level, each with its weight
/// tensor's entry (for locating problems).
struct Layers<'a> {
    encoder: BTreeMap<u32, Vec<(String, &'a TensorInfo)>>,
    decoder: BTreeMap<u32, Vec<(String, &'a TensorInfo)>>,
}

impl<'a> Layers<'a> {
    fn read(archive: &'a Archive) -> Result<Layers<'a>, NetworkError> {
        let mut layers = Layers { encoder: BTreeMap::new(), decoder: BTreeMap::new() };
        let mut names: BTreeMap<(bool, u32, String), (String, &TensorInfo)> = BTreeMap::new();
        for t in archive.tensors() {
            let unknown = || NetworkError {
                at: t.entry_at,
                message: format!(
                    "tensor `{}` is not part of a U-Net: expected <layer>.weight or <layer>.bias, the layer enc_conv<level>[a-z] or dec_conv<level>[a-z]",
                    t.name
                ),
            };
            let layer = t.name.strip_suffix(".weight").or_else(|| t.name.strip_suffix(".bias")).ok_or_else(unknown)?;
            let (decoder, rest) = match (layer.strip_prefix("enc_conv"), layer.strip_prefix("dec_conv")) {
                (Some(rest), _) => (false, rest),
                (_, Some(rest)) => (true, rest),
                _ => return Err(unknown()),
            };
            let digits = rest.find(|c: char| !c.is_ascii_digit()).unwrap_or(rest.len());
            let (level, suffix) = rest.split_at(digits);
            let level_text = level;
            let level: u32 = level.parse().map_err(|_| unknown())?;
            if level.to_string() != level_text || suffix.len() > 1 || !suffix.chars().all(|c| c.is_ascii_lowercase()) || level > 8 {
                return Err(unknown());
            }
            let weight = format!("{layer}.weight");
            let Some(w) = archive.get(&weight) else {
                return Err(NetworkError { at: t.entry_at, message: format!("layer `{layer}` has a bias but no `{weight}`") });
            };
            if archive.get(&format!("{layer}.bias")).is_none() {
                return Err(NetworkError { at: w.entry_at, message: format!("layer `{layer}` has weights but no `{layer}.bias`") });
            }
            names.insert((decoder, level, suffix.to_owned()), (layer.to_owned(), w));
        }
        for ((decoder, level, _), layer) in names {
            let side = if decoder { &mut layers.decoder } else { &mut layers.encoder };
            side.entry(level).or_default().push(layer);
        }
        Ok(layers)
    }

    /// The first encoder level (0 or 1) and the number of pools: levels
    /// must run without a gap from the first to the bottleneck, at least 2.
    fn encoder_levels(&self, archive: &Archive) -> Result<(u32, u32), NetworkError> {
        let first = if self.encoder.contains_key(&0) { 0 } else { 1 };
        let mut expected = first;
        for &level in self.encoder.keys() {
            if level != expected {
                return Err(missing(archive, &format!("enc_conv{expected}")));
            }
            expected += 1;
        }
        match expected - 1 {
            bottleneck if expected > 2 => Ok((first, bottleneck - 1)),
            _ => Err(missing(archive, &format!("enc_conv{expected}"))),
        }
    }

    /// The decoder levels in the order they run: `pools` down to 1, then 0
    /// when there is one.
    fn decoder_levels(&self, archive: &Archive, pools: u32) -> Result<Vec<u32>, NetworkError> {
        let levels: Vec<u32> = (1..=pools).rev().chain(self.decoder.contains_key(&0).then_some(0)).collect();
        if let Some((&found, layers)) = self.decoder.iter().find(|(l, _)| !levels.contains(l)) {
            let (name, t) = &layers[0];
            let message = format!(
                "layer `{name}` is at decoder level {found}, but the encoder pools {pools} times: decoder levels run {pools}..=1 (and 0)"
            );
            return Err(NetworkError { at: t.entry_at, message });
        }
        match levels.iter().find(|l| !self.decoder.contains_key(l)) {
            Some(l) => Err(missing(archive, &format!("dec_conv{l}"))),
            None => Ok(levels),
        }
    }

    /// What the network takes, from its first convolution's input channels.
    fn inputs(&self, first: u32) -> Result<Inputs, NetworkError> {
        let (name, w) = &self.encoder[&first][0];
        let n = *w.dims.get(1).ok_or_else(|| shape_error(w, "4 dimensions [out, in, 3, 3]"))?;
        match n {
            3 => Ok(Inputs::Color),
            6 => Ok(Inputs::ColorAlbedo),
            9 => Ok(Inputs::ColorAlbedoNormal),
            n => {
                let message =
                    format!("the first layer `{name}` takes {n} input channels: expected 3 (colour), 6 (+ albedo) or 9 (+ normal)");
                Err(NetworkError { at: w.entry_at, message })
            }
        }
    }

    /// The last convolution (no ReLU after it): the last of the lowest
    /// decoder level. `from_archive` checked the decoder has levels.
    fn last(&self) -> &(String, &'a TensorInfo) {
        self.decoder.values().next().and_then(|v| v.last()).expect("decoder levels hold a layer")
    }
}

fn missing(archive: &Archive, layer: &str) -> NetworkError {
    NetworkError { at: archive.table_at(), message: format!("the tensor table has no layer `{layer}` (no `{layer}.weight`)") }
}

fn shape_error(t: &TensorInfo, expected: &str) -> NetworkError {
    let layout = match t.layout {
        Layout::Oihw => "oihw",
        Layout::X => "x",
    };
    NetworkError { at: t.entry_at, message: format!("tensor `{}` has shape {:?} ({layout}): expected {expected}", t.name, t.dims) }
}

struct Builder<'a> {
    archive: &'a Archive,
    tensors: Vec<Tensor>,
    ops: Vec<Op>,
}

impl Builder<'_> {
    fn tensor(&mut self, name: &str, channels: usize, level: u32) -> TensorId {
        self.tensors.push(Tensor { name: name.to_owned(), channels, level, last_use: 0, skip: false });
        TensorId(self.tensors.len() - 1)
    }

    /// Adds layer `name`'s convolution of `src`, its shapes checked.
    fn conv(&mut self, (name, w): &(String, &TensorInfo), src: TensorId, relu: bool) -> Result<TensorId, NetworkError> {
        let b = self.archive.get(&format!("{name}.bias")).expect("Layers::read checked the bias exists");
        let [o, i, 3, 3] = w.dims[..] else {
            return Err(shape_error(w, "[out, in, 3, 3]: loupe runs 3×3 convolutions"));
        };
        if w.layout != Layout::Oihw {
            return Err(shape_error(w, "layout oihw"));
        }
        let (o, i) = (o as usize, i as usize);
        if b.dims[..] != [o as u32] || b.layout != Layout::X {
            return Err(shape_error(b, &format!("[{o}] (x): one bias per output channel of `{name}.weight`")));
        }
        let s = &self.tensors[src.0];
        if i != s.channels {
            let message = format!(
                "`{name}.weight` takes {i} input channels, but `{}` before it has {}{}",
                s.name,
                s.channels,
                self.concat_parts(src)
            );
            return Err(NetworkError { at: w.entry_at, message });
        }
        if o == 0 {
            return Err(shape_error(w, "at least one output channel"));
        }
        let level = s.level;
        let dst = self.tensor(name, o, level);
        let (weight, bias) = (self.archive.values(w), self.archive.values(b));
        self.ops.push(Op::Conv(Conv { name: name.clone(), src, dst, in_channels: i, out_channels: o, relu, weight, bias }));
        Ok(dst)
    }

    /// " (upsample4: 96 + pool3: 64)" when `id` is a concatenation.
    fn concat_parts(&self, id: TensorId) -> String {
        self.ops
            .iter()
            .find_map(|op| match op {
                Op::Concat { first, second, dst } if *dst == id => {
                    let (a, b) = (&self.tensors[first.0], &self.tensors[second.0]);
                    Some(format!(" ({}: {} + {}: {})", a.name, a.channels, b.name, b.channels))
                }
                _ => None,
            })
            .unwrap_or_default()
    }
}

#[cfg(test)]
mod tests;
