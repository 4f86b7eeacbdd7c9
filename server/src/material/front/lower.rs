//! From the syntax trees of a material file and its imports to one
//! `Definition` per material of the root file: names resolved, types
//! checked, `let`s and `fn` calls inlined, a material of another file called
//! with named arguments inlined with those parameters replaced (the others
//! are their defaults, as constants). Every error is located; lowering goes
//! on after one where it can (a poisoned value, `Val::Error`, silences the
//! errors that would follow from it).

use std::collections::BTreeMap;

use super::ast::{self, Ident, Span, TypeName};
use super::imports::Unit;
use crate::diag::{Code, Diagnostic, Location};
use crate::material::analysis::{channels as components, constant};
use crate::material::tree::*;

/// How deep `fn` and material calls may inline into each other.
const MAX_INLINE_DEPTH: usize = 64;
/// How many nodes and expressions one material may lower to: calls inline,
/// so a few lines calling each other twice can ask for millions.
const MAX_SIZE: usize = 1 << 16;

const OPERATORS: [&str; 4] = ["mix", "layer", "coverage", "add"];

pub struct Lowered {
    pub definitions: Vec<Definition>,
    /// The images texture params name (`Value::Texture` indexes it).
    pub textures: Vec<TextureSource>,
    pub errors: Vec<Diagnostic>,
    pub warnings: Vec<Diagnostic>,
}

pub fn lower(units: &[Unit]) -> Lowered {
    let mut errors = Vec::new();
    let mut textures = Vec::new();
    let params: Vec<Vec<ParamInfo>> = (0..units.len()).map(|u| declared_params(units, u, &mut textures, &mut errors)).collect();
    for u in units {
        check_names(u, &mut errors);
    }
    let mut definitions = Vec::new();
    let mut used = vec![false; params[0].len()];
    for m in &units[0].ast.materials {
        let mut l = Lowerer::new(units, &params);
        let scope = Scope { unit: 0, env: Env::Symbolic, locals: Vec::new() };
        let value = l.material_body(&scope, m, &m.name.span);
        let ok = l.errors.is_empty();
        errors.append(&mut l.errors);
        if let (true, Val::Slab(root)) = (ok, value) {
            let def = l.finish(&m.name, root);
            for p in &def.params {
                if let Some(i) = params[0].iter().position(|q| q.name == p.name) {
                    used[i] = true;
                }
            }
            definitions.push(def);
        }
    }
    let mut warnings = Vec::new();
    if errors.is_empty() {
        for (p, _) in params[0].iter().zip(&used).filter(|(_, u)| !**u) {
            warnings.push(Diagnostic::warning(Code::Material, format!("param `{}` is used by no material", p.name)).with_label(
                p.location.clone(),
                "unused",
                true,
            ));
        }
    }
    Lowered { definitions, textures, errors, warnings }
}

/// A param as declared: its default and range evaluated. One per `param`
/// of the file, in order, so an AST index is a `ParamInfo` index; a param
/// whose declaration is wrong (already reported) gets a placeholder.
struct ParamInfo {
    name: String,
    ty: Type,
    default: Value,
    range: Option<(f32, f32)>,
    unit: Option<String>,
    doc: Option<String>,
    location: Location,
}

fn declared_params(units: &[Unit], u: usize, textures: &mut Vec<TextureSource>, errors: &mut Vec<Diagnostic>) -> Vec<ParamInfo> {
    let unit = &units[u];
    let loc = |s: &Span| unit.source.location(s.clone());
    let mut out = Vec::new();
    for p in &unit.ast.params {
        let mut info = ParamInfo {
            name: p.name.name.clone(),
            ty: scalar(p.ty),
            default: Value::Float(0.0),
            range: None,
            unit: p.unit.as_ref().map(|u| u.name.clone()),
            doc: p.doc.clone(),
            location: loc(&p.name.span),
        };
        let ty = info.ty;
        if p.ty == TypeName::Slab {
            errors.push(error("a param cannot be a slab", loc(&p.ty_span), "params are `float`, `color`, `vec3` or `texture`"));
            out.push(info);
            continue;
        }
        if let Some(t) = &p.texture {
            match texture_source(unit, t) {
                Ok(source) => {
                    textures.push(source);
                    info.default = Value::Texture(textures.len() as u32 - 1);
                }
                Err(d) => errors.push(d),
            }
            out.push(info);
            continue;
        }
        let mut constant_of = |e: &ast::Expr, what: &str, want: Type| -> Option<Value> {
            let mut l = Lowerer::new(units, &[]);
            let scope = Scope { unit: u, env: Env::Constant, locals: Vec::new() };
            let v = l.expr(&scope, e);
            errors.append(&mut l.errors);
            let id = l.value(v, e, &scope, want, what)?;
            let value = constant(&l.exprs, id);
            match value {
                Some(v) if components(v).iter().all(|x| x.is_finite()) => Some(v),
                _ => {
                    errors.push(error(format!("{what} is not a finite constant"), loc(&e.span), "here"));
                    None
                }
            }
        };
        let default = constant_of(&p.default, "the default", ty);
        let range = p.range.as_ref().and_then(|(lo, hi)| {
            let lo = constant_of(lo, "a range bound", Type::Float)?;
            let hi = constant_of(hi, "a range bound", Type::Float)?;
            let (Value::Float(lo), Value::Float(hi)) = (lo, hi) else { return None };
            Some((lo, hi))
        });
        let (Some(default), Some(range)) = (default, p.range.as_ref().map_or(Some(None), |_| range.map(Some))) else {
            out.push(info);
            continue;
        };
        if let Some((lo, hi)) = range {
            let span = p.range.as_ref().map_or(p.default.span.clone(), |(l, h)| l.span.start..h.span.end);
            if lo > hi {
                errors.push(error(format!("empty range: {lo} is above {hi}"), loc(&span), "the low bound comes first"));
                out.push(info);
                continue;
            }
            if let Some(bad) = components(default).into_iter().find(|x| !(lo..=hi).contains(x)) {
                errors.push(
                    error(
                        format!("the default of `{}` is outside its range", p.name.name),
                        loc(&p.default.span),
                        format!("{bad} is not in [{lo}, {hi}]"),
                    )
                    .with_label(loc(&span), "the declared range", false),
                );
                out.push(info);
                continue;
            }
        }
        info.default = default;
        info.range = range;
        out.push(info);
    }
    out
}

