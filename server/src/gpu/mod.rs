//! Opening a wgpu device without a window.
//!
//! Architecture Invariant: wgpu objects are created on one thread per device
//! (the render thread in `serve`, the calling thread in `check` and
//! `render`): error scopes are per thread, and catching pipeline errors with
//! them is how loupe keeps the last good pipeline.

pub mod pipeline;
#[cfg(any(test, feature = "testing"))]
pub mod testing;

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

/// What to tell a user with no adapter at all, whichever command failed:
/// what to install, and the one command that works without a device (only
/// `loupe check` takes --no-device).
pub const NO_ADAPTER_HINT: &str = "no GPU adapter found: install a Vulkan driver \
(on Debian/Ubuntu without a GPU: `apt-get install mesa-vulkan-drivers libvulkan1` for lavapipe); \
without one, `loupe check --no-device` still checks shaders and scenes";

#[derive(Debug, thiserror::Error)]
pub enum OpenError {
    #[error("{NO_ADAPTER_HINT}")]
    NoAdapter,
    #[error("the adapter `{adapter}` refused a device: {reason}")]
    RequestDevice { adapter: String, reason: String },
}

/// An open device and what it can do.
#[derive(Clone)]
pub struct Gpu {
    /// Kept for what shares the device: `loupe view`'s window creates its
    /// surface with it.
    pub instance: wgpu::Instance,
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
        capabilities(self.features, self.adapter.get_downlevel_capabilities().flags)
    }

    /// Everything the adapter could grant, requested or not: what `loupe
    /// check` validates arbitrary WGSL with on this machine.
    pub fn adapter_capabilities(&self) -> naga::valid::Capabilities {
        capabilities(self.adapter.features(), self.adapter.get_downlevel_capabilities().flags)
    }

    /// The granted features by their wgpu names (`TIMESTAMP_QUERY`).
    pub fn feature_names(&self) -> Vec<String> {
        feature_names(self.features)
    }
}

/// Feature names as wgpu spells its flags, in flag order.
pub fn feature_names(features: wgpu::Features) -> Vec<String> {
    features.iter_names().map(|(name, _)| name.to_owned()).collect()
}

/// The naga capabilities a device with these features and downlevel flags
/// has: wgpu's own mapping, the one it validates shader modules with.
pub fn capabilities(features: wgpu::Features, downlevel: wgpu::DownlevelFlags) -> naga::valid::Capabilities {
    wgpu_naga_bridge::features_to_naga_capabilities(features, downlevel)
}

/// Capabilities assumed when checking without a device: everything loupe
/// can request on a WebGPU-compliant adapter, so sources are judged on
/// their own and the device pass reports what a particular adapter lacks.
pub fn capabilities_without_device() -> naga::valid::Capabilities {
    let requestable = OPTIONAL_FEATURES.iter().fold(wgpu::Features::SUBGROUP_BARRIER, |all, (f, _)| all | *f);
    capabilities(requestable, wgpu::DownlevelFlags::compliant())
}

/// Gives the process a private `XDG_RUNTIME_DIR` when it has none (or a
/// relative one, which is as bad).
///
/// Why: creating a Vulkan instance runs Mesa's implicit device-select
/// layer, which connects to Wayland to find the default GPU because wgpu
/// enables `VK_KHR_wayland_surface` whenever the driver offers it
/// (wgpu-hal's `desired_extensions` has no opt-out, even for an instance
/// without a display). Without the variable, libwayland prints `error:
/// XDG_RUNTIME_DIR is invalid or not set in the environment.` on stderr
/// for every instance; with a valid directory that holds no compositor
/// socket, the connection fails quietly. Turning the layer off instead
/// (`NODEVICE_SELECT=1`) would also silence it, but would override a
/// user's `MESA_VK_DEVICE_SELECT`.
///
/// # Safety
///
/// Changes the environment: call before any other thread starts.
pub unsafe fn provide_runtime_dir() {
    let usable = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| std::path::Path::new(&d).is_absolute());
    if usable {
        return;
    }
    if let Some(dir) = private_runtime_dir() {
        // SAFETY: the caller guarantees no other thread runs yet.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", dir) };
    }
}

/// `$TMPDIR/loupe-runtime-<uid>`, created 0700, used only when it is a
/// real directory (not a link) owned by this user with mode 0700, as the
/// XDG base directory spec requires of a runtime directory.
#[cfg(unix)]
fn private_runtime_dir() -> Option<std::path::PathBuf> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt};
    // The owner of /proc/self is the process's effective user.
    let uid = std::fs::metadata("/proc/self").ok()?.uid();
    let dir = std::env::temp_dir().join(format!("loupe-runtime-{uid}"));
    match std::fs::DirBuilder::new().mode(0o700).create(&dir) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => {}
        Err(_) => return None,
    }
    let meta = std::fs::symlink_metadata(&dir).ok()?;
    (meta.is_dir() && meta.uid() == uid && meta.mode() & 0o777 == 0o700).then_some(dir)
}

#[cfg(not(unix))]
fn private_runtime_dir() -> Option<std::path::PathBuf> {
    None
}

/// Opens the best adapter: a real GPU over a CPU one. `LOUPE_ADAPTER`
/// (a substring of the adapter name) picks one explicitly.
/// The most bytes one storage buffer binding may hold on a device.
pub fn largest_binding(limits: &wgpu::Limits) -> u64 {
    limits.max_storage_buffer_binding_size.min(limits.max_buffer_size)
}

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
    Ok(Gpu { instance, adapter, device, queue, info, features, degraded, uncaptured })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn feature_names_are_wgpu_flag_names() {
        let names = feature_names(wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::SHADER_F16 | wgpu::Features::SUBGROUP);
        assert_eq!(names, ["SUBGROUP", "TIMESTAMP_QUERY", "SHADER_F16"]);
        assert!(feature_names(wgpu::Features::empty()).is_empty());
    }

    #[test]
    fn a_device_reports_its_features_by_name() {
        let gpu = open().unwrap_or_else(|e| panic!("needs a device (lavapipe will do): {e}"));
        let names = gpu.feature_names();
        assert!(!names.is_empty(), "lavapipe grants some optional features");
        let mut back = wgpu::Features::empty();
        for name in &names {
            assert!(!name.is_empty() && name.chars().all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_'), "{name:?}");
            back |= wgpu::Features::from_name(name).unwrap_or_else(|| panic!("{name} is no wgpu feature"));
        }
        assert_eq!(back, gpu.features, "the names say exactly what was granted");
    }

    #[test]
    fn capabilities_without_device_allow_what_loupe_can_request() {
        use naga::valid::Capabilities as C;
        let caps = capabilities_without_device();
        for c in
            [C::SHADER_FLOAT16, C::SUBGROUP, C::SUBGROUP_BARRIER, C::PRIMITIVE_INDEX, C::CUBE_ARRAY_TEXTURES, C::SHADER_FLOAT16_IN_FLOAT32]
        {
            assert!(caps.contains(c), "{c:?}");
        }
        for c in [C::FLOAT64, C::SHADER_INT64, C::RAY_QUERY] {
            assert!(!caps.contains(c), "{c:?} is not requested");
        }
    }

    #[test]
    fn runtime_dir_is_private() {
        use std::os::unix::fs::MetadataExt;
        let dir = private_runtime_dir().expect("a runtime directory under the temp dir");
        let meta = std::fs::symlink_metadata(&dir).unwrap();
        assert!(meta.is_dir());
        assert_eq!(meta.mode() & 0o777, 0o700);
        assert_eq!(private_runtime_dir(), Some(dir), "found again on the next start");
    }
}
