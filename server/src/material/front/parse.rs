//! Recursive descent from tokens to the syntax tree. Nesting is bounded
//! (`MAX_DEPTH`): a deeply nested or enormous expression is a diagnostic,
//! never a stack overflow. After an error the parser skips to the next
//! declaration, so one run reports an error per broken declaration.

use super::ast::*;
use super::lexer::{Comment, Tok, Token, lex};
use crate::material::tree::BinOp;

/// How deep expressions may nest (parentheses, calls, unary minus, and
/// operands chained by one operator, which lowering walks recursively too).
pub const MAX_DEPTH: usize = 128;

const KEYWORDS: [&str; 6] = ["import", "param", "fn", "material", "let", "in"];

#[derive(Debug, Clone, PartialEq)]
pub struct SyntaxError {
    pub message: String,
    pub label: String,
    pub span: Span,
}

pub fn parse(text: &str) -> (File, Vec<SyntaxError>) {
    let lexed = lex(text);
    let mut errors: Vec<SyntaxError> =
        lexed.errors.into_iter().map(|e| SyntaxError { message: e.message, label: "here".into(), span: e.span }).collect();
    let mut p = Parser { tokens: lexed.tokens, pos: 0, depth: 0, errors: Vec::new() };
    let mut file = File::default();
    while !p.at_eof() {
        let start = p.pos;
        if p.declaration(&mut file, text, &lexed.comments).is_err() {
            p.recover(start);
        }
    }
    errors.append(&mut p.errors);
    errors.sort_by_key(|e| e.span.start);
    (file, errors)
}

/// A reported error; the parser unwinds to the declaration and recovers.
struct Reported;

type PResult<T> = Result<T, Reported>;

struct Parser {
    tokens: Vec<Token>,
    pos: usize,
    depth: usize,
    errors: Vec<SyntaxError>,
}

impl Parser {
    fn peek(&self) -> &Token {
        &self.tokens[self.pos]
    }

    fn at_eof(&self) -> bool {
        self.peek().tok == Tok::Eof
    }

    fn bump(&mut self) -> Token {
        let t = self.tokens[self.pos].clone();
        if t.tok != Tok::Eof {
            self.pos += 1;
        }
        t
    }

    fn is_punct(&self, c: char) -> bool {
        self.peek().tok == Tok::Punct(c)
    }

    fn is_keyword(&self, k: &str) -> bool {
        matches!(&self.peek().tok, Tok::Ident(n) if n == k)
    }

    fn eat_punct(&mut self, c: char) -> bool {
        let yes = self.is_punct(c);
        if yes {
            self.bump();
        }
        yes
    }

    fn error<T>(&mut self, message: impl Into<String>, label: impl Into<String>, span: Span) -> PResult<T> {
        self.errors.push(SyntaxError { message: message.into(), label: label.into(), span });
        Err(Reported)
    }

    /// An error at the next token: "expected X, found Y".
    fn expected<T>(&mut self, what: &str) -> PResult<T> {
        let t = self.peek().clone();
        self.error(format!("expected {what}, found {}", describe(&t.tok)), format!("expected {what}"), t.span)
    }

    fn expect_punct(&mut self, c: char) -> PResult<Span> {
        if self.is_punct(c) { Ok(self.bump().span) } else { self.expected(&format!("`{c}`")) }
    }

    fn ident(&mut self, what: &str) -> PResult<Ident> {
        match self.peek().tok.clone() {
            Tok::Ident(name) if !KEYWORDS.contains(&name.as_str()) => Ok(Ident { name, span: self.bump().span }),
            _ => self.expected(what),
        }
    }

    /// Skips to the next token that starts a declaration (always moving on
    /// from `start`, so recovery cannot loop).
    fn recover(&mut self, start: usize) {
        if self.pos == start {
            self.bump();
        }
        while !self.at_eof() && !["import", "param", "fn", "material"].iter().any(|k| self.is_keyword(k)) {
            self.bump();
        }
        self.depth = 0;
    }

    fn declaration(&mut self, file: &mut File, text: &str, comments: &[Comment]) -> PResult<()> {
        let Tok::Ident(kw) = self.peek().tok.clone() else { return self.expected("`import`, `param`, `fn` or `material`") };
        match kw.as_str() {
            "import" => file.imports.push(self.import()?),
            "param" => {
                let doc = doc_above(text, comments, self.peek().span.start);
                file.params.push(self.param(doc)?);
            }
            "fn" => file.fns.push(self.function()?),
            "material" => file.materials.push(self.material()?),
            _ => return self.expected("`import`, `param`, `fn` or `material`"),
        }
        Ok(())
    }