/// A texture param's image: its path resolved against the file, and its
/// colour space (as written, else linear for EXR and sRGB for the rest).
fn texture_source(unit: &Unit, t: &ast::TextureDecl) -> Result<TextureSource, Diagnostic> {
    let path = unit.source.path.parent().unwrap_or(std::path::Path::new(".")).join(&t.path);
    let exr = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    let space = match &t.space {
        None if exr => ColorSpace::Linear,
        None => ColorSpace::Srgb,
        Some(s) => match ColorSpace::ALL.iter().find(|(name, _)| *name == s.name) {
            Some((_, space)) => *space,
            None => {
                let at = unit.source.location(s.span.clone());
                return Err(error(format!("unknown colour space `{}`", s.name), at, "one of `srgb`, `linear` or `normal`"));
            }
        },
    };
    Ok(TextureSource { path, space, location: unit.source.location(t.path_span.clone()) })
}

/// Every name a file declares is declared once, and none hides an operator
/// or a built-in.
fn check_names(unit: &Unit, errors: &mut Vec<Diagnostic>) {
    let ast = &unit.ast;
    let names = ast
        .imports
        .iter()
        .map(|i| (&i.prefix, "import"))
        .chain(ast.params.iter().map(|p| (&p.name, "param")))
        .chain(ast.fns.iter().map(|f| (&f.name, "fn")))
        .chain(ast.materials.iter().map(|m| (&m.name, "material")));
    let mut seen: BTreeMap<&str, &Ident> = BTreeMap::new();
    for (name, kind) in names {
        let here = unit.source.location(name.span.clone());
        if let Some(first) = seen.get(name.name.as_str()) {
            errors.push(error(format!("`{}` is declared twice", name.name), here, format!("this {kind} repeats the name")).with_label(
                unit.source.location(first.span.clone()),
                "first declared here",
                false,
            ));
        } else if kind != "param" && (OPERATORS.contains(&name.name.as_str()) || Builtin::from_name(&name.name).is_some()) {
            errors.push(error(format!("`{}` is a built-in name", name.name), here, "choose another name"));
        } else {
            seen.insert(&name.name, name);
        }
    }
    for f in &ast.fns {
        let mut args: BTreeMap<&str, &Ident> = BTreeMap::new();
        for (a, _) in &f.args {
            if let Some(first) = args.insert(&a.name, a) {
                errors.push(
                    error(format!("argument `{}` is declared twice", a.name), unit.source.location(a.span.clone()), "repeated").with_label(
                        unit.source.location(first.span.clone()),
                        "first declared here",
                        false,
                    ),
                );
            }
        }
    }
}

fn error(message: impl Into<String>, at: Location, label: impl Into<String>) -> Diagnostic {
    Diagnostic::error(Code::Material, message).with_label(at, label, true)
}

/// A lowered value.
#[derive(Debug, Clone, Copy)]
enum Val {
    Value(ExprId),
    Slab(NodeId),
    /// Something already reported; whatever uses it says nothing more.
    Error,
}

/// What a file's param names mean where an expression is lowered.
#[derive(Clone)]
enum Env {
    /// The root file's own materials: params stay symbolic (`ExprKind::Param`).
    Symbolic,
    /// A material or fn of another file, or a material called with
    /// arguments: each param is its argument, else its default.
    Bound(Vec<Option<Val>>),
    /// A param's default or range: no param is in scope.
    Constant,
}

struct Scope {
    unit: usize,
    env: Env,
    locals: Vec<(String, Val)>,
}

struct Lowerer<'a> {
    units: &'a [Unit],
    params: &'a [Vec<ParamInfo>],
    nodes: Vec<Node>,
    exprs: Vec<Expr>,
    errors: Vec<Diagnostic>,
    /// The fns and materials being inlined, outermost first: (unit, name).
    stack: Vec<(usize, String)>,
    /// Ranges root params take from the field they feed directly, when
    /// they declare none.
    ranges: BTreeMap<u32, (f32, f32)>,
}

