// Random numbers for Monte Carlo passes (the path tracer), deterministic
// per (pixel, sample index, dimension): the same frame renders the same
// image on every run and every adapter, and any sample can be replayed
// alone when debugging. Each number is one PCG hash (Jarzynski and Olano,
// "Hash Functions for GPU Rendering", JCGT 2020) of a key mixing the three,
// so no state is carried between dimensions and none needs storing.
#define_import_path loupe::random

// The PCG-RXS-M-XS hash of one 32-bit word.
fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The key of (pixel, sample): distinct for every pixel of a target up to
// 65536 wide and every sample, then scrambled.
fn random_key(pixel: vec2<u32>, sample: u32) -> u32 {
    return pcg_hash(pcg_hash(pixel.x + (pixel.y << 16u)) ^ sample);
}

// Number `dimension` of a sample, uniform in [0, 1): 24 random bits, so
// 1.0 itself never comes out.
fn random_f32(key: u32, dimension: u32) -> f32 {
    return f32(pcg_hash(key ^ pcg_hash(dimension)) >> 8u) * (1.0 / 16777216.0);
}