    fn import(&mut self) -> PResult<Import> {
        self.bump();
        let t = self.peek().clone();
        let Tok::Str(path) = t.tok else { return self.expected("a quoted path") };
        self.bump();
        let prefix = if self.is_keyword("as") {
            self.bump();
            self.ident("a name")?
        } else {
            let stem = std::path::Path::new(&path).file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            Ident { name: stem, span: t.span.clone() }
        };
        Ok(Import { path, path_span: t.span, prefix })
    }

    fn type_name(&mut self) -> PResult<(TypeName, Span)> {
        if let Tok::Ident(n) = &self.peek().tok
            && let Some((_, t)) = TypeName::ALL.iter().find(|(name, _)| *name == n.as_str())
        {
            return Ok((*t, self.bump().span));
        }
        self.expected("a type (`float`, `color`, `vec3`, `texture` or `slab`)")
    }

    fn param(&mut self, doc: Option<String>) -> PResult<ParamDecl> {
        self.bump();
        let name = self.ident("a parameter name")?;
        self.expect_punct(':')?;
        let (ty, ty_span) = self.type_name()?;
        self.expect_punct('=')?;
        if ty == TypeName::Texture {
            return self.texture_param(name, ty_span, doc);
        }
        let default = self.expr()?;
        let range = if self.is_keyword("in") {
            self.bump();
            self.expect_punct('[')?;
            let lo = self.expr()?;
            self.expect_punct(',')?;
            let hi = self.expr()?;
            self.expect_punct(']')?;
            Some((lo, hi))
        } else {
            None
        };
        let has_unit = matches!(&self.peek().tok, Tok::Ident(n) if !KEYWORDS.contains(&n.as_str()));
        let unit = if has_unit { Some(self.ident("a unit")?) } else { None };
        Ok(ParamDecl { name, ty, ty_span, default, range, unit, doc, texture: None })
    }

    /// The rest of `param NAME: texture = "PATH" [SPACE]`.
    fn texture_param(&mut self, name: Ident, ty_span: Span, doc: Option<String>) -> PResult<ParamDecl> {
        let t = self.peek().clone();
        let Tok::Str(path) = t.tok else { return self.expected("a quoted image path") };
        self.bump();
        let is_space = matches!(&self.peek().tok, Tok::Ident(n) if !KEYWORDS.contains(&n.as_str()));
        let space = if is_space { Some(self.ident("a colour space")?) } else { None };
        let default = Expr { kind: ExprKind::Number(0.0), span: t.span.clone() };
        let texture = Some(TextureDecl { path, path_span: t.span, space });
        Ok(ParamDecl { name, ty: TypeName::Texture, ty_span, default, range: None, unit: None, doc, texture })
    }

    fn function(&mut self) -> PResult<FnDecl> {
        self.bump();
        let name = self.ident("a function name")?;
        self.expect_punct('(')?;
        let mut args = Vec::new();
        while !self.is_punct(')') {
            let arg = self.ident("an argument name")?;
            self.expect_punct(':')?;
            args.push((arg, self.type_name()?.0));
            if !self.eat_punct(',') {
                break;
            }
        }
        self.expect_punct(')')?;
        if self.peek().tok != Tok::Arrow {
            return self.expected("`->` and the return type");
        }
        self.bump();
        let ret = self.type_name()?.0;
        self.expect_punct('{')?;
        let body = self.block('}')?;
        Ok(FnDecl { name, args, ret, body })
    }

    fn material(&mut self) -> PResult<MaterialDecl> {
        self.bump();
        let name = self.ident("a material name")?;
        let body = if self.eat_punct('{') {
            self.block('}')?
        } else {
            self.expect_punct('=')?;
            Block { lets: Vec::new(), value: self.expr()? }
        };
        Ok(MaterialDecl { name, body })
    }

    /// `let NAME = EXPR [;]` ... `EXPR` `close`.
    fn block(&mut self, close: char) -> PResult<Block> {
        let mut lets = Vec::new();
        while self.is_keyword("let") {
            self.bump();
            let name = self.ident("a name")?;
            self.expect_punct('=')?;
            lets.push((name, self.expr()?));
            self.eat_punct(';');
        }
        let value = self.expr()?;
        self.eat_punct(';');
        self.expect_punct(close)?;
        Ok(Block { lets, value })
    }