impl<'a> Lowerer<'a> {
    fn new(units: &'a [Unit], params: &'a [Vec<ParamInfo>]) -> Self {
        Lowerer { units, params, nodes: Vec::new(), exprs: Vec::new(), errors: Vec::new(), stack: Vec::new(), ranges: BTreeMap::new() }
    }

    fn loc(&self, unit: usize, span: &Span) -> Location {
        self.units[unit].source.location(span.clone())
    }

    fn err(&mut self, scope: &Scope, span: &Span, message: impl Into<String>, label: impl Into<String>) -> Val {
        let d = error(message, self.loc(scope.unit, span), label);
        self.errors.push(d);
        Val::Error
    }

    fn too_big(&mut self, scope: &Scope, span: &Span) -> bool {
        let big = self.nodes.len() + self.exprs.len() > MAX_SIZE;
        if big && !self.errors.iter().any(|e| e.message.starts_with("material too large")) {
            self.err(
                scope,
                span,
                format!("material too large: its calls inline to more than {MAX_SIZE} nodes and expressions"),
                "while inlining this",
            );
        }
        big
    }

    fn push_expr(&mut self, scope: &Scope, span: &Span, kind: ExprKind, ty: Type) -> Val {
        if self.too_big(scope, span) {
            return Val::Error;
        }
        let location = self.loc(scope.unit, span);
        self.exprs.push(Expr { kind, ty, location });
        Val::Value(ExprId(self.exprs.len() as u32 - 1))
    }

    fn push_node(&mut self, scope: &Scope, span: &Span, kind: NodeKind) -> Val {
        if self.too_big(scope, span) {
            return Val::Error;
        }
        let location = self.loc(scope.unit, span);
        self.nodes.push(Node { kind, location });
        Val::Slab(NodeId(self.nodes.len() as u32 - 1))
    }

    fn ty(&self, id: ExprId) -> Type {
        self.exprs[id.0 as usize].ty
    }

    /// `v` as a value of type `want` (a float where a colour is wanted is
    /// an error, with a hint); `None` after an error.
    fn value(&mut self, v: Val, e: &ast::Expr, scope: &Scope, want: Type, what: &str) -> Option<ExprId> {
        match v {
            Val::Error => None,
            Val::Slab(_) => {
                self.err(scope, &e.span, format!("{what} must be a {}, not a slab", type_name(want)), "a slab");
                None
            }
            Val::Value(id) if self.ty(id) == want => Some(id),
            Val::Value(id) => {
                let got = self.ty(id);
                let hint = if got == Type::Float && want == Type::Color { " (write `grey(x)` for a grey colour)" } else { "" };
                self.err(
                    scope,
                    &e.span,
                    format!("{what} must be a {}, not a {}{hint}", type_name(want), type_name(got)),
                    format!("a {}", type_name(got)),
                );
                None
            }
        }
    }

    fn slab(&mut self, v: Val, e: &ast::Expr, scope: &Scope, what: &str) -> Option<NodeId> {
        match v {
            Val::Slab(n) => Some(n),
            Val::Error => None,
            Val::Value(id) => {
                let got = type_name(self.ty(id));
                self.err(scope, &e.span, format!("{what} must be a slab, not a {got}"), format!("a {got}"));
                None
            }
        }
    }

    fn material_body(&mut self, scope: &Scope, m: &ast::MaterialDecl, call: &Span) -> Val {
        self.inline(scope, call, (scope.unit, m.name.name.clone()), |l| {
            let mut inner = Scope { unit: scope.unit, env: scope.env.clone(), locals: Vec::new() };
            l.block(&mut inner, &m.body)
        })
    }

    /// Runs `f` with `key` on the inlining stack: a key already there is
    /// recursion, an error at `call`.
    fn inline(&mut self, scope: &Scope, call: &Span, key: (usize, String), f: impl FnOnce(&mut Self) -> Val) -> Val {
        if let Some(i) = self.stack.iter().position(|k| *k == key) {
            let chain: Vec<&str> = self.stack[i..].iter().map(|(_, n)| n.as_str()).chain([key.1.as_str()]).collect();
            let message = format!("recursion: {}", chain.join(" -> "));
            return self.err(scope, call, message, "calls itself through this");
        }
        if self.too_big(scope, call) {
            return Val::Error;
        }
        if self.stack.len() >= MAX_INLINE_DEPTH {
            return self.err(scope, call, format!("calls nest more than {MAX_INLINE_DEPTH} deep"), "inlining limit reached here");
        }
        self.stack.push(key);
        let v = f(self);
        self.stack.pop();
        v
    }

    fn block(&mut self, scope: &mut Scope, b: &ast::Block) -> Val {
        for (name, e) in &b.lets {
            let v = self.expr(scope, e);
            scope.locals.push((name.name.clone(), v));
        }
        self.expr(scope, &b.value)
    }

