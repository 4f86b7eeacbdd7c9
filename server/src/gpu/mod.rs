//! Opening a wgpu device without a window.
//!
//! Architecture Invariant: wgpu objects are created on one thread per device
//! (the render thread in `serve`, the calling thread in `check` and
//! `render`): error scopes are per thread, and catching pipeline errors with
//! them is how loupe keeps the last good pipeline.

pub mod pipeline;

use std::sync::{Arc, Mutex};

/// Optional features the debugger uses, with what each one buys. Requested
/// when the adapter has them; missing ones degrade with a message.
pub const OPTIONAL_FEATURES: &[(wgpu::Features, &str)] = &[
    (wgpu::Features::TIMESTAMP_QUERY, "GPU pass timings (CPU timings are shown instead)"),
    (wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS, "per-pass GPU timestamps inside one encoder"),
    (wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES, "per-draw GPU timestamps"),
    (wgpu::Features::PIPELINE_STATISTICS_QUERY, "per-draw pipeline statistics"),
    (wgpu::Features::SUBGROUP, "subgroup and quad operations in shaders"),
    (wgpu::Features::SHADER_F16, "f16 in shaders"),
    (wgpu::Features::PRIMITIVE_INDEX, "@builtin(primitive_index) in fragment shaders"),
    (wgpu::Features::FLOAT32_FILTERABLE, "filtered sampling of f32 textures"),
];

/// What to tell a user with no adapter at all.
pub const NO_ADAPTER_HINT: &str = "no GPU adapter found: install a Vulkan driver \
(on Debian/Ubuntu without a GPU: `apt-get install mesa-vulkan-drivers libvulkan1` for lavapipe), or pass --no-device";

#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    #[error("{NO_ADAPTER_HINT}")]
    NoAdapter,
    #[error("the adapter `{adapter}` refused a device: {reason}")]
    RequestDevice { adapter: String, reason: String },
}

/// An open device and what it can do.
pub struct Gpu {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub features: wgpu::Features,
    /// One line per optional feature the adapter lacks, saying what degrades.
    pub degraded: Vec<String>,
    /// Errors no error scope caught. Collected instead of wgpu's default
    /// handler, which panics.
    pub uncaptured: Arc<Mutex<Vec<String>>>,
}

impl Gpu {
    /// `Name (backend, type)`, how reports and the UI name the adapter.
    pub fn adapter_name(&self) -> String {
        format!("{} ({:?}, {:?})", self.info.name, self.info.backend, self.info.device_type)
    }

    pub fn is_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The naga capabilities matching the granted features, so shaders are
    /// validated against what this device can actually run.
    pub fn capabilities(&self) -> naga::valid::Capabilities {
        capabilities(self.features)
    }
}

pub fn capabilities(features: wgpu::Features) -> naga::valid::Capabilities {
    use naga::valid::Capabilities as C;
    let mut caps = C::default();
    if features.contains(wgpu::Features::SHADER_F16) {
        caps |= C::SHADER_FLOAT16;
    }
    if features.contains(wgpu::Features::SUBGROUP) {
        caps |= C::SUBGROUP;
    }
    if features.contains(wgpu::Features::SUBGROUP_BARRIER) {
        caps |= C::SUBGROUP_BARRIER;
    }
    if features.contains(wgpu::Features::PRIMITIVE_INDEX) {
        caps |= C::PRIMITIVE_INDEX;
    }
    caps
}

/// Capabilities assumed when checking without a device: everything loupe
/// can request, so sources are judged on their own and the device pass
/// reports what a particular adapter lacks.
pub fn capabilities_without_device() -> naga::valid::Capabilities {
    OPTIONAL_FEATURES.iter().fold(capabilities(wgpu::Features::SUBGROUP_BARRIER), |c, (f, _)| c | capabilities(*f))
}

/// Opens the best adapter: a real GPU over a CPU one. `LOUPE_ADAPTER`
/// (a substring of the adapter name) picks one explicitly.
pub fn open() -> Result<Gpu, OpenError> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
    // The GL adapter (llvmpipe) lacks every optional feature; Vulkan covers
    // real GPUs and lavapipe alike.
    desc.backends = wgpu::Backends::VULKAN;
    let instance = wgpu::Instance::new(desc);
    let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
    let wanted = std::env::var("LOUPE_ADAPTER").ok();
    let rank = |a: &wgpu::Adapter| match a.get_info().device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Other => 3,
        wgpu::DeviceType::Cpu => 4,
    };
    let adapter = adapters
        .into_iter()
        .filter(|a| wanted.as_deref().is_none_or(|w| a.get_info().name.to_lowercase().contains(&w.to_lowercase())))
        .min_by_key(rank)
        .ok_or(OpenError::NoAdapter)?;
    let info = adapter.get_info();
    let available = adapter.features();
    let mut features = wgpu::Features::empty();
    let mut degraded = Vec::new();
    for (f, what) in OPTIONAL_FEATURES {
        if available.contains(*f) {
            features |= *f;
        } else {
            degraded.push(format!("adapter lacks {f:?}: no {what}"));
        }
    }
    if available.contains(wgpu::Features::SUBGROUP_BARRIER) {
        features |= wgpu::Features::SUBGROUP_BARRIER;
    }
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("loupe"),
        required_features: features,
        required_limits: adapter.limits(),
        ..Default::default()
    }))
    .map_err(|e| OpenError::RequestDevice { adapter: info.name.clone(), reason: e.to_string() })?;
    let uncaptured = Arc::new(Mutex::new(Vec::new()));
    let sink = uncaptured.clone();
    device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
        if let Ok(mut v) = sink.lock() {
            v.push(e.to_string());
        }
    }));
    Ok(Gpu { adapter, device, queue, info, features, degraded, uncaptured })
}
