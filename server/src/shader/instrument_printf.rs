//! Instrumenting prints: from a composed module whose sources held
//! `debugPrintf` calls (`shader::printf`), a module that writes what the
//! selected pixel's invocations print into a storage buffer.
//!
//! Done in naga's IR, in place: at each entry point's start a private flag
//! says whether this invocation is the selected one (fragment: the floor of
//! `@builtin(position).xy` is the pixel, the builtin added when the entry
//! point lacks it; compute: `global_invocation_id.xy` is the pixel; other
//! stages: never). A compute stage that does not read its global id maps
//! invocations to pixels its own way (the lighting's tile lists): its
//! invocations all print, and a second private flag says so, which a
//! function taking its pixel (an argument `pixel` or `texel` of type
//! `vec2<u32>` or `vec2<i32>`) narrows: at that function's start a local
//! flag says whether this call's argument is the pixel, so each of the
//! calls a loop makes answers for itself. Each site's marker store becomes
//!
//! ```wgsl
//! if loupe_printf_on {                            // or the function's flag
//!     let at = atomicAdd(&buf.used, n);           // n = 1 + argument words
//!     if at <= arrayLength(&buf.words) && n <= arrayLength(&buf.words) - at {
//!         buf.words[at] = site; buf.words[at + 1] = bitcast<u32>(arg0.x); …
//!     } else {
//!         atomicAdd(&buf.dropped, 1u);
//!     }
//! }
//! ```
//!
//! so a write never leaves the buffer, however often a loop prints, and
//! the records that did not fit are counted. The buffer, at
//! `@group(`[`InstrumentedPrints::group`]`) @binding(0)`, one past the
//! highest group the module binds, is
//! `struct { used: atomic<u32>, dropped: atomic<u32>, words: array<u32> }`.

use std::collections::BTreeMap;

use naga::{
    AtomicFunction, BinaryOperator, Binding, BuiltIn, Expression, Function, GlobalVariable, Handle, Literal, LocalVariable, Module,
    ResourceBinding, Scalar, ScalarKind, ShaderStage, Span, Statement, StructMember, Type, TypeInner, VectorSize,
};

use super::printf;

/// Words before the records: `used` and `dropped`.
pub const HEADER_WORDS: u64 = 2;

/// The instrumented module and how to read what it writes.
#[derive(Debug, Clone)]
pub struct InstrumentedPrints {
    pub module: Module,
    pub info: naga::valid::ModuleInfo,
    /// The group of the print buffer (binding 0).
    pub group: u32,
    /// A record starting with word `first_site + i` is from site `i`
    /// (file tag, site index in the file).
    pub sites: Vec<SiteId>,
}

#[derive(Debug, thiserror::Error)]
pub enum PrintInstrumentError {
    /// naga rejected what was generated: a bug in loupe, not in the shader.
    #[error("instrumenting prints failed inside loupe (please report): {0}")]
    Internal(String),
}

/// Whether `module` holds any print site.
pub fn has_prints(module: &Module) -> bool {
    module.functions.iter().map(|(_, f)| f).chain(module.entry_points.iter().map(|e| &e.function)).any(holds_prints)
}

fn holds_prints(f: &Function) -> bool {
    f.local_variables.iter().any(|(_, v)| v.name.as_deref().and_then(printf::parse_var).is_some())
}

