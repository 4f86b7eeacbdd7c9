//! Rendering a case's outputs headless, as `loupe render` does, on a
//! session kept across cases: scenes switch on it (`set_scene_now`, which
//! starts the frame's history over), and the pipelines they share are
//! built once.

use std::collections::BTreeSet;
use std::path::PathBuf;

use super::config::Case;
use super::report::at_case;
use crate::diag::{Code, Diagnostic, display_path};
use crate::gpu::Gpu;
use crate::offline::{frame, frames_to_finish};
use crate::render::capture::CapturedImage;
use crate::render::resource::ResourceDesc;
use crate::render::session::Session;
use crate::shader::Library;

pub struct Renderer {
    gpu: Gpu,
    shader_root: PathBuf,
    lib: Library,
    session: Option<Session>,
}

impl Renderer {
    pub fn new(gpu: Gpu, shader_root: PathBuf, lib: Library) -> Self {
        Renderer { gpu, shader_root, lib, session: None }
    }

    /// Forgets the session, after a panic left it in no known state.
    pub fn reset(&mut self) {
        self.session = None;
    }

    /// The case's outputs in its order (the final output when it names
    /// none), or why they could not be rendered, at the case's lines (an
    /// output the frame lacks at its name).
    pub fn render(&mut self, case: &Case) -> Result<Vec<CapturedImage>, Vec<Diagnostic>> {
        let in_case = |d: Diagnostic| at_case(&case.at, d);
        let scene_error = |d: Diagnostic| in_case(Diagnostic { message: format!("{}: {}", display_path(&case.scene), d.message), ..d });
        let mut loaded = crate::loaded::load_with(&case.scene, &case.overrides).map_err(|d| vec![scene_error(d)])?;
        loaded.scene.width = case.size.0;
        loaded.scene.height = case.size.1;
        let errors = match &mut self.session {
            Some(session) => session.set_scene_now(&loaded),
            None => {
                let session = self.session.insert(Session::new(self.gpu.clone(), &self.shader_root, self.lib.clone(), &loaded));
                session.install_missing()
            }
        };
        let session = self.session.as_mut().expect("made above");
        if !errors.is_empty() {
            return Err(errors.into_iter().map(in_case).collect());
        }
        let images: BTreeSet<String> = session
            .graph()
            .used()
            .into_iter()
            .map(|h| session.graph().resource(h))
            .filter(|r| matches!(r.desc, ResourceDesc::Texture(_)))
            .map(|r| r.name.clone())
            .collect();
        let wanted: Vec<String> = if case.outputs.is_empty() {
            session.graph().final_name().into_iter().collect()
        } else {
            case.outputs.iter().map(|(o, _)| o.clone()).collect()
        };
        let missing: Vec<Diagnostic> = case
            .outputs
            .iter()
            .filter(|(o, _)| !images.contains(o))
            .map(|(o, at)| {
                Diagnostic::error(Code::ProjectFile, format!("the frame of {} has no image output `{o}`", display_path(&case.scene)))
                    .with_label(at.clone(), "named here", true)
                    .with_note(format!("its image outputs: {}", images.iter().cloned().collect::<Vec<_>>().join(", ")))
            })
            .collect();
        if !missing.is_empty() {
            return Err(missing);
        }
        for _ in 1..frames_to_finish(session.scene()) {
            frame(session, Some(&BTreeSet::new()));
        }
        let mut result = frame(session, Some(&wanted.iter().cloned().collect()));
        let gpu_errors = session.take_uncaptured();
        if !gpu_errors.is_empty() {
            return Err(gpu_errors.into_iter().map(|e| in_case(Diagnostic::error(Code::Gpu, e))).collect());
        }
        wanted
            .iter()
            .map(|name| {
                let i = result.captures.iter().position(|c| c.key() == *name);
                i.map(|i| result.captures.swap_remove(i))
                    .ok_or_else(|| vec![in_case(Diagnostic::error(Code::Gpu, format!("`{name}` was not captured")))])
            })
            .collect()
    }
}
