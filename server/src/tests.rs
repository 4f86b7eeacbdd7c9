//! The crate's shape, read from its source text: no import circles. At
//! every level of the module tree (the top-level modules under `crate`,
//! the modules inside each of them, and so on down), the sibling modules
//! import each other one way only, so each can be read, and changed, below
//! the ones that use it. A child using its parent's items is not a circle.
//!
//! Only production code counts: a module declared under `#[cfg(test)]` (or
//! any `cfg` naming `test`: `tests.rs`, `testing.rs`, test directories) and
//! any item so marked (a `use` inside `mod tests { … }`) are left out, as
//! are comments and string literals. An import is a `use` of a
//! `crate::`, `super::` or `self::` path, or such a path written inline.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// A module's path under `crate`, e.g. `["render", "passes"]`.
type ModPath = Vec<String>;

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Ident(String),
    /// `::`
    Sep,
    Punct(char),
}

/// A token and the line it starts on.
type Token = (Tok, usize);

/// The tokens of `text`, comments and the contents of string and
/// character literals dropped, so a doc comment or a message naming a path
/// is not an import. Good enough for finding paths, not a Rust lexer.
fn tokens(text: &str) -> Vec<Token> {
    let c: Vec<char> = text.chars().collect();
    let (mut out, mut i, mut line) = (Vec::new(), 0, 1);
    let ident = |ch: char| ch.is_alphanumeric() || ch == '_';
    // Skips to just past `end` from `i`, counting lines; `escapes`: a
    // backslash escapes the next character.
    let skip_to = |i: &mut usize, line: &mut usize, end: &str, escapes: bool| {
        let end: Vec<char> = end.chars().collect();
        while *i < c.len() && !c[*i..].starts_with(&end) {
            let n = if escapes && c[*i] == '\\' { 2 } else { 1 };
            *line += c[*i..(*i + n).min(c.len())].iter().filter(|ch| **ch == '\n').count();
            *i += n;
        }
        *i += end.len();
    };
    while i < c.len() {
        let ch = c[i];
        let next = c.get(i + 1).copied();
        if ch == '\n' {
            line += 1;
            i += 1;
        } else if ch.is_whitespace() {
            i += 1;
        } else if ch == '/' && next == Some('/') {
            skip_to(&mut i, &mut line, "\n", false);
            line += 1;
        } else if ch == '/' && next == Some('*') {
            i += 2;
            skip_to(&mut i, &mut line, "*/", false);
        } else if ch == '"' {
            i += 1;
            skip_to(&mut i, &mut line, "\"", true);
        } else if let Some((text, hashes)) = raw_string(&c, i) {
            i = text;
            skip_to(&mut i, &mut line, &format!("\"{}", "#".repeat(hashes)), false);
        } else if ch == '\'' && (next == Some('\\') || c.get(i + 2) == Some(&'\'')) {
            // A character literal; otherwise a lifetime, whose name follows.
            i += if next == Some('\\') { 3 } else { 1 };
            skip_to(&mut i, &mut line, "'", false);
        } else if ident(ch) {
            let start = i;
            while i < c.len() && ident(c[i]) {
                i += 1;
            }
            out.push((Tok::Ident(c[start..i].iter().collect()), line));
        } else if ch == ':' && next == Some(':') {
            out.push((Tok::Sep, line));
            i += 2;
        } else {
            out.push((Tok::Punct(ch), line));
            i += 1;
        }
    }
    out
}

/// At a raw string's `r` (or `br`): where its text starts, and its `#`s.
fn raw_string(c: &[char], i: usize) -> Option<(usize, usize)> {
    if i > 0 && (c[i - 1].is_alphanumeric() || c[i - 1] == '_') {
        return None;
    }
    let r = if c[i] == 'b' { i + 1 } else { i };
    if c.get(r) != Some(&'r') {
        return None;
    }
    let hashes = c[r + 1..].iter().take_while(|h| **h == '#').count();
    (c.get(r + 1 + hashes) == Some(&'"')).then_some((r + 2 + hashes, hashes))
}

fn is(t: Option<&Token>, want: &Tok) -> bool {
    t.is_some_and(|(t, _)| t == want)
}

/// Just past the bracket that closes the one at `i`.
fn group_end(toks: &[Token], mut i: usize) -> usize {
    let mut depth = 0;
    while i < toks.len() {
        match toks[i].0 {
            Tok::Punct('(' | '[' | '{') => depth += 1,
            Tok::Punct(')' | ']' | '}') => depth -= 1,
            _ => {}
        }
        i += 1;
        if depth == 0 {
            break;
        }
    }
    i
}

