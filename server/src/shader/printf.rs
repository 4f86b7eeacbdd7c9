//! `debugPrintf` in WGSL, the front: calls are taken out of the source
//! text before naga sees it, since naga 30 has no string literals.
//!
//! The syntax is wgpu's native printf (gfx-rs/wgpu PR 9389): an
//! `enable wgpu_debug_printf;` directive, blanked here, and statements
//! `debugPrintf("x = %f, n = %v3f", x, n);`. Call site `k` of a file becomes
//!
//! ```wgsl
//! { var loupe_printf_<tag>_<k>_0_arg = x; var loupe_printf_<tag>_<k>_1_arg = n;
//!   var loupe_printf_<tag>_<k>_site: u32; loupe_printf_<tag>_<k>_site = 1u; }
//! ```
//!
//! The `var`s keep each argument as a local of its inferred (concrete) type,
//! one per argument even when two arguments are the same expression; the
//! store to the `_site` variable marks where the call was, so the
//! instrumenter (`shader::instrument_printf`) can put the write there. With
//! no pixel selected the block is dead stores to locals nobody reads,
//! which drivers drop. `<tag>` is a hash of the file's display path: sites
//! from several files composed into one module stay apart. Argument text is
//! copied unchanged, and [`Prints::original`] maps every offset of the
//! rewritten text back to the file, so naga's diagnostics keep pointing at
//! what the user wrote.

use std::ops::Range;
use std::sync::Arc;

use crate::diag::Code;

/// The directive that enables prints, as wgpu's native feature spells it.
pub const ENABLE: &str = "wgpu_debug_printf";
/// The call, as wgpu's native feature spells it.
pub const CALL: &str = "debugPrintf";
/// The value stored to a site's marker: naga may zero a local declared
/// in a loop with a store of its own, which is not the site.
pub const MARK: u32 = 1;
/// What every generated name starts with.
pub const PREFIX: &str = "loupe_printf_";

/// A file's text with its prints taken out, and what they were.
#[derive(Debug, Clone, Default)]
pub struct Prints {
    /// The text naga is given.
    pub text: Arc<str>,
    /// The file's tag in generated names.
    pub tag: u32,
    pub sites: Vec<Site>,
    /// Pieces of the rewritten text in order; offsets in the pieces not
    /// copied from the file map to the call they replace.
    pieces: Vec<Piece>,
    /// What is wrong with the prints as written (found before parsing).
    pub problems: Vec<Problem>,
}

#[derive(Debug, Clone)]
struct Piece {
    new: Range<usize>,
    original: Range<usize>,
    copied: bool,
}

/// One `debugPrintf` statement.
#[derive(Debug, Clone, PartialEq)]
pub struct Site {
    /// `debugPrintf` to `;`, in the file.
    pub call: Range<usize>,
    pub format: Vec<Segment>,
    /// Each argument's text, in the file.
    pub args: Vec<Range<usize>>,
}

/// A piece of a format string.
#[derive(Debug, Clone, PartialEq)]
pub enum Segment {
    Text(String),
    Spec(Spec),
}

/// One placeholder: `%[.precision][vN]conversion`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Spec {
    pub conversion: Conversion,
    /// 1 for a scalar, 2 to 4 for `%vN…`.
    pub components: u8,
    pub precision: Option<u8>,
}

/// Vulkan debugPrintf's conversions.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Conversion {
    /// `%d`, `%i`
    Signed,
    /// `%u`
    Unsigned,
    /// `%x`
    Hex,
    /// `%f`
    Fixed,
    /// `%e`
    Exponent,
    /// `%g`
    General,
}

impl Conversion {
    pub fn is_float(self) -> bool {
        matches!(self, Conversion::Fixed | Conversion::Exponent | Conversion::General)
    }
}

/// A mistake in a print, found in the text.
#[derive(Debug, Clone, PartialEq)]
pub struct Problem {
    pub code: Code,
    pub message: String,
    pub range: Range<usize>,
    pub label: String,
}