/// Instruments every print of `module` for the invocation at `pixel`. The
/// buffer's group is the first past the module's groups and at least
/// `min_group`; sites are numbered from `first_site`, so several modules
/// can share one buffer.
pub fn instrument(module: &Module, pixel: [u32; 2], min_group: u32, first_site: u32) -> Result<InstrumentedPrints, PrintInstrumentError> {
    let mut m = module.clone();
    let group = m.global_variables.iter().filter_map(|(_, g)| g.binding.as_ref()).map(|b| b.group + 1).max().unwrap_or(0).max(min_group);
    let ty = Types::add(&mut m);
    let buffer = m.global_variables.append(
        GlobalVariable {
            name: Some("loupe_printf".into()),
            space: naga::AddressSpace::Storage { access: naga::StorageAccess::LOAD | naga::StorageAccess::STORE },
            binding: Some(ResourceBinding { group, binding: 0 }),
            ty: ty.buffer,
            init: None,
            memory_decorations: Default::default(),
        },
        Span::UNDEFINED,
    );
    let mut private = |name: &str| {
        m.global_variables.append(
            GlobalVariable {
                name: Some(name.into()),
                space: naga::AddressSpace::Private,
                binding: None,
                ty: ty.bool,
                init: None,
                memory_decorations: Default::default(),
            },
            Span::UNDEFINED,
        )
    };
    let (on, by_argument) = (private("loupe_printf_on"), private("loupe_printf_by_argument"));
    let globals = Globals { buffer, on, by_argument, ty };
    let mut sites = Sites { first: first_site, ..Sites::default() };
    let Module { types, functions, entry_points, .. } = &mut m;
    for (_, f) in functions.iter_mut() {
        let gate = match pixel_argument(types, f) {
            Some(arg) if holds_prints(f) => Expression::LocalVariable(pixel_gate(f, &globals, arg, pixel)),
            _ => Expression::GlobalVariable(on),
        };
        rewrite_sites(types, f, &globals, &mut sites, &gate);
    }
    for ep in entry_points.iter_mut() {
        rewrite_sites(types, &mut ep.function, &globals, &mut sites, &Expression::GlobalVariable(on));
    }
    for ep in entry_points {
        select(types, ep.stage, &mut ep.function, &globals, pixel);
    }
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&m)
        .map_err(|e| PrintInstrumentError::Internal(e.emit_to_string("")))?;
    Ok(InstrumentedPrints { module: m, info, group, sites: sites.order })
}

#[derive(Clone, Copy)]
struct Types {
    u32: Handle<Type>,
    bool: Handle<Type>,
    buffer: Handle<Type>,
}

impl Types {
    fn add(m: &mut Module) -> Types {
        let mut ty = |inner: TypeInner, name: Option<&str>| m.types.insert(Type { name: name.map(Into::into), inner }, Span::UNDEFINED);
        let u32 = ty(TypeInner::Scalar(Scalar::U32), None);
        let bool = ty(TypeInner::Scalar(Scalar::BOOL), None);
        let atomic = ty(TypeInner::Atomic(Scalar::U32), None);
        let words = ty(TypeInner::Array { base: u32, size: naga::ArraySize::Dynamic, stride: 4 }, None);
        let member = |name: &str, ty, offset| StructMember { name: Some(name.into()), ty, binding: None, offset };
        let buffer = ty(
            TypeInner::Struct {
                members: vec![member("used", atomic, 0), member("dropped", atomic, 4), member("words", words, 8)],
                span: 12,
            },
            Some("LoupePrintf"),
        );
        Types { u32, bool, buffer }
    }
}

struct Globals {
    buffer: Handle<GlobalVariable>,
    /// Whether this invocation prints.
    on: Handle<GlobalVariable>,
    /// Whether the stage prints from every invocation, for functions that
    /// take their pixel to narrow.
    by_argument: Handle<GlobalVariable>,
    ty: Types,
}

/// A site: its file's tag and its index in the file.
pub type SiteId = (u32, usize);

/// A site's argument locals, with their argument index.
type SiteArgs = Vec<(usize, Handle<LocalVariable>)>;

/// The sites met so far, numbered in the order met.
#[derive(Default)]
struct Sites {
    first: u32,
    order: Vec<SiteId>,
    index: BTreeMap<SiteId, u32>,
}

impl Sites {
    fn number(&mut self, site: SiteId) -> u32 {
        *self.index.entry(site).or_insert_with(|| {
            self.order.push(site);
            self.first + self.order.len() as u32 - 1
        })
    }
}

/// Appends expressions to a function, each emitted where it is used.
struct Exprs<'a> {
    f: &'a mut Function,
}

impl Exprs<'_> {
    /// An expression that needs no emitting (literals, variables).
    fn plain(&mut self, e: Expression) -> Handle<Expression> {
        self.f.expressions.append(e, Span::UNDEFINED)
    }

    fn emit(&mut self, out: &mut Vec<Statement>, e: Expression) -> Handle<Expression> {
        let h = self.f.expressions.append(e, Span::UNDEFINED);
        out.push(Statement::Emit(naga::Range::new_from_bounds(h, h)));
        h
    }

    fn u32(&mut self, v: u32) -> Handle<Expression> {
        self.plain(Expression::Literal(Literal::U32(v)))
    }

    fn binary(
        &mut self,
        out: &mut Vec<Statement>,
        op: BinaryOperator,
        left: Handle<Expression>,
        right: Handle<Expression>,
    ) -> Handle<Expression> {
        self.emit(out, Expression::Binary { op, left, right })
    }
}

