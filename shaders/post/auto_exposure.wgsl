// Auto exposure, as two compute passes (entry points `histogram` and
// `adapt`): a histogram of log2 luminance over the metering range, then
// one workgroup that turns it into an exposure and adapts the exposure
// kept from the previous frame toward it.

struct Metering {
    // The metering range in log2 luminance (EV), and 1 / its width.
    min_ev: f32,
    inv_range: f32,
    // Adapt only: 1 - exp(-dt * speed), the share of the way to the target
    // covered this frame.
    rate: f32,
    _pad: f32,
}

// What the adapt pass keeps from frame to frame (a history buffer, zeroed
// when created or reset: `valid` 0 means "no history, start at the target").
struct ExposureState {
    // The exposure applied, in stops: the frame is multiplied by 2^ev.
    ev: f32,
    // Where it is heading: the exposure that maps the mean log luminance
    // to middle grey.
    target_ev: f32,
    // The metered mean log2 luminance, and 1.0 once written.
    mean_log2: f32,
    valid: f32,
}

const BINS: u32 = 256u;
// The luminance middle grey maps to.
const KEY: f32 = 0.18;

@group(0) @binding(0) var<uniform> metering: Metering;
@group(0) @binding(1) var hdr: texture_2d<f32>;
@group(0) @binding(2) var<storage, read_write> bins: array<atomic<u32>, BINS>;

var<workgroup> local_bins: array<atomic<u32>, BINS>;

fn is_finite(x: f32) -> bool {
    // Exponent bits all ones: NaN or Inf. Checked on the bits, since WGSL
    // lets implementations assume floats are finite.
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// Bin 0 holds pixels darker than the range (black); bins 1..255 split the
// range evenly, pixels brighter than it land in the last.
fn bin_of(luminance: f32) -> u32 {
    let t = (log2(luminance) - metering.min_ev) * metering.inv_range;
    if luminance <= 0.0 || t < 0.0 {
        return 0u;
    }
    return 1u + min(u32(t * f32(BINS - 1u)), BINS - 2u);
}

@compute @workgroup_size(16, 16, 1)
fn histogram(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) index: u32) {
    atomicStore(&local_bins[index], 0u);
    workgroupBarrier();
    let size = textureDimensions(hdr);
    if id.x < size.x && id.y < size.y {
        let rgb = textureLoad(hdr, vec2<i32>(id.xy), 0).rgb;
        let luminance = dot(rgb, vec3(0.2126, 0.7152, 0.0722));
        // NaN and Inf pixels are not metered: one bad pixel must not
        // decide the exposure of every later frame.
        if is_finite(luminance) {
            atomicAdd(&local_bins[bin_of(luminance)], 1u);
        }
    }
    workgroupBarrier();
    let count = atomicLoad(&local_bins[index]);
    if count > 0u {
        atomicAdd(&bins[index], count);
    }
}

@group(0) @binding(3) var<storage, read_write> state: ExposureState;

var<workgroup> partial_count: array<f32, BINS>;
var<workgroup> partial_sum: array<f32, BINS>;

@compute @workgroup_size(256, 1, 1)
fn adapt(@builtin(local_invocation_index) index: u32) {
    // Each lane weighs its bin by its centre, in units of bins; bin 0
    // (black) is not metered.
    let count = f32(atomicLoad(&bins[index]));
    let metered = select(count, 0.0, index == 0u);
    partial_count[index] = metered;
    partial_sum[index] = metered * (f32(index) - 0.5);
    workgroupBarrier();
    for (var stride = BINS / 2u; stride > 0u; stride = stride / 2u) {
        if index < stride {
            partial_count[index] += partial_count[index + stride];
            partial_sum[index] += partial_sum[index + stride];
        }
        workgroupBarrier();
    }
    if index != 0u {
        return;
    }
    let previous = state;
    let pixels = partial_count[0];
    if pixels < 1.0 {
        // Nothing to meter (a black or entirely non-finite frame): keep
        // what was there.
        return;
    }
    let range = 1.0 / metering.inv_range;
    let mean_log2 = metering.min_ev + partial_sum[0] / pixels / f32(BINS - 1u) * range;
    let target_ev = log2(KEY) - mean_log2;
    var ev = target_ev;
    if previous.valid > 0.5 && is_finite(previous.ev) {
        ev = previous.ev + (target_ev - previous.ev) * metering.rate;
    }
    if !is_finite(ev) {
        return;
    }
    state = ExposureState(ev, target_ev, mean_log2, 1.0);
}
