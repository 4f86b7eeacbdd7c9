//! The render graph: passes declare the resources they create, read and
//! write, and how (`Access`); the graph orders them, derives every
//! resource's usage flags, culls every pass whose outputs the frame does
//! not need, and says why. Effects are free functions that take the
//! builder and input handles and return output handles
//! (`render::passes`), raster, compute and copy passes alike.
//!
//! Architecture Invariant: a culled pass has no pipeline compiled for it.
//! The set of pipelines to build is derived from the live passes only.

use std::collections::BTreeSet;

use super::context::PassContext;
use super::resource::{Access, Handle, Lifetime, Meaning, PipelineKey, ResourceDesc};

/// What a pass does when the frame runs: bound to its resolved inputs.
pub type Execute = Box<dyn Fn(&mut PassContext<'_>) + Send + Sync>;

/// What kind of GPU work a pass records; every kind gets timestamps.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PassKind {
    Raster,
    Compute,
    Copy,
}

/// A resource as the graph knows it.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct Resource {
    /// `pass/output`, the name captures and the UI use.
    pub name: String,
    pub desc: ResourceDesc,
    /// What its values mean, as the pass that creates it declares.
    pub meaning: Meaning,
    pub lifetime: Lifetime,
    /// Derived from every access passes declare (plus COPY_SRC, so any
    /// resource can be captured, and for a texture TEXTURE_BINDING, so
    /// `loupe view`'s display pass can draw it).
    pub texture_usage: wgpu::TextureUsages,
    pub buffer_usage: wgpu::BufferUsages,
}

impl Resource {
    /// The part of the name after the pass: `color` of `lighting/color`.
    pub fn output(&self) -> &str {
        self.name.rsplit('/').next().unwrap_or(&self.name)
    }
}

pub struct PassNode {
    pub name: String,
    pub kind: PassKind,
    pub pipelines: Vec<PipelineKey>,
    pub accesses: Vec<(Handle, Access)>,
    /// A compute pass whose invocation with global id (x, y, 0) writes
    /// pixel (x, y) of its outputs: pixel history names that invocation.
    pub per_pixel: bool,
    pub execute: Execute,
}

impl PassNode {
    pub fn reads(&self) -> impl Iterator<Item = Handle> + '_ {
        let mut seen = BTreeSet::new();
        self.accesses.iter().filter(|(_, a)| !a.writes()).map(|(h, _)| *h).filter(move |h| seen.insert(*h))
    }

    pub fn writes(&self) -> impl Iterator<Item = Handle> + '_ {
        let mut seen = BTreeSet::new();
        self.accesses.iter().filter(|(_, a)| a.writes()).map(|(h, _)| *h).filter(move |h| seen.insert(*h))
    }
}

/// A pass the scene did not call for, kept so the UI can say why.
#[derive(Debug, Clone)]
pub struct CulledPass {
    pub name: String,
    pub reason: String,
}

#[derive(Default)]
pub struct GraphBuilder {
    resources: Vec<Resource>,
    passes: Vec<PassNode>,
    culled: Vec<CulledPass>,
    outputs: Vec<Handle>,
}

/// One pass being declared: what it uses, then `execute`.
pub struct PassBuilder<'g> {
    graph: &'g mut GraphBuilder,
    node: PassNode,
}

impl PassBuilder<'_> {
    /// The pipeline this pass uses (a pass may use several).
    pub fn pipeline(&mut self, key: PipelineKey) -> PipelineKey {
        self.node.pipelines.push(key.clone());
        key
    }

    /// Uses an existing resource as `access` says.
    pub fn access(&mut self, h: Handle, access: Access) -> Handle {
        self.node.accesses.push((h, access));
        h
    }

    /// A texture read in the shader.
    pub fn sample(&mut self, h: Handle) -> Handle {
        self.access(h, Access::Sampled)
    }

    /// A new resource of this frame, named `pass/output`, holding values
    /// that mean `meaning`, first used as `access`.
    pub fn create(&mut self, output: &str, meaning: Meaning, desc: impl Into<ResourceDesc>, access: Access) -> Handle {
        let h = self.graph.resource(&self.node.name, output, meaning, desc.into(), Lifetime::Frame);
        self.access(h, access)
    }

    /// A resource kept across frames under `pass/output`: this frame sees
    /// what the last one left (zeros when new or reset).
    pub fn history(&mut self, output: &str, meaning: Meaning, desc: impl Into<ResourceDesc>, access: Access) -> Handle {
        let h = self.graph.resource(&self.node.name, output, meaning, desc.into(), Lifetime::History);
        self.access(h, access)
    }

    /// Declares that the pass dispatches one invocation per pixel of its
    /// outputs, its global id the pixel.
    pub fn one_invocation_per_pixel(&mut self) {
        self.node.per_pixel = true;
    }

    /// Finishes the declaration with what the pass records when it runs.
    pub fn execute(self, f: impl Fn(&mut PassContext<'_>) + Send + Sync + 'static) {
        let PassBuilder { graph, mut node } = self;
        node.execute = Box::new(f);
        graph.passes.push(node);
    }
}

impl GraphBuilder {
    pub fn new() -> Self {
        Self::default()
    }