    fn expr(&mut self, scope: &Scope, e: &ast::Expr) -> Val {
        match &e.kind {
            ast::ExprKind::Number(x) => self.push_expr(scope, &e.span, ExprKind::Const(Value::Float(*x)), Type::Float),
            ast::ExprKind::Neg(a) => match self.expr(scope, a) {
                Val::Value(id) => {
                    let ty = self.ty(id);
                    self.push_expr(scope, &e.span, ExprKind::Neg(id), ty)
                }
                Val::Slab(_) => self.err(scope, &a.span, "cannot negate a slab", "a slab"),
                Val::Error => Val::Error,
            },
            ast::ExprKind::Binary(op, a, b) => {
                let (va, vb) = (self.expr(scope, a), self.expr(scope, b));
                match (va, vb) {
                    (Val::Value(x), Val::Value(y)) => match join(self.ty(x), self.ty(y)) {
                        Some(ty) => self.push_expr(scope, &e.span, ExprKind::Binary(*op, x, y), ty),
                        None => {
                            let (tx, ty) = (type_name(self.ty(x)), type_name(self.ty(y)));
                            self.err(scope, &e.span, format!("cannot combine a {tx} with a {ty}"), format!("a {tx} and a {ty}"))
                        }
                    },
                    (Val::Slab(_), _) => {
                        self.err(scope, &a.span, "arithmetic on a slab: combine slabs with `mix`, `layer`, `coverage` or `add`", "a slab")
                    }
                    (_, Val::Slab(_)) => {
                        self.err(scope, &b.span, "arithmetic on a slab: combine slabs with `mix`, `layer`, `coverage` or `add`", "a slab")
                    }
                    _ => Val::Error,
                }
            }
            ast::ExprKind::Name(path) => self.name(scope, path, &e.span),
            ast::ExprKind::Call { callee, args } => self.call(scope, callee, args, &e.span),
            ast::ExprKind::Slab(fields) => self.slab_literal(scope, fields, &e.span),
        }
    }

    fn name(&mut self, scope: &Scope, path: &[Ident], span: &Span) -> Val {
        let unit = &self.units[scope.unit];
        if let [name] = path {
            if let Some((_, v)) = scope.locals.iter().rev().find(|(n, _)| *n == name.name) {
                return *v;
            }
            if let Some(i) = unit.ast.params.iter().position(|p| p.name.name == name.name) {
                return self.param(scope, i, span);
            }
            let constant = matches!(scope.env, Env::Constant);
            if let Some(m) = unit.ast.materials.iter().find(|m| !constant && m.name.name == name.name) {
                return self.material_body(scope, m, span);
            }
            if unit.ast.fns.iter().any(|f| f.name.name == name.name) {
                return self.err(scope, span, format!("`{}` is a fn: call it with its arguments", name.name), "not called");
            }
            if ["nan", "inf", "infinity", "NaN", "Inf"].contains(&name.name.as_str()) {
                return self.err(
                    scope,
                    span,
                    format!("`{}` is not a value: every number must be finite", name.name),
                    "not a finite number",
                );
            }
            if constant {
                return self.unknown(scope, span, "name", &name.name, &[], "");
            }
            let mut known: Vec<&str> = scope.locals.iter().map(|(n, _)| n.as_str()).collect();
            known.extend(unit.ast.params.iter().map(|p| p.name.name.as_str()));
            known.extend(unit.ast.materials.iter().map(|m| m.name.name.as_str()));
            return self.unknown(scope, span, "name", &name.name, &known, "");
        }
        let Some(target) = self.imported(scope, path, span) else { return Val::Error };
        let name = &path[1];
        let target_unit = &self.units[target];
        if let Some(m) = target_unit.ast.materials.iter().find(|m| m.name.name == name.name) {
            let callee = Scope { unit: target, env: Env::Bound(vec![None; self.params[target].len()]), locals: Vec::new() };
            return self.material_in(scope, &callee, m, span);
        }
        let known: Vec<&str> = target_unit.ast.materials.iter().map(|m| m.name.name.as_str()).collect();
        self.unknown(scope, span, "material", &name.name, &known, &format!(" in `{}`", path[0].name))
    }

    /// Lowers `m` in `callee`'s scope, reporting recursion at the caller.
    fn material_in(&mut self, caller: &Scope, callee: &Scope, m: &ast::MaterialDecl, span: &Span) -> Val {
        self.inline(caller, span, (callee.unit, m.name.name.clone()), |l| {
            let mut inner = Scope { unit: callee.unit, env: callee.env.clone(), locals: Vec::new() };
            l.block(&mut inner, &m.body)
        })
    }

    /// The unit `prefix` names in `prefix.name`; an error if none.
    fn imported(&mut self, scope: &Scope, path: &[Ident], span: &Span) -> Option<usize> {
        if path.len() > 2 {
            self.err(scope, span, "a name has at most one prefix (`file.name`)", "too many `.`");
            return None;
        }
        let unit = &self.units[scope.unit];
        if let Some(&(_, target)) = unit.imports.iter().find(|(p, _)| *p == path[0].name) {
            return Some(target);
        }
        let known: Vec<&str> = unit.imports.iter().map(|(p, _)| p.as_str()).collect();
        self.unknown(scope, &path[0].span, "import", &path[0].name, &known, "");
        None
    }