impl Prints {
    /// Takes the prints out of `text`; `tag` names the file in the
    /// generated names ([`tag_of`]).
    pub fn of(text: &str, tag: u32) -> Prints {
        // Most files print nothing: no scan, no copy.
        if !text.contains(CALL) && !text.contains(ENABLE) {
            return Prints { text: text.into(), tag, ..Prints::default() };
        }
        let mut scan = Scanner { text: text.as_bytes(), at: 0, last: None, before: None };
        let mut blanked = text.as_bytes().to_vec();
        let mut calls = Vec::new();
        let mut problems = Vec::new();
        let mut enabled = false;
        while let Some(word) = scan.next_word() {
            match &text[word.clone()] {
                "enable" => enabled |= blank_enable(text, word.start, &mut blanked),
                CALL => match scan.call(text, word.start) {
                    Ok(site) => calls.push(site),
                    Err(p) => problems.push(p),
                },
                _ => {}
            }
        }
        let blanked = String::from_utf8(blanked).expect("only ASCII bytes were replaced by spaces");
        if !enabled && let Some(first) = calls.first().map(|s: &Site| s.call.clone()).or(problems.first().map(|p| p.range.clone())) {
            problems.push(Problem {
                code: Code::PrintfSyntax,
                message: format!("`{CALL}` needs the directive `enable {ENABLE};` at the top of the file"),
                range: first.start..first.start + CALL.len(),
                label: "printed here".into(),
            });
        }
        let mut out = Prints { tag, ..Prints::default() };
        let mut text_out = String::with_capacity(blanked.len());
        let mut copied_to = 0;
        for (k, site) in calls.into_iter().enumerate() {
            if let Err(p) = site.check_counts() {
                problems.push(p);
            }
            out.copy(&mut text_out, &blanked, copied_to..site.call.start);
            out.insert(&mut text_out, "{ ", site.call.start);
            for (i, arg) in site.args.iter().enumerate() {
                out.insert(&mut text_out, &format!("var {} = ", arg_var(tag, k, i)), site.call.start);
                out.copy(&mut text_out, &blanked, arg.clone());
                out.insert(&mut text_out, "; ", site.call.start);
            }
            let marker = site_var(tag, k);
            out.insert(&mut text_out, &format!("var {marker}: u32; {marker} = {MARK}u; }}"), site.call.start);
            copied_to = site.call.end;
            out.sites.push(site);
        }
        out.copy(&mut text_out, &blanked, copied_to..blanked.len());
        out.text = text_out.into();
        out.problems = problems;
        out
    }

    fn copy(&mut self, out: &mut String, from: &str, range: Range<usize>) {
        let start = out.len();
        out.push_str(&from[range.clone()]);
        self.pieces.push(Piece { new: start..out.len(), original: range, copied: true });
    }

    fn insert(&mut self, out: &mut String, text: &str, at: usize) {
        let start = out.len();
        out.push_str(text);
        self.pieces.push(Piece { new: start..out.len(), original: at..at, copied: false });
    }

    /// The offset in the file of offset `at` of [`Prints::text`]: the same
    /// character for copied text, the call's start for generated text.
    pub fn original(&self, at: usize) -> usize {
        if self.pieces.is_empty() {
            return at;
        }
        let i = self.pieces.partition_point(|p| p.new.end <= at).min(self.pieces.len() - 1);
        let p = &self.pieces[i];
        if p.copied { p.original.start + at.saturating_sub(p.new.start).min(p.original.len()) } else { p.original.start }
    }

    pub fn original_range(&self, r: Range<usize>) -> Range<usize> {
        let start = self.original(r.start);
        start..self.original(r.end).max(start)
    }
}

impl Site {
    fn check_counts(&self) -> Result<(), Problem> {
        let wanted = self.format.iter().filter(|s| matches!(s, Segment::Spec(_))).count();
        if wanted == self.args.len() {
            return Ok(());
        }
        let plural = |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
        let range = match self.args.get(wanted) {
            Some(extra) => extra.start..self.args.last().map_or(extra.end, |a| a.end),
            None => self.call.clone(),
        };
        Err(Problem {
            code: Code::PrintfArguments,
            message: format!(
                "the format string has {} but the call passes {}",
                plural(wanted, "placeholder"),
                plural(self.args.len(), "argument")
            ),
            range,
            label: if self.args.len() > wanted { "not printed".into() } else { "too few arguments".into() },
        })
    }