/// Replaces each marker store of `f` with the write of its record, made
/// when the bool `gate` points at (a variable) holds.
fn rewrite_sites(types: &naga::UniqueArena<Type>, f: &mut Function, g: &Globals, sites: &mut Sites, gate: &Expression) {
    let mut args: BTreeMap<SiteId, SiteArgs> = BTreeMap::new();
    let mut markers: BTreeMap<Handle<LocalVariable>, SiteId> = BTreeMap::new();
    for (h, v) in f.local_variables.iter() {
        match v.name.as_deref().and_then(printf::parse_var) {
            Some((tag, k, Some(i))) => args.entry((tag, k)).or_default().push((i, h)),
            Some((tag, k, None)) => {
                markers.insert(h, (tag, k));
            }
            None => {}
        }
    }
    if markers.is_empty() {
        return;
    }
    let mut body = std::mem::take(&mut f.body);
    let mut exprs = Exprs { f };
    walk(
        &mut body,
        &mut |stmt, exprs| {
            let Statement::Store { pointer, value } = *stmt else { return };
            let Expression::LocalVariable(var) = exprs.f.expressions[pointer] else { return };
            if exprs.f.expressions[value] != Expression::Literal(Literal::U32(printf::MARK)) {
                return;
            }
            let Some(&site) = markers.get(&var) else { return };
            let mut site_args = args.get(&site).cloned().unwrap_or_default();
            site_args.sort_unstable();
            let number = sites.number(site);
            *stmt = Statement::Block(naga::Block::from_vec(record(exprs, types, g, gate, number, &site_args)));
        },
        &mut exprs,
    );
    f.body = body;
}