    fn param(&mut self, scope: &Scope, i: usize, span: &Span) -> Val {
        match &scope.env {
            Env::Symbolic => {
                let ty = self.params[scope.unit][i].ty;
                self.push_expr(scope, span, ExprKind::Param(i as u32), ty)
            }
            Env::Bound(args) => match args.get(i).copied().flatten() {
                Some(v) => v,
                None => {
                    let p = &self.params[scope.unit][i];
                    let (default, ty) = (p.default, p.ty);
                    self.push_expr(scope, span, ExprKind::Const(default), ty)
                }
            },
            Env::Constant => self.err(scope, span, "a param's default and range must be constants", "a param"),
        }
    }

    fn unknown(&mut self, scope: &Scope, span: &Span, what: &str, name: &str, known: &[&str], context: &str) -> Val {
        let mut d = error(format!("unknown {what} `{name}`{context}"), self.loc(scope.unit, span), "not declared");
        if let Some(best) = closest(name, known.iter().copied()) {
            d = d.with_note(format!("did you mean `{best}`?"));
        } else if !known.is_empty() {
            d = d.with_note(format!("known: {}", known.join(", ")));
        }
        self.errors.push(d);
        Val::Error
    }

    fn slab_literal(&mut self, scope: &Scope, fields: &[(Ident, ast::Expr)], span: &Span) -> Val {
        let mut slab = Slab::default();
        let mut failed = false;
        for (name, e) in fields {
            let v = self.expr(scope, e);
            let Some(field) = Field::from_name(&name.name) else {
                let known: Vec<&str> = Field::ALL.iter().map(|f| f.name()).collect();
                self.unknown(scope, &name.span, "field", &name.name, &known, "");
                failed = true;
                continue;
            };
            if let Some(first) = fields.iter().map(|(n, _)| n).find(|n| n.name == name.name).filter(|n| n.span != name.span) {
                let d = error(format!("field `{}` is set twice", name.name), self.loc(scope.unit, &name.span), "set again here")
                    .with_label(self.loc(scope.unit, &first.span), "first set here", false);
                self.errors.push(d);
                failed = true;
                continue;
            }
            let Some(id) = self.value(v, e, scope, field.ty(), &format!("`{}`", field.name())) else {
                failed = true;
                continue;
            };
            if !self.in_range(scope, id, e, &format!("`{}`", field.name()), field.range()) {
                failed = true;
            }
            slab.fields.push((field, id));
        }
        if failed { Val::Error } else { self.push_node(scope, span, NodeKind::Slab(slab)) }
    }

    /// Checks a constant `id` (and a root param feeding it directly)
    /// against `range`; false after an error.
    fn in_range(&mut self, scope: &Scope, id: ExprId, e: &ast::Expr, what: &str, range: Option<(f32, f32)>) -> bool {
        let (lo, hi) = range.unwrap_or((f32::MIN, f32::MAX));
        let show = |x: f32| if x == f32::MAX { "∞".to_owned() } else { x.to_string() };
        if let ExprKind::Param(i) = self.exprs[id.0 as usize].kind {
            let p = &self.params[0][i as usize];
            match p.range {
                Some((plo, phi)) if plo < lo || phi > hi => {
                    let d = error(
                        format!("param `{}` may leave the range of {what}", p.name),
                        self.loc(scope.unit, &e.span),
                        format!("{what} takes [{}, {}]", show(lo), show(hi)),
                    )
                    .with_label(p.location.clone(), format!("declared in [{plo}, {phi}]"), false);
                    self.errors.push(d);
                    return false;
                }
                Some(_) => {}
                None => {
                    let r = self.ranges.entry(i).or_insert((lo, hi));
                    *r = (r.0.max(lo), r.1.min(hi));
                }
            }
        }
        let Some(value) = constant(&self.exprs, id) else { return true };
        let bad = components(value).into_iter().find(|x| !(lo..=hi).contains(x));
        match bad {
            None => true,
            Some(x) => {
                let message = if x.is_nan() {
                    format!("{what} evaluates to NaN")
                } else {
                    format!("{what} must lie in [{}, {}], not {x}", show(lo), show(hi))
                };
                self.err(scope, &e.span, message, if x.is_nan() { "not a number" } else { "out of range" });
                false
            }
        }
    }

