//! Uncaptured wgpu errors of a frame as diagnostics, located at the shader
//! of the pass or pipeline involved where that can be known.

use std::collections::{BTreeMap, BTreeSet};

use super::Daemon;
use crate::diag::{Code, Diagnostic, Location};
use crate::gpu::pipeline::PipelineSpec;
use crate::render::passes;
use crate::render::resource::PipelineKey;

impl Daemon {
    /// Turns the uncaptured wgpu errors of the newest frame into
    /// diagnostics, located at the shader of the pass or pipeline involved
    /// when that can be known: a resource label naming one, or — for an
    /// error that first appeared in the frame right after some pipelines
    /// were swapped in — the file of the one pipeline swapped. Otherwise
    /// the diagnostic has no file.
    pub(super) fn set_gpu_errors(&mut self, errors: &[String], swapped: &BTreeSet<PipelineKey>) {
        let mut diagnostics: Vec<Diagnostic> = Vec::new();
        let mut files_by_message = BTreeMap::new();
        for text in errors {
            let message = text.lines().map(str::trim).rfind(|l| !l.is_empty()).unwrap_or("wgpu error").to_owned();
            if files_by_message.contains_key(&message) {
                continue; // the same error, reported again at submit
            }
            let files = self
                .gpu_error_files
                .get(&message)
                .cloned()
                .or_else(|| self.files_named_in(text))
                .or_else(|| {
                    let files: BTreeSet<String> = swapped.iter().map(|k| self.session.shader_display(k.spec)).collect();
                    (self.gpu_errors.is_empty() && !files.is_empty()).then(|| files.into_iter().collect())
                })
                .unwrap_or_default();
            let mut d = Diagnostic::error(Code::Gpu, format!("the GPU rejected frame commands: {message}"))
                .with_note(format!("wgpu reported, with no error scope to catch it:\n{}", text.trim_end()))
                .with_note("the frame's images were not published: the previous image stays");
            match files.as_slice() {
                [one] => d = d.at(Location::file_start(one)),
                [] => {}
                many => d = d.with_note(format!("it began when these were swapped in: {}", many.join(", "))),
            }
            files_by_message.insert(message, files);
            diagnostics.push(d);
        }
        self.gpu_error_files = files_by_message;
        if diagnostics != self.gpu_errors {
            for d in &diagnostics {
                log::error!("frame {}: {d}", self.session.frame());
            }
            self.gpu_errors = diagnostics;
            self.publish_state();
        }
    }

    /// Shader files of the passes and pipelines an error's labels
    /// (`label = 'name'`) name, if any.
    pub(super) fn files_named_in(&self, text: &str) -> Option<Vec<String>> {
        let mut files = BTreeSet::new();
        for label in text.split("label = '").skip(1).filter_map(|rest| rest.split('\'').next()) {
            let specs: Vec<&PipelineSpec> = match self.session.graph().passes.iter().find(|p| p.name == label) {
                Some(pass) => pass.pipelines.iter().map(|k| k.spec).collect(),
                None => passes::spec(label).into_iter().collect(),
            };
            files.extend(specs.into_iter().map(|s| self.session.shader_display(s)));
        }
        (!files.is_empty()).then(|| files.into_iter().collect())
    }
}