    /// Starts declaring pass `name`.
    pub fn pass(&mut self, name: &str, kind: PassKind) -> PassBuilder<'_> {
        let node = PassNode {
            name: name.to_owned(),
            kind,
            pipelines: Vec::new(),
            accesses: Vec::new(),
            per_pixel: false,
            execute: Box::new(|_| {}),
        };
        PassBuilder { graph: self, node }
    }

    fn resource(&mut self, pass: &str, output: &str, meaning: Meaning, desc: ResourceDesc, lifetime: Lifetime) -> Handle {
        self.resources.push(Resource {
            name: format!("{pass}/{output}"),
            desc,
            meaning,
            lifetime,
            texture_usage: wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING,
            buffer_usage: wgpu::BufferUsages::COPY_SRC,
        });
        Handle(self.resources.len() - 1)
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
            if p.writes().any(|w| needed.contains(&w)) {
                live[i] = true;
                needed.extend(p.reads());
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
        let mut resources = self.resources;
        for p in &passes {
            for (h, a) in &p.accesses {
                let r = &mut resources[h.0];
                r.texture_usage |= a.texture_usage();
                r.buffer_usage |= a.buffer_usage();
            }
        }
        Graph { resources, passes, culled, outputs: self.outputs }
    }
}

/// A built frame: live passes in execution order (declaration order, which
/// respects reads-after-writes because a handle exists only once created).
pub struct Graph {
    pub resources: Vec<Resource>,
    pub passes: Vec<PassNode>,
    pub culled: Vec<CulledPass>,
    pub outputs: Vec<Handle>,
}

impl Graph {
    /// Every pipeline the live passes use.
    pub fn pipelines(&self) -> BTreeSet<PipelineKey> {
        self.passes.iter().flat_map(|p| p.pipelines.iter().cloned()).collect()
    }

    pub fn resource(&self, h: Handle) -> &Resource {
        &self.resources[h.0]
    }

    /// Resources some live pass uses: only these are allocated.
    pub fn used(&self) -> BTreeSet<Handle> {
        self.passes.iter().flat_map(|p| p.accesses.iter().map(|(h, _)| *h)).collect()
    }

    /// The final image: the first declared output.
    pub fn final_output(&self) -> Option<Handle> {
        self.outputs.first().copied()
    }

    /// `pass/output` of the final image.
    pub fn final_name(&self) -> Option<String> {
        self.final_output().map(|h| self.resource(h).name.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::resource::{Element, TensorLayout, TextureDesc};

    #[test]
    fn passes_whose_outputs_nobody_needs_are_culled_with_a_reason() {
        let mut g = GraphBuilder::new();
        let d = TextureDesc::d2(wgpu::TextureFormat::Rgba16Float, 4, 4);
        let mut p = g.pass("a", PassKind::Raster);
        let a = p.create("out", Meaning::Color, d.clone(), Access::ColorTarget);
        p.execute(|_| {});
        let mut p = g.pass("debug", PassKind::Raster);
        p.sample(a);
        p.create("out", Meaning::Color, d.clone(), Access::ColorTarget);
        p.execute(|_| {});
        let mut p = g.pass("b", PassKind::Raster);
        p.sample(a);
        let b = p.create("out", Meaning::Color, d, Access::ColorTarget);
        p.execute(|_| {});
        g.cull("volumes", "the scene has no participating media");
        g.output(b);
        let graph = g.build();
        let live: Vec<_> = graph.passes.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(live, ["a", "b"]);
        let culled: Vec<_> = graph.culled.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(culled, ["volumes", "debug"]);
    }

    #[test]
    fn usage_is_derived_from_the_live_passes_accesses() {
        let mut g = GraphBuilder::new();
        let d = TextureDesc::d2(wgpu::TextureFormat::Rgba16Float, 4, 4);
        let mut p = g.pass("render", PassKind::Raster);
        let color = p.create("color", Meaning::Color, d, Access::ColorTarget);
        p.execute(|_| {});
        let mut p = g.pass("reduce", PassKind::Compute);
        p.sample(color);
        let sum = p.create("sum", Meaning::Data, TensorLayout::new(&[("bin", 8)], Element::U32), Access::StorageWrite);
        p.execute(|_| {});
        // Indirect dispatch arguments: INDIRECT as well.
        let mut p = g.pass("dispatch", PassKind::Compute);
        p.access(sum, Access::Indirect);
        p.access(sum, Access::StorageWrite);
        p.execute(|_| {});
        let mut p = g.pass("state", PassKind::Compute);
        p.access(sum, Access::StorageRead);
        let state = p.history("state", Meaning::Data, TensorLayout::new(&[("v", 4)], Element::F32), Access::StorageWrite);
        p.execute(|_| {});
        // A pass nobody needs adds no usage.
        let mut p = g.pass("unused", PassKind::Copy);
        p.access(color, Access::CopySrc);
        p.create("copy", Meaning::Color, TextureDesc::d2(wgpu::TextureFormat::Rgba16Float, 4, 4), Access::CopyDst);
        p.execute(|_| {});
        g.output(state);
        let graph = g.build();
        use wgpu::{BufferUsages as B, TextureUsages as T};
        assert_eq!(graph.resource(color).texture_usage, T::RENDER_ATTACHMENT | T::TEXTURE_BINDING | T::COPY_SRC);
        assert_eq!(graph.resource(sum).buffer_usage, B::STORAGE | B::INDIRECT | B::COPY_SRC);
        assert_eq!(graph.resource(state).lifetime, Lifetime::History);
        assert_eq!(graph.passes.iter().map(|p| p.name.as_str()).collect::<Vec<_>>(), ["render", "reduce", "dispatch", "state"]);
    }
}