    fn call(&mut self, scope: &Scope, callee: &[Ident], args: &[ast::Arg], span: &Span) -> Val {
        let (target, name) = if let [name] = callee {
            (scope.unit, name)
        } else {
            match self.imported(scope, callee, span) {
                Some(t) => (t, &callee[1]),
                None => return Val::Error,
            }
        };
        let unit = &self.units[target];
        if let Some(f) = unit.ast.fns.iter().find(|f| f.name.name == name.name) {
            return self.call_fn(scope, target, f, args, span);
        }
        if let Some(m) = unit.ast.materials.iter().find(|m| m.name.name == name.name) {
            return self.call_material(scope, target, m, args, span);
        }
        let mut known: Vec<&str> = unit.ast.fns.iter().map(|f| f.name.name.as_str()).collect();
        known.extend(unit.ast.materials.iter().map(|m| m.name.name.as_str()));
        if target == scope.unit {
            if let Some(op) = OPERATORS.iter().find(|o| **o == name.name) {
                return self.operator(scope, op, args, span);
            }
            if let Some(b) = Builtin::from_name(&name.name) {
                return self.builtin(scope, b, args, span);
            }
            known.extend(OPERATORS);
            known.extend(Builtin::ALL.iter().map(|b| b.name()));
        }
        let note = if target == scope.unit { String::new() } else { format!(" in `{}`", callee[0].name) };
        self.unknown(scope, &name.span, "function", &name.name, &known, &note)
    }

    /// The arguments as values, positionally; an error (and `None`) for a
    /// named one or a wrong count.
    fn positional(&mut self, scope: &Scope, what: &str, args: &[ast::Arg], want: usize, span: &Span) -> Option<Vec<Val>> {
        if let Some(n) = args.iter().find_map(|a| a.name.as_ref()) {
            self.err(scope, &n.span, format!("{what} takes its arguments by position"), "remove the name");
            return None;
        }
        if args.len() != want {
            let s = if want == 1 { "" } else { "s" };
            self.err(scope, span, format!("{what} takes {want} argument{s}, not {}", args.len()), format!("{} given", args.len()));
            return None;
        }
        Some(args.iter().map(|a| self.expr(scope, &a.value)).collect())
    }

    fn call_fn(&mut self, scope: &Scope, target: usize, f: &ast::FnDecl, args: &[ast::Arg], span: &Span) -> Val {
        let what = format!("`{}`", f.name.name);
        let Some(vals) = self.positional(scope, &what, args, f.args.len(), span) else { return Val::Error };
        let mut locals = Vec::new();
        let mut failed = false;
        for ((arg, ty), (v, a)) in f.args.iter().zip(vals.into_iter().zip(args)) {
            let ok = match ty {
                TypeName::Slab => self.slab(v, &a.value, scope, &format!("argument `{}`", arg.name)).is_some(),
                t => self.value(v, &a.value, scope, scalar(*t), &format!("argument `{}`", arg.name)).is_some(),
            };
            failed |= !ok;
            locals.push((arg.name.clone(), v));
        }
        if failed {
            return Val::Error;
        }
        let env = if target == scope.unit { scope.env.clone() } else { Env::Bound(vec![None; self.params[target].len()]) };
        let v = self.inline(scope, span, (target, f.name.name.clone()), |l| {
            let mut inner = Scope { unit: target, env, locals };
            l.block(&mut inner, &f.body)
        });
        let inner = Scope { unit: target, env: Env::Constant, locals: Vec::new() };
        let body = &f.body.value;
        let what = format!("the result of `{}`", f.name.name);
        match f.ret {
            TypeName::Slab => self.slab(v, body, &inner, &what).map_or(Val::Error, Val::Slab),
            t => self.value(v, body, &inner, scalar(t), &what).map_or(Val::Error, Val::Value),
        }
    }

    fn call_material(&mut self, scope: &Scope, target: usize, m: &ast::MaterialDecl, args: &[ast::Arg], span: &Span) -> Val {
        let params = &self.params[target];
        let mut bound: Vec<Option<Val>> = vec![None; params.len()];
        let mut failed = false;
        for a in args {
            let v = self.expr(scope, &a.value);
            let Some(name) = &a.name else {
                self.err(
                    scope,
                    &a.value.span,
                    format!("material `{}` takes its params by name (`name: value`)", m.name.name),
                    "name this argument",
                );
                failed = true;
                continue;
            };
            let Some(i) = params.iter().position(|p| p.name == name.name) else {
                let known: Vec<&str> = params.iter().map(|p| p.name.as_str()).collect();
                self.unknown(scope, &name.span, "param", &name.name, &known, &format!(" of `{}`", m.name.name));
                failed = true;
                continue;
            };
            if bound[i].is_some() {
                self.err(scope, &name.span, format!("param `{}` is given twice", name.name), "given again");
                failed = true;
                continue;
            }
            let (ty, range) = (params[i].ty, params[i].range);
            match self.value(v, &a.value, scope, ty, &format!("param `{}`", name.name)) {
                Some(id) if self.in_range(scope, id, &a.value, &format!("param `{}`", name.name), range) => bound[i] = Some(v),
                _ => failed = true,
            }
        }
        if failed {
            return Val::Error;
        }
        let callee = Scope { unit: target, env: Env::Bound(bound), locals: Vec::new() };
        self.material_in(scope, &callee, m, span)
    }