    /// The placeholders in order.
    pub fn specs(&self) -> impl Iterator<Item = Spec> + '_ {
        self.format.iter().filter_map(|s| match s {
            Segment::Spec(spec) => Some(*spec),
            Segment::Text(_) => None,
        })
    }
}

/// Blanks `enable …wgpu_debug_printf…;` at `at` (the word `enable`):
/// the whole directive when it enables nothing else, else the one item.
fn blank_enable(text: &str, at: usize, out: &mut [u8]) -> bool {
    let Some(len) = text[at..].find(';') else { return false };
    let end = at + len;
    let list = at + "enable".len()..end;
    let mut items = Vec::new();
    let mut start = list.start;
    for part in text[list.clone()].split(',') {
        items.push(start..start + part.len());
        start += part.len() + 1;
    }
    let Some(i) = items.iter().position(|r| text[r.clone()].trim() == ENABLE) else { return false };
    let blank = if items.len() == 1 {
        at..end + 1
    } else if i + 1 < items.len() {
        items[i].start..items[i + 1].start
    } else {
        items[i - 1].end..items[i].end
    };
    out[blank].iter_mut().filter(|b| **b != b'\n').for_each(|b| *b = b' ');
    true
}

/// Walks WGSL text word by word, skipping comments.
struct Scanner<'a> {
    text: &'a [u8],
    at: usize,
    /// The last character that was neither space nor comment.
    last: Option<u8>,
    /// `last` before the word [`Scanner::next_word`] returned.
    before: Option<u8>,
}

fn is_word(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_' || b >= 0x80
}

impl Scanner<'_> {
    fn peek(&self) -> Option<u8> {
        self.text.get(self.at).copied()
    }

    /// Skips spaces and comments (`//…`, nested `/* … */`).
    fn skip_blank(&mut self) {
        while let Some(b) = self.peek() {
            if b.is_ascii_whitespace() {
                self.at += 1;
            } else if self.text[self.at..].starts_with(b"//") {
                while self.peek().is_some_and(|b| b != b'\n') {
                    self.at += 1;
                }
            } else if self.text[self.at..].starts_with(b"/*") {
                let mut depth = 0;
                while self.at < self.text.len() {
                    if self.text[self.at..].starts_with(b"/*") {
                        depth += 1;
                        self.at += 2;
                    } else if self.text[self.at..].starts_with(b"*/") {
                        depth -= 1;
                        self.at += 2;
                        if depth == 0 {
                            break;
                        }
                    } else {
                        self.at += 1;
                    }
                }
            } else {
                return;
            }
        }
    }

    /// The next identifier-like word outside comments.
    fn next_word(&mut self) -> Option<Range<usize>> {
        loop {
            self.skip_blank();
            let b = self.peek()?;
            if is_word(b) {
                let start = self.at;
                self.before = self.last;
                while self.peek().is_some_and(is_word) {
                    self.at += 1;
                }
                self.last = Some(b'a');
                if !b.is_ascii_digit() {
                    return Some(start..self.at);
                }
            } else {
                self.last = Some(b);
                self.at += 1;
            }
        }
    }

    /// Parses a call whose name starts at `start` (the scanner stands
    /// after the name) up to its `;`.
    fn call(&mut self, text: &str, start: usize) -> Result<Site, Problem> {
        let name = start..start + CALL.len();
        let problem = |code, message: String, range: Range<usize>, label: &str| Problem { code, message, range, label: label.into() };
        if !matches!(self.before, None | Some(b';' | b'{' | b'}')) {
            return Err(problem(
                Code::PrintfSyntax,
                format!("`{CALL}` is a statement: it cannot be used as a value"),
                name,
                "used inside an expression",
            ));
        }
        self.skip_blank();
        if self.peek() != Some(b'(') {
            return Err(problem(Code::PrintfSyntax, format!("`{CALL}` must be called: `{CALL}(\"…\", …);`"), name, "not called"));
        }
        self.at += 1;
        self.skip_blank();
        if self.peek() != Some(b'"') {
            let here = self.at..self.at + 1;
            return Err(problem(Code::PrintfSyntax, format!("`{CALL}`'s first argument must be a string literal"), here, "expected `\"`"));
        }
        let open = self.at;
        let line_end = text[open..].find('\n').map_or(text.len(), |n| open + n);
        let Some(close) = text[open + 1..line_end].find('"').map(|n| open + 1 + n) else {
            self.at = line_end;
            return Err(problem(Code::PrintfSyntax, "unterminated string".into(), open..line_end, "the string is not closed on this line"));
        };
        let format = parse_format(&text[open + 1..close]).map_err(|(at, message)| {
            let at = open + 1 + at;
            problem(Code::PrintfFormat, message, at..(at + 2).min(close), "here")
        })?;
        self.at = close + 1;
        let mut args = Vec::new();
        loop {
            self.skip_blank();
            match self.peek() {
                Some(b')') => {
                    self.at += 1;
                    break;
                }
                Some(b',') => {
                    self.at += 1;
                    args.push(self.argument(text)?);
                }
                _ => {
                    let here = self.at..(self.at + 1).min(text.len());
                    return Err(problem(Code::PrintfSyntax, format!("expected `,` or `)` in `{CALL}`"), here, "here"));
                }
            }
        }
        self.skip_blank();
        if self.peek() != Some(b';') {
            return Err(problem(
                Code::PrintfSyntax,
                format!("`{CALL}` is a statement: end it with `;`"),
                start..self.at,
                "used inside an expression",
            ));
        }
        self.at += 1;
        self.last = Some(b';');
        Ok(Site { call: start..self.at, format, args })
    }

    /// One argument: text up to a `,` or `)` outside brackets.
    fn argument(&mut self, text: &str) -> Result<Range<usize>, Problem> {
        self.skip_blank();
        let start = self.at;
        let mut depth = 0usize;
        let mut end = start;
        loop {
            self.skip_blank();
            let Some(b) = self.peek() else {
                return Err(Problem {
                    code: Code::PrintfSyntax,
                    message: format!("`{CALL}` is not closed"),
                    range: start..text.len(),
                    label: "expected `)`".into(),
                });
            };
            match b {
                b'(' | b'[' => depth += 1,
                b')' | b']' if depth > 0 => depth -= 1,
                b',' | b')' if depth == 0 => break,
                _ => {}
            }
            self.at += 1;
            end = self.at;
        }
        if end == start {
            let here = start..start + 1;
            return Err(Problem { code: Code::PrintfSyntax, message: "an argument is missing".into(), range: here, label: "here".into() });
        }
        Ok(start..end)
    }
}