/// Just past the item starting at `i`: its `;` or its body's closing
/// brace, whichever comes first outside brackets.
fn item_end(toks: &[Token], mut i: usize) -> usize {
    while i < toks.len() {
        match toks[i].0 {
            Tok::Punct('{') => return group_end(toks, i),
            Tok::Punct('(' | '[') => i = group_end(toks, i),
            Tok::Punct(';') => return i + 1,
            _ => i += 1,
        }
    }
    i
}

/// The tokens with every item under a `cfg` that names `test` taken out,
/// and every `#[path]` attribute reported (`path_attributes`).
fn production(toks: Vec<Token>, path_attributes: &mut Vec<usize>) -> Vec<Token> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        if is(toks.get(i), &Tok::Punct('#')) && is(toks.get(i + 1), &Tok::Punct('[')) {
            let end = group_end(&toks, i + 1);
            let attr = &toks[i + 2..end - 1];
            if is(attr.first(), &Tok::Ident("path".into())) {
                path_attributes.push(toks[i].1);
            }
            if is(attr.first(), &Tok::Ident("cfg".into())) && attr.iter().any(|(t, _)| *t == Tok::Ident("test".into())) {
                // The attributes that follow belong to the same item.
                let mut start = end;
                while is(toks.get(start), &Tok::Punct('#')) {
                    start = group_end(&toks, start + 1);
                }
                i = item_end(&toks, start);
                continue;
            }
        }
        out.push(toks[i].clone());
        i += 1;
    }
    out
}

/// Expands a use tree (`a::{b, c::{self, D}}`) into its paths, `self`
/// dropped, `as` renames ignored.
fn use_paths(toks: &[Tok], prefix: &[String], out: &mut Vec<Vec<String>>) {
    let mut path = prefix.to_vec();
    let mut i = 0;
    while i < toks.len() {
        match &toks[i] {
            Tok::Ident(s) if s == "as" => break,
            Tok::Ident(s) if s != "self" => path.push(s.clone()),
            Tok::Punct('{') => {
                let inner = &toks[i + 1..toks.len() - 1];
                let mut depth = 0;
                let mut start = 0;
                for (k, t) in inner.iter().enumerate() {
                    match t {
                        Tok::Punct('{') => depth += 1,
                        Tok::Punct('}') => depth -= 1,
                        Tok::Punct(',') if depth == 0 => {
                            use_paths(&inner[start..k], &path, out);
                            start = k + 1;
                        }
                        _ => {}
                    }
                }
                use_paths(&inner[start..], &path, out);
                return;
            }
            _ => {}
        }
        i += 1;
    }
    if !path.is_empty() {
        out.push(path);
    }
}

/// A path one file names: the absolute module path it resolves to (items
/// included) and the line that names it.
struct Named {
    target: Vec<String>,
    line: usize,
    text: String,
}

/// The `crate::`, `super::` and `self::` paths `toks` name, resolved from
/// module `at`.
fn named_paths(toks: &[Token], at: &[String]) -> Vec<Named> {
    let resolve = |p: &[String]| -> Option<Vec<String>> {
        let mut base: Vec<String> = match p.first()?.as_str() {
            "crate" => vec![],
            "super" | "self" => at.to_vec(),
            _ => return None,
        };
        let mut rest = p;
        if rest[0] == "crate" {
            rest = &rest[1..];
        }
        while let Some(first) = rest.first() {
            match first.as_str() {
                "super" => base.pop(),
                "self" => None,
                _ => break,
            };
            rest = &rest[1..];
        }
        base.extend(rest.iter().cloned());
        Some(base)
    };
    let mut out = Vec::new();
    let mut i = 0;
    while i < toks.len() {
        let (t, line) = &toks[i];
        if *t == Tok::Ident("use".into()) {
            // A use tree holds no `;`: the first one ends it.
            let end = toks[i..].iter().position(|(t, _)| *t == Tok::Punct(';')).map_or(toks.len(), |k| i + k + 1);
            let tree: Vec<Tok> = toks[i + 1..end - 1].iter().map(|(t, _)| t.clone()).collect();
            let mut paths = vec![];
            use_paths(&tree, &[], &mut paths);
            let text = format!("use {};", render(&tree));
            out.extend(paths.iter().filter_map(|p| Some(Named { target: resolve(p)?, line: *line, text: text.clone() })));
            i = end;
            continue;
        }
        if let Tok::Ident(first) = t
            && ["crate", "super", "self"].contains(&first.as_str())
            && is(toks.get(i + 1), &Tok::Sep)
        {
            let mut p = vec![first.clone()];
            let mut k = i + 1;
            while is(toks.get(k), &Tok::Sep)
                && let Some((Tok::Ident(s), _)) = toks.get(k + 1)
            {
                p.push(s.clone());
                k += 2;
            }
            out.extend(resolve(&p).map(|target| Named { target, line: *line, text: p.join("::") }));
            i = k;
            continue;
        }
        i += 1;
    }
    out
}