    fn operator(&mut self, scope: &Scope, op: &str, args: &[ast::Arg], span: &Span) -> Val {
        let (slabs, weighted) = match op {
            "mix" => (2, true),
            "coverage" => (1, true),
            _ => (2, false),
        };
        let what = format!("`{op}`");
        let Some(vals) = self.positional(scope, &what, args, slabs + usize::from(weighted), span) else { return Val::Error };
        let mut nodes = Vec::new();
        for (i, (v, a)) in vals.iter().zip(args).take(slabs).enumerate() {
            nodes.push(self.slab(*v, &a.value, scope, &format!("argument {} of {what}", i + 1)));
        }
        let weight = if weighted {
            let a = &args[slabs].value;
            let id = self.value(vals[slabs], a, scope, Type::Float, &format!("the weight of {what}"));
            match id {
                Some(id) if self.in_range(scope, id, a, &format!("the weight of {what}"), Some((0.0, 1.0))) => Some(id),
                _ => return Val::Error,
            }
        } else {
            None
        };
        let kind = match (op, nodes.as_slice(), weight) {
            ("mix", &[Some(a), Some(b)], Some(weight)) => NodeKind::Mix { a, b, weight },
            ("coverage", &[Some(a)], Some(weight)) => NodeKind::Coverage { a, weight },
            ("layer", &[Some(top), Some(base)], _) => NodeKind::Layer { top, base },
            ("add", &[Some(a), Some(b)], _) => NodeKind::Add { a, b },
            _ => return Val::Error,
        };
        self.push_node(scope, span, kind)
    }

    fn builtin(&mut self, scope: &Scope, b: Builtin, args: &[ast::Arg], span: &Span) -> Val {
        use Builtin::*;
        let count = match b {
            Rgb | Lerp | Clamp => 3,
            Min | Max | Pow | TransmittanceToMfp | NormalMap => 2,
            _ => 1,
        };
        let what = format!("`{}`", b.name());
        let Some(vals) = self.positional(scope, &what, args, count, span) else { return Val::Error };
        let mut ids = Vec::new();
        for (i, (v, a)) in vals.iter().zip(args).enumerate() {
            match v {
                Val::Value(id) => ids.push(*id),
                Val::Slab(_) => {
                    return self.err(scope, &a.value.span, format!("argument {} of {what} must be a value, not a slab", i + 1), "a slab");
                }
                Val::Error => return Val::Error,
            }
        }
        let tys: Vec<Type> = ids.iter().map(|&id| self.ty(id)).collect();
        // Each built-in's fixed argument types, then its result.
        let fixed = |want: &[Type], ret: Type| (want.to_vec(), Some(ret));
        let (want, ret) = match b {
            Rgb => fixed(&[Type::Float; 3], Type::Color),
            Grey => fixed(&[Type::Float], Type::Color),
            Luminance => fixed(&[Type::Color], Type::Float),
            Srgb => fixed(&[Type::Color], Type::Color),
            IorToF0 => fixed(&[Type::Float], Type::Float),
            TransmittanceToMfp => fixed(&[Type::Color, Type::Float], Type::Color),
            Sample => fixed(&[Type::Texture], Type::Color),
            NormalMap => fixed(&[Type::Texture, Type::Float], Type::Vec3),
            // The rest work per component: their arguments join to one type.
            _ => (Vec::new(), tys.iter().try_fold(tys[0], |acc, t| join(acc, *t))),
        };
        for (i, (w, t)) in want.iter().zip(&tys).enumerate() {
            if w != t {
                let a = &args[i].value;
                return self.err(
                    scope,
                    &a.span,
                    format!("argument {} of {what} must be a {}, not a {}", i + 1, type_name(*w), type_name(*t)),
                    format!("a {}", type_name(*t)),
                );
            }
        }
        // The texture's layer is the instance's value of a param of this
        // material: a default made constant (another file's) has none.
        if matches!(b, Sample | NormalMap) && !matches!(self.exprs[ids[0].0 as usize].kind, ExprKind::Param(_)) {
            let at = &args[0].value.span;
            return self.err(scope, at, format!("{what} takes a texture param of this material's file"), "not a param of this file");
        }
        let Some(ret) = ret else {
            let shown: Vec<&str> = tys.iter().map(|t| type_name(*t)).collect();
            return self.err(scope, span, format!("{what} cannot combine {}", shown.join(", ")), "mismatched argument types");
        };
        self.push_expr(scope, span, ExprKind::Call(b, ids), ret)
    }