/// Parses a format string into text and placeholders; on error, the byte
/// offset in the string and why.
pub fn parse_format(s: &str) -> Result<Vec<Segment>, (usize, String)> {
    let mut out = Vec::new();
    let mut text = String::new();
    let mut chars = s.char_indices().peekable();
    while let Some((at, c)) = chars.next() {
        if c != '%' {
            text.push(c);
            continue;
        }
        if chars.next_if(|(_, c)| *c == '%').is_some() {
            text.push('%');
            continue;
        }
        let mut precision = None;
        if chars.next_if(|(_, c)| *c == '.').is_some() {
            let mut digits = String::new();
            while let Some((_, d)) = chars.next_if(|(_, c)| c.is_ascii_digit()) {
                digits.push(d);
            }
            precision =
                Some(digits.parse::<u8>().ok().filter(|p| *p <= 20).ok_or((at, "a precision is 0 to 20 digits: `%.3f`".to_owned()))?);
        }
        let mut components = 1;
        if chars.next_if(|(_, c)| *c == 'v').is_some() {
            components = match chars.next() {
                Some((_, n @ '2'..='4')) => n as u8 - b'0',
                _ => return Err((at, "a vector placeholder names 2, 3 or 4 components: `%v3f`".to_owned())),
            };
        }
        let conversion = match chars.next().map(|(_, c)| c) {
            Some('d' | 'i') => Conversion::Signed,
            Some('u') => Conversion::Unsigned,
            Some('x') => Conversion::Hex,
            Some('f') => Conversion::Fixed,
            Some('e') => Conversion::Exponent,
            Some('g') => Conversion::General,
            Some(other) => return Err((at, format!("`%{other}` is not a placeholder; use %d %i %u %x %f %e %g, %vN… or %%"))),
            None => return Err((at, "the format string ends inside a placeholder".to_owned())),
        };
        if precision.is_some() && !conversion.is_float() {
            return Err((at, "a precision applies to %f, %e and %g only".to_owned()));
        }
        if !text.is_empty() {
            out.push(Segment::Text(std::mem::take(&mut text)));
        }
        out.push(Segment::Spec(Spec { conversion, components, precision }));
    }
    if !text.is_empty() {
        out.push(Segment::Text(text));
    }
    Ok(out)
}

