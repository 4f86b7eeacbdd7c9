//! One module per panel; each draws from the model (and the frame
//! texture) and reports what the user asked for, never acting on a link.

pub mod frame;
pub mod inspector;
pub mod passes;
pub mod pixel;
pub mod problems;
pub mod quad_overlay;
pub mod scene;
pub mod tensors;
pub mod timings;
pub mod zoom;