/// Tokens back to text, for the report.
fn render(toks: &[Tok]) -> String {
    let mut s = String::new();
    for t in toks {
        match t {
            Tok::Ident(x) => {
                if s.ends_with(|c: char| c.is_alphanumeric() || c == '_') {
                    s.push(' ');
                }
                s.push_str(x);
            }
            Tok::Sep => s.push_str("::"),
            Tok::Punct(',') => s.push_str(", "),
            Tok::Punct(c) => s.push(*c),
        }
    }
    s
}

/// The modules `toks` declare with a file of their own: `mod x;`, and
/// the names listed in a macro that expands to `mod $name;`
/// (`render::passes`'s `passes![…]`).
fn declared(toks: &[Token]) -> Vec<String> {
    let ident = |k: usize| match toks.get(k) {
        Some((Tok::Ident(s), _)) => Some(s.as_str()),
        _ => None,
    };
    let mut names = vec![];
    let mut macros = vec![];
    for k in 0..toks.len() {
        if ident(k) == Some("mod") && is(toks.get(k + 2), &Tok::Punct(';')) {
            names.extend(ident(k + 1).map(str::to_owned));
        }
        if ident(k) == Some("macro_rules") && is(toks.get(k + 1), &Tok::Punct('!')) {
            let body = &toks[k..item_end(toks, k)];
            if body.windows(2).any(|w| w[0].0 == Tok::Ident("mod".into()) && w[1].0 == Tok::Punct('$')) {
                macros.extend(ident(k + 2));
            }
        }
        if ident(k).is_some_and(|m| macros.contains(&m)) && is(toks.get(k + 1), &Tok::Punct('!')) {
            let list = &toks[k + 2..group_end(toks, k + 2)];
            names.extend(list.iter().filter_map(|(t, _)| if let Tok::Ident(s) = t { Some(s.clone()) } else { None }));
        }
    }
    names
}

/// A production module: its source file and its tokens, test items out.
struct Module {
    file: PathBuf,
    toks: Vec<Token>,
}