    /// The definition rooted at `root`: only what it reaches is kept (a
    /// `let` never used leaves nothing), children before parents, and only
    /// the params it uses, in declaration order.
    fn finish(self, name: &Ident, root: NodeId) -> Definition {
        let mut node_live = vec![false; self.nodes.len()];
        let mut expr_live = vec![false; self.exprs.len()];
        node_live[root.0 as usize] = true;
        // Children have lower ids than parents: one pass downward marks all.
        for i in (0..self.nodes.len()).rev() {
            if !node_live[i] {
                continue;
            }
            let (kids, exprs) = node_refs(&self.nodes[i].kind);
            kids.iter().for_each(|k| node_live[k.0 as usize] = true);
            exprs.iter().for_each(|e| expr_live[e.0 as usize] = true);
        }
        for i in (0..self.exprs.len()).rev() {
            if expr_live[i] {
                expr_refs(&self.exprs[i].kind).iter().for_each(|e| expr_live[e.0 as usize] = true);
            }
        }
        let remap = |live: &[bool]| -> Vec<u32> {
            let mut n = 0;
            live.iter()
                .map(|&l| {
                    let id = n;
                    n += u32::from(l);
                    id
                })
                .collect()
        };
        let (node_id, expr_id) = (remap(&node_live), remap(&expr_live));
        let used: Vec<u32> = (0..self.params[0].len() as u32)
            .filter(|&p| self.exprs.iter().zip(&expr_live).any(|(e, &l)| l && e.kind == ExprKind::Param(p)))
            .collect();
        let e = |id: ExprId| ExprId(expr_id[id.0 as usize]);
        let n = |id: NodeId| NodeId(node_id[id.0 as usize]);
        let exprs = self.exprs.iter().zip(&expr_live).filter(|(_, l)| **l).map(|(x, _)| Expr {
            kind: match &x.kind {
                ExprKind::Param(p) => ExprKind::Param(used.iter().position(|u| u == p).expect("a used param") as u32),
                ExprKind::Neg(a) => ExprKind::Neg(e(*a)),
                ExprKind::Binary(op, a, b) => ExprKind::Binary(*op, e(*a), e(*b)),
                ExprKind::Call(b, args) => ExprKind::Call(*b, args.iter().map(|&a| e(a)).collect()),
                k @ ExprKind::Const(_) => k.clone(),
            },
            ..x.clone()
        });
        let nodes = self.nodes.iter().zip(&node_live).filter(|(_, l)| **l).map(|(x, _)| Node {
            kind: match &x.kind {
                NodeKind::Slab(s) => NodeKind::Slab(Slab { fields: s.fields.iter().map(|&(f, id)| (f, e(id))).collect() }),
                NodeKind::Mix { a, b, weight } => NodeKind::Mix { a: n(*a), b: n(*b), weight: e(*weight) },
                NodeKind::Layer { top, base } => NodeKind::Layer { top: n(*top), base: n(*base) },
                NodeKind::Coverage { a, weight } => NodeKind::Coverage { a: n(*a), weight: e(*weight) },
                NodeKind::Add { a, b } => NodeKind::Add { a: n(*a), b: n(*b) },
            },
            ..x.clone()
        });
        let params = used
            .iter()
            .map(|&i| {
                let p = &self.params[0][i as usize];
                Param {
                    name: p.name.clone(),
                    ty: p.ty,
                    default: p.default,
                    range: p.range.or_else(|| self.ranges.get(&i).copied()),
                    unit: p.unit.clone(),
                    doc: p.doc.clone(),
                    location: p.location.clone(),
                }
            })
            .collect();
        Definition {
            name: name.name.clone(),
            location: self.units[0].source.location(name.span.clone()),
            params,
            nodes: nodes.collect(),
            exprs: exprs.collect(),
            root: n(root),
            energy_compensation: true,
        }
    }
}

fn node_refs(kind: &NodeKind) -> (Vec<NodeId>, Vec<ExprId>) {
    match kind {
        NodeKind::Slab(s) => (Vec::new(), s.fields.iter().map(|&(_, e)| e).collect()),
        NodeKind::Mix { a, b, weight } => (vec![*a, *b], vec![*weight]),
        NodeKind::Layer { top, base } => (vec![*top, *base], Vec::new()),
        NodeKind::Coverage { a, weight } => (vec![*a], vec![*weight]),
        NodeKind::Add { a, b } => (vec![*a, *b], Vec::new()),
    }
}

fn expr_refs(kind: &ExprKind) -> Vec<ExprId> {
    match kind {
        ExprKind::Const(_) | ExprKind::Param(_) => Vec::new(),
        ExprKind::Neg(a) => vec![*a],
        ExprKind::Binary(_, a, b) => vec![*a, *b],
        ExprKind::Call(_, args) => args.clone(),
    }
}

fn scalar(t: TypeName) -> Type {
    match t {
        TypeName::Float => Type::Float,
        TypeName::Color => Type::Color,
        TypeName::Vec3 | TypeName::Slab => Type::Vec3,
        TypeName::Texture => Type::Texture,
    }
}

fn type_name(t: Type) -> &'static str {
    match t {
        Type::Float => "float",
        Type::Color => "color",
        Type::Vec3 => "vec3",
        Type::Texture => "texture",
    }
}

/// The type of an operation on `a` and `b`: a float broadcasts; a colour
/// and a vector do not mix; a texture takes part in none (only `sample`
/// and `normal_map` read it).
fn join(a: Type, b: Type) -> Option<Type> {
    match (a, b) {
        (Type::Texture, _) | (_, Type::Texture) => None,
        (x, y) if x == y => Some(x),
        (Type::Float, y) => Some(y),
        (x, Type::Float) => Some(x),
        _ => None,
    }
}

/// The known name closest to `name`, if close enough to be a likely typo.
fn closest<'a>(name: &str, known: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    known.map(|k| (edit_distance(name, k), k)).filter(|(d, k)| *d <= k.len().max(name.len()).div_ceil(3)).min().map(|(_, k)| k)
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = (prev + usize::from(ca != *cb)).min(row[j] + 1).min(cur + 1);
            prev = cur;
        }
    }
    row[b.len()]
}