/// Calls `visit` on every statement of `block`, nested ones included.
fn walk(block: &mut naga::Block, visit: &mut impl FnMut(&mut Statement, &mut Exprs<'_>), exprs: &mut Exprs<'_>) {
    for (stmt, _) in block.span_iter_mut() {
        match stmt {
            Statement::Block(b) => walk(b, visit, exprs),
            Statement::If { accept, reject, .. } => {
                walk(accept, visit, exprs);
                walk(reject, visit, exprs);
            }
            Statement::Switch { cases, .. } => cases.iter_mut().for_each(|c| walk(&mut c.body, visit, exprs)),
            Statement::Loop { body, continuing, .. } => {
                walk(body, visit, exprs);
                walk(continuing, visit, exprs);
            }
            _ => visit(stmt, exprs),
        }
    }
}

/// The statements that append one record (see the module docs).
fn record(
    x: &mut Exprs<'_>,
    types: &naga::UniqueArena<Type>,
    g: &Globals,
    gate: &Expression,
    site: u32,
    args: &[(usize, Handle<LocalVariable>)],
) -> Vec<Statement> {
    let mut out = Vec::new();
    let gate = x.plain(gate.clone());
    let selected = x.emit(&mut out, Expression::Load { pointer: gate });
    let mut accept = Vec::new();
    // The words: the site, then each argument's components as u32.
    let mut words = vec![x.u32(site)];
    let (zero, one) = (x.u32(0), x.u32(1));
    let mut values = Vec::new();
    for &(_, var) in args {
        let ptr = x.plain(Expression::LocalVariable(var));
        let ty = x.f.local_variables[var].ty;
        values.push((ptr, ty));
    }
    let buffer = x.plain(Expression::GlobalVariable(g.buffer));
    let mut loaded = Vec::new();
    for (ptr, _) in &values {
        loaded.push(x.emit(&mut accept, Expression::Load { pointer: *ptr }));
    }
    let mut writes = Vec::new();
    for ((_, ty), value) in values.iter().zip(&loaded) {
        let Some((kind, components)) = printf::printable(&types[*ty].inner) else { continue };
        for c in 0..components {
            let comp =
                if components == 1 { *value } else { x.emit(&mut writes, Expression::AccessIndex { base: *value, index: c.into() }) };
            let word = match kind {
                ScalarKind::Uint => comp,
                ScalarKind::Bool => x.emit(&mut writes, Expression::Select { condition: comp, accept: one, reject: zero }),
                _ => x.emit(&mut writes, Expression::As { expr: comp, kind: ScalarKind::Uint, convert: None }),
            };
            words.push(word);
        }
    }
    let n = x.u32(words.len() as u32);
    let used = x.emit(&mut accept, Expression::AccessIndex { base: buffer, index: 0 });
    let at = x.plain(Expression::AtomicResult { ty: g.ty.u32, comparison: false });
    accept.push(Statement::Atomic { pointer: used, fun: AtomicFunction::Add, value: n, result: Some(at) });
    let store = x.emit(&mut accept, Expression::AccessIndex { base: buffer, index: 2 });
    let len = x.emit(&mut accept, Expression::ArrayLength(store));
    let starts_inside = x.binary(&mut accept, BinaryOperator::LessEqual, at, len);
    let room = x.binary(&mut accept, BinaryOperator::Subtract, len, at);
    let fits = x.binary(&mut accept, BinaryOperator::LessEqual, n, room);
    let ok = x.binary(&mut accept, BinaryOperator::LogicalAnd, starts_inside, fits);
    for (j, word) in words.into_iter().enumerate() {
        let offset = x.u32(j as u32);
        let index = x.binary(&mut writes, BinaryOperator::Add, at, offset);
        let pointer = x.emit(&mut writes, Expression::Access { base: store, index });
        writes.push(Statement::Store { pointer, value: word });
    }
    let mut dropped = Vec::new();
    let counter = x.emit(&mut dropped, Expression::AccessIndex { base: buffer, index: 1 });
    dropped.push(Statement::Atomic { pointer: counter, fun: AtomicFunction::Add, value: one, result: None });
    accept.push(Statement::If { condition: ok, accept: naga::Block::from_vec(writes), reject: naga::Block::from_vec(dropped) });
    out.push(Statement::If { condition: selected, accept: naga::Block::from_vec(accept), reject: naga::Block::new() });
    out
}

/// Sets the private flag at the start of entry point `f`.
fn select(types: &mut naga::UniqueArena<Type>, stage: ShaderStage, f: &mut Function, g: &Globals, pixel: [u32; 2]) {
    let (builtin, ty) = match stage {
        ShaderStage::Fragment => {
            (BuiltIn::Position { invariant: false }, TypeInner::Vector { size: VectorSize::Quad, scalar: Scalar::F32 })
        }
        ShaderStage::Compute => (BuiltIn::GlobalInvocationId, TypeInner::Vector { size: VectorSize::Tri, scalar: Scalar::U32 }),
        _ => return,
    };
    let is = |b: Option<&Binding>| matches!(b, Some(Binding::BuiltIn(x)) if std::mem::discriminant(x) == std::mem::discriminant(&builtin));
    let mut found = None;
    for (i, a) in f.arguments.iter().enumerate() {
        if is(a.binding.as_ref()) {
            found = Some((i, None));
        } else if let TypeInner::Struct { members, .. } = &types[a.ty].inner
            && let Some(m) = members.iter().position(|m| is(m.binding.as_ref()))
        {
            found = Some((i, Some(m as u32)));
        }
    }
    // A compute stage that does not read its global id maps invocations
    // to pixels some other way (the lighting's tile lists): every
    // invocation prints, into the same bounded buffer, but for what the
    // functions that take their pixel narrow (`pixel_gate`).
    if found.is_none() && stage == ShaderStage::Compute {
        let mut x = Exprs { f };
        let yes = x.plain(Expression::Literal(Literal::Bool(true)));
        let stores = [g.on, g.by_argument].map(|v| Statement::Store { pointer: x.plain(Expression::GlobalVariable(v)), value: yes });
        prepend(x.f, stores.into());
        return;
    }
    let (arg, member) = found.unwrap_or_else(|| {
        let ty = types.insert(Type { name: None, inner: ty }, Span::UNDEFINED);
        f.arguments.push(naga::FunctionArgument { name: Some("loupe_printf_at".into()), ty, binding: Some(Binding::BuiltIn(builtin)) });
        (f.arguments.len() - 1, None)
    });
    let mut x = Exprs { f };
    let mut out = Vec::new();
    let (px, py) = (x.u32(pixel[0]), x.u32(pixel[1]));
    let on = x.plain(Expression::GlobalVariable(g.on));
    let mut at = x.plain(Expression::FunctionArgument(arg as u32));
    if let Some(m) = member {
        at = x.emit(&mut out, Expression::AccessIndex { base: at, index: m });
    }
    let coordinate = |x: &mut Exprs<'_>, out: &mut Vec<Statement>, c: u32| {
        let v = x.emit(out, Expression::AccessIndex { base: at, index: c });
        match stage {
            ShaderStage::Fragment => x.emit(out, Expression::As { expr: v, kind: ScalarKind::Uint, convert: Some(4) }),
            _ => v,
        }
    };
    let (cx, cy) = (coordinate(&mut x, &mut out, 0), coordinate(&mut x, &mut out, 1));
    let ex = x.binary(&mut out, BinaryOperator::Equal, cx, px);
    let ey = x.binary(&mut out, BinaryOperator::Equal, cy, py);
    let both = x.binary(&mut out, BinaryOperator::LogicalAnd, ex, ey);
    out.push(Statement::Store { pointer: on, value: both });
    prepend(x.f, out);
}