/// The crate's production modules, from `lib.rs`'s `mod` declarations
/// down (a module under a test `cfg` is never reached), and the `#[path]`
/// attributes met on the way.
fn modules(src: &Path) -> (BTreeMap<ModPath, Module>, Vec<String>) {
    let mut found = BTreeMap::new();
    let mut redirects = Vec::new();
    let mut todo: Vec<(ModPath, PathBuf)> = vec![(vec![], src.join("lib.rs"))];
    while let Some((path, file)) = todo.pop() {
        let text = std::fs::read_to_string(&file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        let mut attrs = vec![];
        let toks = production(tokens(&text), &mut attrs);
        redirects.extend(attrs.iter().map(|l| format!("{}:{l}", file.display())));
        // `foo.rs`'s children are in `foo/`; `mod.rs`'s and `lib.rs`'s beside it.
        let stem = file.file_stem().unwrap().to_str().unwrap();
        let dir = if stem == "mod" || path.is_empty() { file.parent().unwrap().to_owned() } else { file.with_extension("") };
        for name in declared(&toks) {
            let flat = dir.join(format!("{name}.rs"));
            let child = if flat.exists() { flat } else { dir.join(&name).join("mod.rs") };
            todo.push(([path.clone(), vec![name]].concat(), child));
        }
        found.insert(path, Module { file, toks });
    }
    (found, redirects)
}

/// Sibling imports: (parent, from, to) → the lines that make the edge.
type Edges = BTreeMap<(ModPath, String, String), Vec<String>>;

fn sibling_edges(modules: &BTreeMap<ModPath, Module>, root: &Path) -> Edges {
    let mut edges = Edges::new();
    for (at, m) in modules {
        for named in named_paths(&m.toks, at) {
            let common = at.iter().zip(&named.target).take_while(|(a, b)| a == b).count();
            if common >= at.len() || common >= named.target.len() {
                continue; // its own items, a child's or an ancestor's
            }
            let parent = at[..common].to_vec();
            let to = &named.target[common];
            if !modules.contains_key(&[parent.clone(), vec![to.clone()]].concat()) {
                continue; // an item of the common ancestor, not a module
            }
            let file = m.file.strip_prefix(root).unwrap_or(&m.file).display();
            edges.entry((parent, at[common].clone(), to.clone())).or_default().push(format!("{file}:{}: {}", named.line, named.text));
        }
    }
    for lines in edges.values_mut() {
        lines.dedup();
    }
    edges
}

/// The sets of sibling modules that import each other in a circle, with
/// the parent they are under.
fn circles(edges: &Edges) -> Vec<(ModPath, BTreeSet<String>)> {
    let mut by_parent: BTreeMap<&ModPath, BTreeMap<&str, BTreeSet<&str>>> = BTreeMap::new();
    for (parent, from, to) in edges.keys() {
        by_parent.entry(parent).or_default().entry(from.as_str()).or_default().insert(to.as_str());
    }
    let mut out = Vec::new();
    for (parent, graph) in by_parent {
        let reach = |from: &str| {
            let mut seen = BTreeSet::new();
            let mut todo = vec![from];
            while let Some(m) = todo.pop() {
                for next in graph.get(m).into_iter().flatten() {
                    if seen.insert(*next) {
                        todo.push(*next);
                    }
                }
            }
            seen
        };
        let reached: BTreeMap<&str, BTreeSet<&str>> = graph.keys().map(|m| (*m, reach(m))).collect();
        let mut seen = BTreeSet::new();
        for (m, r) in &reached {
            let circle: BTreeSet<String> =
                r.iter().filter(|n| reached.get(**n).is_some_and(|back| back.contains(m))).map(|n| (*n).to_owned()).collect();
            if circle.len() > 1 && seen.insert(circle.clone()) {
                out.push((parent.clone(), circle));
            }
        }
    }
    out
}

fn report(edges: &Edges, found: &[(ModPath, BTreeSet<String>)]) -> String {
    let mut s = String::new();
    for (parent, circle) in found {
        let under = if parent.is_empty() { "crate".to_owned() } else { format!("crate::{}", parent.join("::")) };
        s += &format!("\nunder {under}: {} import each other in a circle:\n", circle.iter().cloned().collect::<Vec<_>>().join(", "));
        for ((p, from, to), lines) in edges {
            if p == parent && circle.contains(from) && circle.contains(to) {
                s += &format!("  {from} → {to}\n");
                for l in lines.iter().take(4) {
                    s += &format!("    {l}\n");
                }
                if lines.len() > 4 {
                    s += &format!("    … and {} more\n", lines.len() - 4);
                }
            }
        }
    }
    s
}

#[test]
fn the_crate_has_no_import_circles() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let (modules, redirects) = modules(&root.join("src"));
    assert_eq!(redirects, Vec::<String>::new(), "`#[path]` attributes: a module's file is where Rust looks for it");
    let edges = sibling_edges(&modules, root);
    let edge = |parent: &[&str], from: &str, to: &str| {
        edges.contains_key(&(parent.iter().map(|s| (*s).to_owned()).collect(), from.to_owned(), to.to_owned()))
    };
    // The scan sees imports: a `use` inside a module, one at the top, one
    // by `super::`, and none from a test.
    assert!(edge(&["render"], "graph", "context") && edge(&[], "render", "scene"), "the scan sees imports: {:?}", edges.keys());
    assert!(edge(&["scene"], "overrides", "settings"), "the scan sees `super::` imports: {:?}", edges.keys());
    assert!(!modules.keys().any(|m| m.last().is_some_and(|n| n == "tests" || n == "testing")), "test modules are left out");
    let found = circles(&edges);
    assert!(found.is_empty(), "import circles:{}", report(&edges, &found));
}

#[test]
fn the_scan_reads_paths_not_comments_strings_or_tests() {
    let text = r###"
        // use crate::a::X;
        /* crate::a::Y */
        const S: &str = "crate::a::Z";
        const R: &str = r#"crate::a::W"#;
        const C: char = '{';
        use super::{b::{self, B}, c::C as D};
        fn f<'a>(x: &'a str) { crate::d::f(x) }
        #[cfg(test)]
        mod tests { use crate::a::T; }
    "###;
    let mut attrs = vec![];
    let toks = production(tokens(text), &mut attrs);
    let named: Vec<(String, usize)> = named_paths(&toks, &["m".into(), "n".into()]).iter().map(|n| (n.target.join("::"), n.line)).collect();
    assert_eq!(named, [("m::b".to_owned(), 7), ("m::b::B".to_owned(), 7), ("m::c::C".to_owned(), 7), ("d::f".to_owned(), 8)]);
}