    /// Enters one level of nesting at `span`; an error past `MAX_DEPTH`.
    fn enter(&mut self, span: &Span) -> PResult<()> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return self.error(
                format!("expression nested too deeply (more than {MAX_DEPTH} levels)"),
                "nesting limit reached here",
                span.clone(),
            );
        }
        Ok(())
    }

    fn expr(&mut self) -> PResult<Expr> {
        let depth = self.depth;
        let r = self.binary(0);
        self.depth = depth;
        r
    }

    /// Operators by precedence: level 0 is `+ -`, level 1 `* /`.
    fn binary(&mut self, level: usize) -> PResult<Expr> {
        const LEVELS: [&[(char, BinOp)]; 2] = [&[('+', BinOp::Add), ('-', BinOp::Sub)], &[('*', BinOp::Mul), ('/', BinOp::Div)]];
        let mut lhs = if level + 1 < LEVELS.len() { self.binary(level + 1)? } else { self.unary()? };
        let depth = self.depth;
        while let Some(&(_, op)) = LEVELS[level].iter().find(|(c, _)| self.is_punct(*c)) {
            let op_span = self.bump().span;
            self.enter(&op_span)?;
            let rhs = if level + 1 < LEVELS.len() { self.binary(level + 1)? } else { self.unary()? };
            let span = lhs.span.start..rhs.span.end;
            lhs = Expr { kind: ExprKind::Binary(op, Box::new(lhs), Box::new(rhs)), span };
        }
        self.depth = depth;
        Ok(lhs)
    }

    fn unary(&mut self) -> PResult<Expr> {
        if self.is_punct('-') {
            let start = self.bump().span;
            self.enter(&start)?;
            let inner = self.unary()?;
            self.depth -= 1;
            let span = start.start..inner.span.end;
            return Ok(Expr { kind: ExprKind::Neg(Box::new(inner)), span });
        }
        self.primary()
    }

    fn primary(&mut self) -> PResult<Expr> {
        let t = self.peek().clone();
        match t.tok {
            Tok::Number(Some(v)) => {
                self.bump();
                Ok(Expr { kind: ExprKind::Number(v), span: t.span })
            }
            Tok::Number(None) => {
                self.bump();
                self.error("number literal is not a finite 32-bit float", "out of range: values must be finite", t.span)
            }
            Tok::Punct('(') => {
                self.bump();
                self.enter(&t.span)?;
                let inner = self.expr()?;
                self.depth -= 1;
                let end = self.expect_punct(')')?;
                Ok(Expr { span: t.span.start..end.end, ..inner })
            }
            Tok::Ident(ref n) if n == "slab" && self.tokens.get(self.pos + 1).is_some_and(|n| n.tok == Tok::Punct('{')) => {
                self.bump();
                self.bump();
                self.enter(&t.span)?;
                let mut fields = Vec::new();
                while !self.is_punct('}') {
                    let field = self.ident("a field name")?;
                    self.expect_punct(':')?;
                    fields.push((field, self.expr()?));
                    if !self.eat_punct(',') {
                        break;
                    }
                }
                let end = self.expect_punct('}')?;
                self.depth -= 1;
                Ok(Expr { kind: ExprKind::Slab(fields), span: t.span.start..end.end })
            }
            Tok::Ident(_) => self.name_or_call(),
            _ => self.expected("an expression"),
        }
    }

    fn name_or_call(&mut self) -> PResult<Expr> {
        let mut path = vec![self.ident("a name")?];
        while self.eat_punct('.') {
            path.push(self.ident("a name after `.`")?);
        }
        let start = path[0].span.start;
        let mut end = path.last().expect("one name").span.end;
        if !self.is_punct('(') {
            return Ok(Expr { kind: ExprKind::Name(path), span: start..end });
        }
        let open = self.bump().span;
        self.enter(&open)?;
        let mut args = Vec::new();
        while !self.is_punct(')') {
            let named = matches!(self.peek().tok, Tok::Ident(_)) && self.tokens.get(self.pos + 1).is_some_and(|t| t.tok == Tok::Punct(':'));
            let name = if named {
                let n = self.ident("an argument name")?;
                self.bump();
                Some(n)
            } else {
                None
            };
            args.push(Arg { name, value: self.expr()? });
            if !self.eat_punct(',') {
                break;
            }
        }
        end = self.expect_punct(')')?.end;
        self.depth -= 1;
        Ok(Expr { kind: ExprKind::Call { callee: path, args }, span: start..end })
    }
}

fn describe(tok: &Tok) -> String {
    match tok {
        Tok::Ident(n) => format!("`{n}`"),
        Tok::Number(_) => "a number".into(),
        Tok::Str(_) => "a string".into(),
        Tok::Punct(c) => format!("`{c}`"),
        Tok::Arrow => "`->`".into(),
        Tok::Eof => "the end of the file".into(),
    }
}

/// The `//` comments on the lines right above `start`, joined: a param's
/// documentation. A blank line ends it.
fn doc_above(text: &str, comments: &[Comment], start: usize) -> Option<String> {
    let mut lines = Vec::new();
    let mut next = start;
    for c in comments.iter().rev().filter(|c| c.span.end <= start) {
        let gap = &text[c.span.end..next];
        let line_start = text[..c.span.start].rfind('\n').map_or(0, |n| n + 1);
        if gap.chars().filter(|&ch| ch == '\n').count() != 1 || !gap.trim().is_empty() || !text[line_start..c.span.start].trim().is_empty()
        {
            break;
        }
        lines.push(c.text.clone());
        next = line_start;
    }
    lines.reverse();
    (!lines.is_empty()).then(|| lines.join(" "))
}
