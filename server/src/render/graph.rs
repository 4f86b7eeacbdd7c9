//! The render graph: passes declare what they read and write; the graph
//! orders them, culls every pass whose outputs the frame does not need, and
//! says why. Effects are free functions that take the builder and input
//! handles and return output handles.
//!
//! Architecture Invariant: a culled pass has no pipeline compiled for it.
//! The set of pipelines to build is derived from the live passes only.

use std::collections::BTreeSet;

use crate::gpu::pipeline::PipelineSpec;
use crate::shader::ShaderDefs;

/// A texture produced by one pass and read by others.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Handle(pub(crate) usize);

#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct TextureDesc {
    /// `pass/output`, the name captures and the UI use.
    pub name: String,
    pub format: wgpu::TextureFormat,
    pub width: u32,
    pub height: u32,
    /// Array layers (shadow maps hold one or six per light).
    pub layers: u32,
    /// Viewed as an array texture even with one layer.
    pub array: bool,
}

/// An output a pass declares: its name within the pass, format and size.
pub struct Target {
    pub output: &'static str,
    pub format: wgpu::TextureFormat,
    pub width: u32,
    pub height: u32,
    pub layers: u32,
    pub array: bool,
}

impl Target {
    pub fn new(output: &'static str, format: wgpu::TextureFormat, width: u32, height: u32) -> Self {
        Target { output, format, width, height, layers: 1, array: false }
    }

    /// An array texture of `layers` layers.
    pub fn layers(self, layers: u32) -> Self {
        Target { layers, array: true, ..self }
    }
}

/// Which pipeline a pass uses, with the defs this frame needs.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct PipelineKey {
    pub spec: &'static str,
    pub defs: ShaderDefs,
}

impl PipelineKey {
    pub fn new(spec: &PipelineSpec, defs: impl IntoIterator<Item = &'static str>) -> Self {
        PipelineKey { spec: spec.name, defs: defs.into_iter().map(str::to_owned).collect() }
    }

    pub fn label(&self) -> String {
        if self.defs.is_empty() {
            self.spec.to_owned()
        } else {
            format!("{}[{}]", self.spec, crate::shader::defs_key(&self.defs))
        }
    }
}

/// What a pass does when the frame runs: bound to its resolved inputs.
pub type Execute = Box<dyn Fn(&mut super::frame::PassContext<'_>) + Send + Sync>;

pub struct PassNode {
    pub name: String,
    pub pipelines: Vec<PipelineKey>,
    pub reads: Vec<Handle>,
    pub writes: Vec<Handle>,
    pub execute: Execute,
}

/// A pass the scene did not call for, kept so the UI can say why.
#[derive(Debug, Clone)]
pub struct CulledPass {
    pub name: String,
    pub reason: String,
}

#[derive(Default)]
pub struct GraphBuilder {
    pub(crate) textures: Vec<TextureDesc>,
    pub(crate) passes: Vec<PassNode>,
    culled: Vec<CulledPass>,
    outputs: Vec<Handle>,
}

impl GraphBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Declares a pass; its outputs are created here and returned in order.
    pub fn add_pass(
        &mut self,
        name: &str,
        pipelines: Vec<PipelineKey>,
        reads: &[Handle],
        writes: Vec<Target>,
        execute: Execute,
    ) -> Vec<Handle> {
        let handles: Vec<Handle> = writes
            .into_iter()
            .map(|t| {
                self.textures.push(TextureDesc { name: format!("{name}/{}", t.output), format: t.format, width: t.width, height: t.height, layers: t.layers, array: t.array });
                Handle(self.textures.len() - 1)
            })
            .collect();
        self.passes.push(PassNode {
            name: name.to_owned(),
            pipelines,
            reads: reads.to_vec(),
            writes: handles.clone(),
            execute,
        });
        handles
    }

    /// Records a pass the scene does not call for, without adding it.
    pub fn cull(&mut self, name: &str, reason: impl Into<String>) {
        self.culled.push(CulledPass { name: name.to_owned(), reason: reason.into() });
    }

    /// Marks what the frame must produce; everything not leading here is culled.
    pub fn output(&mut self, h: Handle) {
        self.outputs.push(h);
    }

    pub fn build(self) -> Graph {
        let mut needed: BTreeSet<Handle> = self.outputs.iter().copied().collect();
        let mut live = vec![false; self.passes.len()];
        for (i, p) in self.passes.iter().enumerate().rev() {
            if p.writes.iter().any(|w| needed.contains(w)) {
                live[i] = true;
                needed.extend(p.reads.iter().copied());
            }
        }
        let mut culled = self.culled;
        let mut passes = Vec::new();
        for (p, keep) in self.passes.into_iter().zip(live) {
            if keep {
                passes.push(p);
            } else {
                culled.push(CulledPass { name: p.name, reason: "no output of this pass is needed by the frame".into() });
            }
        }
        Graph { textures: self.textures, passes, culled, outputs: self.outputs }
    }
}

/// A built frame: live passes in execution order (declaration order, which
/// respects reads-after-writes because a handle exists only once written).
pub struct Graph {
    pub textures: Vec<TextureDesc>,
    pub passes: Vec<PassNode>,
    pub culled: Vec<CulledPass>,
    pub outputs: Vec<Handle>,
}

impl Graph {
    /// Every pipeline the live passes use.
    pub fn pipelines(&self) -> BTreeSet<PipelineKey> {
        self.passes.iter().flat_map(|p| p.pipelines.iter().cloned()).collect()
    }

    pub fn texture(&self, h: Handle) -> &TextureDesc {
        &self.textures[h.0]
    }

    /// The final image: the first declared output.
    pub fn final_output(&self) -> Option<Handle> {
        self.outputs.first().copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noop() -> Execute {
        Box::new(|_| {})
    }

    #[test]
    fn passes_whose_outputs_nobody_needs_are_culled_with_a_reason() {
        let mut g = GraphBuilder::new();
        let f = wgpu::TextureFormat::Rgba16Float;
        let a = g.add_pass("a", vec![], &[], vec![Target::new("out", f, 4, 4)], noop());
        let _unused = g.add_pass("debug", vec![], &[a[0]], vec![Target::new("out", f, 4, 4)], noop());
        let b = g.add_pass("b", vec![], &[a[0]], vec![Target::new("out", f, 4, 4)], noop());
        g.cull("volumes", "the scene has no participating media");
        g.output(b[0]);
        let graph = g.build();
        let live: Vec<_> = graph.passes.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(live, ["a", "b"]);
        let culled: Vec<_> = graph.culled.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(culled, ["volumes", "debug"]);
    }
}
