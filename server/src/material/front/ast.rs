//! The syntax of one material file, as written, every part with its byte
//! span. Names are not resolved yet (that is `lower`'s job).

use std::ops::Range;

pub type Span = Range<usize>;

#[derive(Debug, Clone, PartialEq)]
pub struct Ident {
    pub name: String,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq, Default)]
pub struct File {
    pub imports: Vec<Import>,
    pub params: Vec<ParamDecl>,
    pub fns: Vec<FnDecl>,
    pub materials: Vec<MaterialDecl>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Import {
    /// The path as written, and the span of the string.
    pub path: String,
    pub path_span: Span,
    /// The prefix its items are named with: `as NAME`, else the file stem.
    pub prefix: Ident,
}

/// The types a declaration names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TypeName {
    Float,
    Color,
    Vec3,
    Slab,
    Texture,
}

impl TypeName {
    pub const ALL: [(&'static str, TypeName); 5] = [
        ("float", TypeName::Float),
        ("color", TypeName::Color),
        ("vec3", TypeName::Vec3),
        ("slab", TypeName::Slab),
        ("texture", TypeName::Texture),
    ];
}

#[derive(Debug, Clone, PartialEq)]
pub struct ParamDecl {
    pub name: Ident,
    pub ty: TypeName,
    pub ty_span: Span,
    pub default: Expr,
    /// `in [LO, HI]`: each bound an expression (a constant once lowered).
    pub range: Option<(Expr, Expr)>,
    pub unit: Option<Ident>,
    pub doc: Option<String>,
    /// A `texture` param's default, `"PATH" [SPACE]` (its `default` is then
    /// a placeholder at the path's span).
    pub texture: Option<TextureDecl>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct TextureDecl {
    pub path: String,
    pub path_span: Span,
    /// `srgb`, `linear` or `normal`, if written.
    pub space: Option<Ident>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct FnDecl {
    pub name: Ident,
    pub args: Vec<(Ident, TypeName)>,
    pub ret: TypeName,
    pub body: Block,
}

#[derive(Debug, Clone, PartialEq)]
pub struct MaterialDecl {
    pub name: Ident,
    pub body: Block,
}

/// `let` bindings, then the value.
#[derive(Debug, Clone, PartialEq)]
pub struct Block {
    pub lets: Vec<(Ident, Expr)>,
    pub value: Expr,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    Number(f32),
    /// `name` or `prefix.name`.
    Name(Vec<Ident>),
    Neg(Box<Expr>),
    Binary(crate::material::tree::BinOp, Box<Expr>, Box<Expr>),
    Call {
        callee: Vec<Ident>,
        args: Vec<Arg>,
    },
    Slab(Vec<(Ident, Expr)>),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Arg {
    /// `name: value`, or positional.
    pub name: Option<Ident>,
    pub value: Expr,
}