impl Site {
    /// Words a record of this site holds after its site word.
    pub fn words(&self) -> usize {
        self.specs().map(|s| usize::from(s.components)).sum()
    }

    /// The printed line from a record's argument words ([`Site::words`]
    /// of them), and each argument's value (a number, or an array of them
    /// for a vector; a float that is not finite as a string).
    pub fn render(&self, words: &[u32]) -> (String, Vec<serde_json::Value>) {
        let mut text = String::new();
        let mut values = Vec::new();
        let mut words = words.iter().copied();
        for segment in &self.format {
            match segment {
                Segment::Text(t) => text.push_str(t),
                Segment::Spec(spec) => {
                    let parts: Vec<(String, serde_json::Value)> =
                        (0..spec.components).map(|_| spec.render(words.next().unwrap_or_default())).collect();
                    text.push_str(&parts.iter().map(|(t, _)| t.as_str()).collect::<Vec<_>>().join(", "));
                    let mut v: Vec<serde_json::Value> = parts.into_iter().map(|(_, v)| v).collect();
                    values.push(if v.len() == 1 { v.remove(0) } else { serde_json::Value::Array(v) });
                }
            }
        }
        (text, values)
    }
}

impl Spec {
    /// One component as C's printf shows it, and its value.
    fn render(&self, word: u32) -> (String, serde_json::Value) {
        use serde_json::Value;
        match self.conversion {
            Conversion::Signed => ((word as i32).to_string(), Value::from(word as i32)),
            Conversion::Unsigned => (word.to_string(), Value::from(word)),
            Conversion::Hex => (format!("{word:x}"), Value::from(word)),
            float => {
                let x = f32::from_bits(word);
                let p = usize::from(self.precision.unwrap_or(6));
                let text = if x.is_nan() {
                    "nan".to_owned()
                } else if x.is_infinite() {
                    if x > 0.0 { "inf" } else { "-inf" }.to_owned()
                } else {
                    match float {
                        Conversion::Fixed => format!("{x:.p$}"),
                        Conversion::Exponent => exponent(f64::from(x), p),
                        _ => general(f64::from(x), p),
                    }
                };
                let value = if x.is_finite() { Value::from(f64::from(x)) } else { Value::from(text.clone()) };
                (text, value)
            }
        }
    }
}

/// C's `%.pe`: `1.500000e+00`.
fn exponent(x: f64, p: usize) -> String {
    let rust = format!("{x:.p$e}");
    let (mantissa, exp) = rust.split_once('e').unwrap_or((&rust, "0"));
    let exp: i32 = exp.parse().unwrap_or(0);
    format!("{mantissa}e{}{:02}", if exp < 0 { '-' } else { '+' }, exp.abs())
}

/// C's `%.pg`: `%e` or `%f` by the exponent, trailing zeros dropped.
fn general(x: f64, p: usize) -> String {
    let p = p.max(1);
    let exp: i32 = format!("{x:.*e}", p - 1).split_once('e').and_then(|(_, e)| e.parse().ok()).unwrap_or(0);
    let trim = |s: String| -> String {
        match s.split_once('e') {
            Some((m, e)) if m.contains('.') => format!("{}e{e}", m.trim_end_matches('0').trim_end_matches('.')),
            None if s.contains('.') => s.trim_end_matches('0').trim_end_matches('.').to_owned(),
            _ => s,
        }
    };
    if exp < -4 || exp >= p as i32 { trim(exponent(x, p - 1)) } else { trim(format!("{x:.*}", (p as i32 - 1 - exp) as usize)) }
}

