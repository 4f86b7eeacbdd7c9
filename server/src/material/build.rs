//! Test helper: material trees built by hand, for the passes' tests (the
//! parser is not needed to test what comes after it). Every node and
//! expression is placed on its own line of `test.mat`, in creation order
//! (the first on line 1), so a test can tell them apart by location.

use super::tree::Field;
use super::tree::{BinOp, Builtin, Definition, Expr, ExprId, ExprKind, Node, NodeId, NodeKind, Param, Slab, Type, Value};
use crate::diag::Location;

pub struct Build {
    def: Definition,
    line: u32,
}

impl Build {
    pub fn new(name: &str) -> Self {
        let def = Definition {
            name: name.to_owned(),
            location: Location::file_start("test.mat"),
            params: vec![],
            nodes: vec![],
            exprs: vec![],
            root: NodeId(0),
            energy_compensation: true,
        };
        Build { def, line: 0 }
    }

    fn next_location(&mut self) -> Location {
        self.line += 1;
        Location { file: "test.mat".to_owned(), line: self.line, column: 1, end_line: self.line, end_column: 2 }
    }

    fn expr(&mut self, kind: ExprKind, ty: Type) -> ExprId {
        let location = self.next_location();
        self.def.exprs.push(Expr { kind, ty, location });
        ExprId(self.def.exprs.len() as u32 - 1)
    }

    fn node(&mut self, kind: NodeKind) -> NodeId {
        let location = self.next_location();
        self.def.nodes.push(Node { kind, location });
        NodeId(self.def.nodes.len() as u32 - 1)
    }

    fn ty(&self, e: ExprId) -> Type {
        self.def.expr(e).ty
    }

    pub fn float(&mut self, x: f32) -> ExprId {
        self.expr(ExprKind::Const(Value::Float(x)), Type::Float)
    }

    pub fn rgb(&mut self, c: [f32; 3]) -> ExprId {
        self.expr(ExprKind::Const(Value::Vec3(c)), Type::Color)
    }

    /// Declares a parameter and returns the expression reading it.
    pub fn param(&mut self, name: &str, ty: Type, default: Value, range: Option<(f32, f32)>) -> ExprId {
        let location = self.next_location();
        let index = self.def.params.len() as u32;
        self.def.params.push(Param { name: name.to_owned(), ty, default, range, unit: None, doc: None, location });
        self.expr(ExprKind::Param(index), ty)
    }

    pub fn neg(&mut self, x: ExprId) -> ExprId {
        self.expr(ExprKind::Neg(x), self.ty(x))
    }

    /// A float with a colour is a colour.
    pub fn bin(&mut self, op: BinOp, a: ExprId, b: ExprId) -> ExprId {
        let ty = if self.ty(a) == Type::Float { self.ty(b) } else { self.ty(a) };
        self.expr(ExprKind::Binary(op, a, b), ty)
    }

    pub fn call(&mut self, f: Builtin, args: &[ExprId]) -> ExprId {
        let ty = match f {
            Builtin::Rgb | Builtin::Grey => Type::Color,
            Builtin::Luminance => Type::Float,
            _ => args.iter().map(|&a| self.ty(a)).find(|&t| t != Type::Float).unwrap_or(Type::Float),
        };
        self.expr(ExprKind::Call(f, args.to_vec()), ty)
    }

    pub fn slab(&mut self, fields: &[(Field, ExprId)]) -> NodeId {
        self.node(NodeKind::Slab(Slab { fields: fields.to_vec() }))
    }

    pub fn mix(&mut self, a: NodeId, b: NodeId, weight: ExprId) -> NodeId {
        self.node(NodeKind::Mix { a, b, weight })
    }

    pub fn layer(&mut self, top: NodeId, base: NodeId) -> NodeId {
        self.node(NodeKind::Layer { top, base })
    }

    pub fn coverage(&mut self, a: NodeId, weight: ExprId) -> NodeId {
        self.node(NodeKind::Coverage { a, weight })
    }

    pub fn add(&mut self, a: NodeId, b: NodeId) -> NodeId {
        self.node(NodeKind::Add { a, b })
    }

    pub fn finish(mut self, root: NodeId) -> Definition {
        self.def.root = root;
        self.def
    }
}
