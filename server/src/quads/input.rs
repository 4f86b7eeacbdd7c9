//! What one draw hands the model: its post-vertex-stage positions and the
//! fixed-function state that decides coverage, mirroring wgpu's
//! `PrimitiveState`, `Viewport`, scissor rect and `DepthStencilState`
//! without depending on wgpu. Also the checks on that state: the same
//! limits WebGPU validates, so the model never sees a draw a GPU refuses.

/// The largest target side the model accepts: keeps every snapped
/// coordinate and edge function exactly representable (see `clip`).
pub const MAX_TARGET_SIZE: u32 = 1 << 15;

/// How much two depths may differ and still compare as equal, in depth
/// units: 2^-20, 16 steps of a 24-bit buffer and 16 ULPs of an f32 just
/// below 1.0. The GPU interpolates depth in f32 from its own setup, so its
/// values differ from this model's f64 plane by a few ULPs; a pass that
/// tests `Equal` or `LessEqual` against a depth prepass of the same
/// geometry must still pass, while surfaces 2^-20 apart (a millionth of
/// the depth range) are closer than any scene separates on purpose.
pub const DEPTH_TOLERANCE: f32 = 1.0 / (1 << 20) as f32;

/// One draw: triangles of a triangle list and the state they are drawn with.
/// `Default` is an empty, sequential draw over the whole target, culling
/// nothing, without a depth test.
#[derive(Debug, Clone, Default)]
pub struct Draw<'a> {
    /// Clip-space positions (x, y, z, w) the vertex stage wrote, one per vertex.
    pub positions: &'a [[f32; 4]],
    /// Indices into `positions`, three per triangle; `None` draws the
    /// positions in order. A last incomplete triangle is ignored, as GPUs do.
    pub indices: Option<&'a [u32]>,
    /// wgpu's `PrimitiveState::cull_mode`.
    pub cull: Option<Face>,
    /// wgpu's `PrimitiveState::front_face`.
    pub front_face: FrontFace,
    /// `None`: the whole target, depth 0 to 1 (wgpu's default).
    pub viewport: Option<Viewport>,
    pub scissor: Option<Scissor>,
    /// `None`: the pipeline does not test depth.
    pub depth: Option<DepthState>,
}

/// The face a pipeline culls (wgpu's `Face`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Face {
    Front,
    Back,
}

/// Which winding faces the viewer (wgpu's `FrontFace`): counter-clockwise
/// or clockwise as seen on screen, i.e. in NDC with y up.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrontFace {
    #[default]
    Ccw,
    Cw,
}

/// wgpu's `RenderPass::set_viewport`, in pixels of the target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Viewport {
    pub x: f32,
    pub y: f32,
    pub width: f32,
    pub height: f32,
    pub min_depth: f32,
    pub max_depth: f32,
}

/// wgpu's `RenderPass::set_scissor_rect`, in pixels of the target.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Scissor {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

/// wgpu's `CompareFunction`: `Less` passes when the fragment's depth is
/// less than the stored one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Compare {
    Never,
    Less,
    Equal,
    LessEqual,
    Greater,
    NotEqual,
    GreaterEqual,
    Always,
}

/// The depth test of a pipeline that has one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DepthState {
    pub compare: Compare,
    /// wgpu's `depth_write_enabled`.
    pub write: bool,
    pub bias: DepthBias,
    /// Depths closer than this compare as equal; `DEPTH_TOLERANCE` unless set.
    pub tolerance: f32,
}

impl DepthState {
    pub fn new(compare: Compare, write: bool) -> DepthState {
        DepthState { compare, write, bias: DepthBias::default(), tolerance: DEPTH_TOLERANCE }
    }
}

/// wgpu's `DepthBiasState`, applied as WebGPU specifies it for a
/// `Depth32Float` buffer (loupe's only depth format): `constant` units of
/// 2^(e - 23), e the exponent of the primitive's largest depth, plus
/// `slope_scale` times its largest depth slope per pixel, clamped to `clamp`
/// when that is not 0.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DepthBias {
    pub constant: i32,
    pub slope_scale: f32,
    pub clamp: f32,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum QuadError {
    #[error("a {width}x{height} target: each side must be 1 to {MAX_TARGET_SIZE} pixels")]
    TargetSize { width: u32, height: u32 },
    #[error("the depth buffer holds {got} values; a {width}x{height} target needs {}", *width as u64 * *height as u64)]
    DepthSize { got: usize, width: u32, height: u32 },
    #[error("the depth buffer's value at pixel ({x}, {y}) is {value}, not a finite depth")]
    DepthValue { x: u32, y: u32, value: f32 },
    #[error("the draw tests depth but the pass has no depth buffer")]
    NoDepthBuffer,
    #[error("index {value} (at {at}) is past the draw's {vertices} positions")]
    Index { at: usize, value: u32, vertices: usize },
    #[error("viewport {0:?} is not a rectangle inside the {1}x{2} target with 0 <= min_depth <= max_depth <= 1")]
    Viewport(Viewport, u32, u32),
    #[error("scissor {0:?} is not inside the {1}x{2} target")]
    Scissor(Scissor, u32, u32),
    #[error("pixel ({x}, {y}) is outside the {width}x{height} target")]
    Pixel { x: u32, y: u32, width: u32, height: u32 },
    #[error("depth state {0:?}: tolerance must be finite and at least 0, slope_scale and clamp finite")]
    DepthState(DepthState),
}

impl Draw<'_> {
    /// How many triangles the draw has, once its indices are checked.
    pub(super) fn triangles(&self) -> Result<usize, QuadError> {
        let triangles = self.indices.map_or(self.positions.len(), <[u32]>::len) / 3;
        let vertices = self.positions.len();
        let indices = self.indices.unwrap_or_default();
        match indices.iter().take(3 * triangles).position(|&i| i as usize >= vertices) {
            Some(at) => Err(QuadError::Index { at, value: indices[at], vertices }),
            None => Ok(triangles),
        }
    }
}

impl Viewport {
    /// wgpu's default: the whole target, depth 0 to 1.
    pub fn whole(width: u32, height: u32) -> Viewport {
        Viewport { x: 0.0, y: 0.0, width: width as f32, height: height as f32, min_depth: 0.0, max_depth: 1.0 }
    }

    pub(super) fn check(&self, width: u32, height: u32) -> Result<(), QuadError> {
        let v = [self.x, self.y, self.width, self.height, self.min_depth, self.max_depth].map(f64::from);
        let [x, y, w, h, near, far] = v;
        let inside = v.iter().all(|c| c.is_finite())
            && x >= 0.0
            && y >= 0.0
            && w >= 0.0
            && h >= 0.0
            && x + w <= f64::from(width)
            && y + h <= f64::from(height)
            && 0.0 <= near
            && near <= far
            && far <= 1.0;
        if inside { Ok(()) } else { Err(QuadError::Viewport(*self, width, height)) }
    }
}

impl Scissor {
    pub(super) fn check(&self, width: u32, height: u32) -> Result<(), QuadError> {
        let fits = |at: u32, size: u32, side: u32| u64::from(at) + u64::from(size) <= u64::from(side);
        if fits(self.x, self.width, width) && fits(self.y, self.height, height) {
            Ok(())
        } else {
            Err(QuadError::Scissor(*self, width, height))
        }
    }
}

impl DepthState {
    pub(super) fn check(&self) -> Result<(), QuadError> {
        let ok = self.tolerance.is_finite() && self.tolerance >= 0.0 && self.bias.slope_scale.is_finite() && self.bias.clamp.is_finite();
        if ok { Ok(()) } else { Err(QuadError::DepthState(*self)) }
    }
}