/// Names an argument may have that says which pixel its function works
/// on (the lighting's `shade_at(pixel, …)` and `shade(texel)`).
const PIXEL_ARGUMENTS: [&str; 2] = ["pixel", "texel"];

/// The index of `f`'s argument that is its pixel: named as
/// [`PIXEL_ARGUMENTS`] say, of type `vec2<u32>` or `vec2<i32>`.
fn pixel_argument(types: &naga::UniqueArena<Type>, f: &Function) -> Option<u32> {
    let is_pixel = |a: &naga::FunctionArgument| {
        a.name.as_deref().is_some_and(|n| PIXEL_ARGUMENTS.contains(&n))
            && matches!(types[a.ty].inner, TypeInner::Vector { size: VectorSize::Bi, scalar: Scalar::U32 | Scalar::I32 })
    };
    f.arguments.iter().position(is_pixel).map(|i| i as u32)
}

/// A local flag set at the start of `f`: whether this call prints, which
/// is the stage's flag, narrowed to calls whose argument `arg` is `pixel`
/// where the stage prints from every invocation:
/// `on && (!by_argument || all(bitcast<vec2<u32>>(arg) == pixel))`.
fn pixel_gate(f: &mut Function, g: &Globals, arg: u32, pixel: [u32; 2]) -> Handle<LocalVariable> {
    let here =
        f.local_variables.append(LocalVariable { name: Some("loupe_printf_here".into()), ty: g.ty.bool, init: None }, Span::UNDEFINED);
    let mut x = Exprs { f };
    let mut out = Vec::new();
    let value = x.plain(Expression::FunctionArgument(arg));
    let mut same = Vec::new();
    for (c, want) in pixel.into_iter().enumerate() {
        let component = x.emit(&mut out, Expression::AccessIndex { base: value, index: c as u32 });
        // An `i32` argument compares by its bits: a negative one is past
        // any pixel.
        let component = x.emit(&mut out, Expression::As { expr: component, kind: ScalarKind::Uint, convert: None });
        let want = x.u32(want);
        same.push(x.binary(&mut out, BinaryOperator::Equal, component, want));
    }
    let is_pixel = x.binary(&mut out, BinaryOperator::LogicalAnd, same[0], same[1]);
    let [on, by_argument] = [g.on, g.by_argument].map(|v| {
        let pointer = x.plain(Expression::GlobalVariable(v));
        x.emit(&mut out, Expression::Load { pointer })
    });
    let by_invocation = x.emit(&mut out, Expression::Unary { op: naga::UnaryOperator::LogicalNot, expr: by_argument });
    let narrowed = x.binary(&mut out, BinaryOperator::LogicalOr, by_invocation, is_pixel);
    let prints = x.binary(&mut out, BinaryOperator::LogicalAnd, on, narrowed);
    let pointer = x.plain(Expression::LocalVariable(here));
    out.push(Statement::Store { pointer, value: prints });
    prepend(x.f, out);
    here
}

/// Puts `statements` before the rest of `f`'s body.
fn prepend(f: &mut Function, statements: Vec<Statement>) {
    let mut body = naga::Block::from_vec(statements);
    body.append(&mut f.body);
    f.body = body;
}

#[cfg(test)]
mod tests;