/// A value a print can show: 32-bit scalars and vectors of f32, i32, u32
/// and bool, as (scalar kind, components).
pub fn printable(inner: &naga::TypeInner) -> Option<(naga::ScalarKind, u8)> {
    let (scalar, components) = match *inner {
        naga::TypeInner::Scalar(s) => (s, 1),
        naga::TypeInner::Vector { size, scalar } => (scalar, size as u8),
        _ => return None,
    };
    let bool = scalar.kind == naga::ScalarKind::Bool;
    (bool || scalar.width == 4).then_some((scalar.kind, components))
}

impl Prints {
    /// The arguments of this file's sites in `module` whose type cannot be
    /// printed or does not fit its placeholder.
    pub fn type_problems(&self, module: &naga::Module) -> Vec<Problem> {
        let mut out = Vec::new();
        let functions = module.functions.iter().map(|(_, f)| f).chain(module.entry_points.iter().map(|e| &e.function));
        for (_, var) in functions.flat_map(|f| f.local_variables.iter()) {
            let Some((tag, k, Some(i))) = var.name.as_deref().and_then(parse_var) else { continue };
            let (Some(site), true) = (self.sites.get(k), tag == self.tag) else { continue };
            let (Some(spec), Some(range)) = (site.specs().nth(i), site.args.get(i)) else { continue };
            let ty = module.types[var.ty]
                .name
                .clone()
                .unwrap_or_else(|| naga::common::wgsl::TypeContext::type_to_string(&module.to_ctx(), var.ty));
            let problem =
                |message: String| Problem { code: Code::PrintfType, message, range: range.clone(), label: format!("this is {ty}") };
            match printable(&module.types[var.ty].inner) {
                None => out.push(problem(format!("a {ty} cannot be printed: print scalars or vectors of f32, i32, u32 or bool"))),
                Some((kind, components)) => {
                    let float = kind == naga::ScalarKind::Float;
                    if spec.components != components || spec.conversion.is_float() != float {
                        out.push(problem(format!("`{}` does not fit a {ty}; {} would", spec, Spec::fitting(kind, components))));
                    }
                }
            }
        }
        out.sort_by_key(|p| p.range.start);
        out.dedup();
        out
    }
}

impl std::fmt::Display for Spec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("%")?;
        if let Some(p) = self.precision {
            write!(f, ".{p}")?;
        }
        if self.components > 1 {
            write!(f, "v{}", self.components)?;
        }
        let c = match self.conversion {
            Conversion::Signed => 'd',
            Conversion::Unsigned => 'u',
            Conversion::Hex => 'x',
            Conversion::Fixed => 'f',
            Conversion::Exponent => 'e',
            Conversion::General => 'g',
        };
        write!(f, "{c}")
    }
}

impl Spec {
    /// The plain placeholder for a value of this kind.
    fn fitting(kind: naga::ScalarKind, components: u8) -> Spec {
        let conversion = match kind {
            naga::ScalarKind::Float => Conversion::Fixed,
            naga::ScalarKind::Uint => Conversion::Unsigned,
            _ => Conversion::Signed,
        };
        Spec { conversion, components, precision: None }
    }
}

/// The tag of a file in generated names: from its display path, so the
/// same file gets the same names in every module it is composed into.
pub fn tag_of(display: &str) -> u32 {
    let hash = blake3::hash(display.as_bytes());
    u32::from_le_bytes(hash.as_bytes()[..4].try_into().expect("4 bytes"))
}

/// The local holding argument `i` of site `k`.
pub fn arg_var(tag: u32, k: usize, i: usize) -> String {
    format!("{PREFIX}{tag:08x}_{k}_{i}_arg")
}

/// The local whose store marks site `k`.
pub fn site_var(tag: u32, k: usize) -> String {
    format!("{PREFIX}{tag:08x}_{k}_site")
}

/// What a generated local is: the file's tag, the site, and the argument
/// (`None` for the site's marker).
pub fn parse_var(name: &str) -> Option<(u32, usize, Option<usize>)> {
    let mut parts = name.strip_prefix(PREFIX)?.split('_');
    let tag = u32::from_str_radix(parts.next()?, 16).ok()?;
    let k = parts.next()?.parse().ok()?;
    match (parts.next()?, parts.next(), parts.next()) {
        ("site", None, None) => Some((tag, k, None)),
        (i, Some("arg"), None) => Some((tag, k, Some(i.parse().ok()?))),
        _ => None,
    }
}

#[cfg(test)]
mod tests;
