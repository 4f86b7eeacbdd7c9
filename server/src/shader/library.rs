//! The shader library: WGSL files read from disk, checked for the problems
//! that stop composition before it starts (unreadable, not UTF-8, empty, too
//! large), and scanned for `#define_import_path` / `#import` so the import
//! graph is known without compiling anything.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use super::printf::{self, Prints};
use crate::diag::{Code, Diagnostic, LineIndex, Location, display_path};

/// Files above this are refused: real shaders are a few hundred kilobytes at
/// most, and naga's parser holds the whole text and its IR in memory.
pub const MAX_FILE_BYTES: u64 = 8 << 20;

/// One WGSL file as the user wrote it.
#[derive(Debug, Clone)]
pub struct SourceFile {
    /// Path diagnostics show (relative to the working directory when under it).
    pub display: String,
    pub path: PathBuf,
    pub text: Arc<str>,
    pub lines: Arc<LineIndex>,
    /// Content hash: equal hashes mean nothing to recompile.
    pub hash: blake3::Hash,
    /// `#define_import_path` value and where it is written.
    pub import_path: Option<(String, Range<usize>)>,
    /// Every `#import`, as written (module part only).
    pub imports: Vec<Import>,
    /// Whether any preprocessor directive appears; files without one are
    /// plain WGSL and skip the composer entirely.
    pub has_directives: bool,
    /// The `debugPrintf` calls, and the text naga is given without them.
    pub prints: Arc<Prints>,
}

impl SourceFile {
    pub fn location(&self, range: Range<usize>) -> Location {
        self.lines.location(&self.display, &self.text, range)
    }

    /// The location of `range` of the text naga is given
    /// ([`Prints::text`]), in the file.
    pub fn composed_location(&self, range: Range<usize>) -> Location {
        self.location(self.prints.original_range(range))
    }

    /// The problems of its prints found before parsing, as diagnostics.
    pub fn print_problems(&self) -> impl Iterator<Item = Diagnostic> + '_ {
        self.prints.problems.iter().map(|p| self.print_problem(p))
    }

    pub fn print_problem(&self, p: &printf::Problem) -> Diagnostic {
        Diagnostic::error(p.code, p.message.clone()).with_label(self.location(p.range.clone()), p.label.clone(), true)
    }

    /// Builds a source file from text already in memory.
    pub fn from_text(display: String, path: PathBuf, text: Arc<str>) -> Self {
        let Directives { import_path, imports, has_directives } = scan_directives(&text);
        SourceFile {
            prints: Arc::new(Prints::of(&text, printf::tag_of(&display))),
            display,
            path,
            lines: Arc::new(LineIndex::new(&text)),
            hash: blake3::hash(text.as_bytes()),
            text,
            import_path,
            imports,
            has_directives,
        }
    }

    /// Reads a file, turning every way it can be unusable into a diagnostic.
    pub fn read(path: &Path, display: String) -> Result<Self, Diagnostic> {
        let here = Location::file_start(&display);
        let meta = std::fs::metadata(path).map_err(|e| Diagnostic::error(Code::Io, format!("cannot read file: {e}")).at(here.clone()))?;
        if meta.len() > MAX_FILE_BYTES {
            return Err(too_large(meta.len(), here));
        }
        let bytes = std::fs::read(path).map_err(|e| Diagnostic::error(Code::Io, format!("cannot read file: {e}")).at(here))?;
        Self::from_bytes(path, display, bytes)
    }

    /// Checks content already read (the watcher reads it to hash it).
    pub fn from_bytes(path: &Path, display: String, bytes: Vec<u8>) -> Result<Self, Diagnostic> {
        let here = Location::file_start(&display);
        if bytes.len() as u64 > MAX_FILE_BYTES {
            return Err(too_large(bytes.len() as u64, here));
        }
        if bytes.iter().all(u8::is_ascii_whitespace) {
            return Err(Diagnostic::error(Code::EmptyFile, "file is empty").at(here));
        }
        let text = String::from_utf8(bytes).map_err(|e| {
            let valid = e.utf8_error().valid_up_to();
            let prefix = std::str::from_utf8(&e.as_bytes()[..valid]).unwrap_or_default();
            let (line, column) = LineIndex::new(prefix).line_col(prefix, valid);
            let loc = Location { file: display.clone(), line, column, end_line: line, end_column: column + 1 };
            Diagnostic::error(Code::Encoding, format!("file is not valid UTF-8 (invalid byte at offset {valid})")).with_label(
                loc,
                "invalid UTF-8 here",
                true,
            )
        })?;
        Ok(SourceFile::from_text(display, path.to_owned(), text.into()))
    }
}

fn too_large(len: u64, at: Location) -> Diagnostic {
    Diagnostic::error(Code::FileTooLarge, format!("file is {len} bytes; the limit is {MAX_FILE_BYTES} bytes")).at(at)
}

/// One module an `#import` line names.
#[derive(Clone, Debug)]
pub struct Import {
    /// The module part, as written.
    pub module: String,
    /// The line's import specification, in the file's bytes.
    pub range: Range<usize>,
    /// The `#ifdef`-style conditions the line sits under.
    pub guards: Vec<Guard>,
}

/// A condition an `#import` sits under, as far as the import graph needs
/// it: a def defined, a def not defined, or an `#if` expression, which may
/// hold either way.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Guard {
    Defined(String),
    Undefined(String),
    Unknown,
}

impl Guard {
    fn negated(&self) -> Guard {
        match self {
            Guard::Defined(d) => Guard::Undefined(d.clone()),
            Guard::Undefined(d) => Guard::Defined(d.clone()),
            Guard::Unknown => Guard::Unknown,
        }
    }

    /// Whether the condition may hold with every def of `surely` defined
    /// and none outside `maybe`.
    fn may_hold(&self, surely: &BTreeSet<String>, maybe: &BTreeSet<String>) -> bool {
        match self {
            Guard::Defined(d) => maybe.contains(d),
            Guard::Undefined(d) => !surely.contains(d),
            Guard::Unknown => true,
        }
    }

    /// The condition an `#if…` directive's rest of line opens (`ifdef X`,
    /// `ifndef X`, `if …`).
    fn of(directive: &str) -> Guard {
        let mut words = directive.split_whitespace();
        match (words.next(), words.next()) {
            (Some("ifdef"), Some(d)) => Guard::Defined(d.to_owned()),
            (Some("ifndef"), Some(d)) => Guard::Undefined(d.to_owned()),
            _ => Guard::Unknown,
        }
    }
}

/// One `#if…` … `#endif` being read: the negations of the branches passed
/// and the current branch's own condition (none after a bare `#else`).
struct Branch {
    passed: Vec<Guard>,
    current: Option<Guard>,
}

struct Directives {
    import_path: Option<(String, Range<usize>)>,
    imports: Vec<Import>,
    has_directives: bool,
}

/// Scans preprocessor lines. Only the module part of an import matters for
/// the graph: `#import a::b::{x, y}` and `#import a::b as c` import `a::b`,
/// and `#import a::b::item` is resolved against known paths later. Each
/// import keeps the conditions it sits under (naga_oil's `#ifdef`,
/// `#ifndef`, `#if`, `#else`, `#else ifdef`, `#endif`), so a pipeline is
/// built only from the imports its defs can reach.
fn scan_directives(text: &str) -> Directives {
    // Every directive starts with `#`; most WGSL files have none.
    if !text.contains('#') {
        return Directives { import_path: None, imports: Vec::new(), has_directives: false };
    }
    let mut import_path = None;
    let mut imports = Vec::new();
    let mut open: Vec<Branch> = Vec::new();
    let mut has_directives = false;
    let mut offset = 0;
    for line in text.split_inclusive('\n') {
        let start = offset;
        offset += line.len();
        let trimmed = line.trim_start();
        if !trimmed.starts_with('#') {
            continue;
        }
        has_directives = true;
        let lead = line.len() - trimmed.len();
        let body = trimmed.trim_end();
        if let Some(rest) = body.strip_prefix("#define_import_path") {
            let name = rest.trim();
            let at = start + lead + body.len() - rest.trim_start().len();
            import_path = Some((name.to_owned(), at..at + name.len()));
        } else if let Some(rest) = body.strip_prefix("#import") {
            let spec = rest.trim();
            let at = start + lead + body.len() - rest.trim_start().len();
            let under: Vec<Guard> = open.iter().flat_map(|b| b.passed.iter().chain(&b.current)).cloned().collect();
            for module in import_modules(spec) {
                imports.push(Import { module, range: at..at + spec.len(), guards: under.clone() });
            }
        } else if let Some(rest) = body.strip_prefix("#else") {
            if let Some(b) = open.last_mut() {
                if let Some(c) = b.current.take() {
                    b.passed.push(c.negated());
                }
                let rest = rest.trim();
                b.current = rest.starts_with("if").then(|| Guard::of(rest));
            }
        } else if body.starts_with("#endif") {
            open.pop();
        } else if let Some(rest) = body.strip_prefix('#').filter(|r| r.starts_with("if")) {
            open.push(Branch { passed: Vec::new(), current: Some(Guard::of(rest)) });
        }
    }
    Directives { import_path, imports, has_directives }
}

/// The module paths one `#import` line names. Handles naga_oil's forms:
/// `a::b`, `a::b as c`, `a::b::{x, y}`, `a::{b, c::d}`, `"file.wgsl"`.
fn import_modules(spec: &str) -> Vec<String> {
    let spec = spec.split(" as ").next().unwrap_or(spec).trim();
    if let Some(q) = spec.strip_prefix('"') {
        return vec![q.trim_end_matches('"').to_owned()];
    }
    match spec.find("::{") {
        Some(brace) => {
            let base = &spec[..brace];
            let inner = spec[brace + 3..].trim_end_matches('}');
            // Items inside braces may be modules (`a::{b, c::d}`); keep the
            // base plus every multi-segment inner path as candidates.
            let mut out = vec![base.to_owned()];
            for item in inner.split(',').map(str::trim).filter(|s| !s.is_empty()) {
                let item = item.split(" as ").next().unwrap_or(item).trim();
                out.push(format!("{base}::{item}"));
            }
            out
        }
        None => vec![spec.to_owned()],
    }
}

/// Every WGSL file of the project, by display path, with the import graph.
#[derive(Debug, Clone, Default)]
pub struct Library {
    files: BTreeMap<String, Arc<SourceFile>>,
    /// `#define_import_path` → display path of the file that declares it.
    providers: HashMap<String, String>,
    /// Problems found while indexing (duplicate import paths).
    pub diagnostics: Vec<Diagnostic>,
}

impl Library {
    pub fn new(files: impl IntoIterator<Item = SourceFile>) -> Self {
        let mut lib = Library::default();
        for f in files {
            lib.files.insert(f.display.clone(), Arc::new(f));
        }
        lib.reindex();
        lib
    }

    /// Adds or replaces one file (hot reload); returns whether its content changed.
    pub fn upsert(&mut self, file: SourceFile) -> bool {
        let changed = self.files.get(&file.display).is_none_or(|old| old.hash != file.hash);
        if changed {
            self.files.insert(file.display.clone(), Arc::new(file));
            self.reindex();
        }
        changed
    }

    pub fn remove(&mut self, display: &str) -> bool {
        let removed = self.files.remove(display).is_some();
        if removed {
            self.reindex();
        }
        removed
    }

    fn reindex(&mut self) {
        self.providers.clear();
        self.diagnostics.clear();
        for f in self.files.values() {
            let Some((name, range)) = &f.import_path else { continue };
            if let Some(first) = self.providers.get(name) {
                let first = &self.files[first];
                let (_, first_range) = first.import_path.as_ref().expect("provider has a path");
                self.diagnostics.push(
                    Diagnostic::error(Code::ImportDuplicate, format!("import path `{name}` is defined twice"))
                        .with_label(f.location(range.clone()), "defined again here", true)
                        .with_label(first.location(first_range.clone()), "first defined here", false),
                );
            } else {
                self.providers.insert(name.clone(), f.display.clone());
            }
        }
    }

    pub fn get(&self, display: &str) -> Option<&Arc<SourceFile>> {
        self.files.get(display)
    }

    pub fn files(&self) -> impl Iterator<Item = &Arc<SourceFile>> {
        self.files.values()
    }

    pub fn provider(&self, import_path: &str) -> Option<&Arc<SourceFile>> {
        self.providers.get(import_path).and_then(|d| self.files.get(d))
    }

    /// Resolves one import as written to the file providing it: the longest
    /// known prefix wins, so `a::b::item` finds module `a::b`.
    fn resolve(&self, import: &str) -> Option<&Arc<SourceFile>> {
        let mut candidate = import;
        loop {
            if let Some(f) = self.provider(candidate) {
                return Some(f);
            }
            candidate = &candidate[..candidate.rfind("::")?];
        }
    }

    /// The files `file` imports directly, deduplicated, in first-use order,
    /// and a diagnostic per import no file provides. Candidate paths from
    /// brace lists that resolve to the same file count once.
    pub fn direct_imports(&self, file: &SourceFile) -> (Vec<Arc<SourceFile>>, Vec<Diagnostic>) {
        let mut found: Vec<Arc<SourceFile>> = Vec::new();
        let mut missing = Vec::new();
        let mut by_line: BTreeMap<usize, (bool, &str)> = BTreeMap::new();
        for Import { module, range, .. } in &file.imports {
            let entry = by_line.entry(range.start).or_insert((false, module));
            if let Some(dep) = self.resolve(module) {
                entry.0 = true;
                if !found.iter().any(|f| f.display == dep.display) {
                    found.push(dep.clone());
                }
            }
        }
        for (start, (resolved, import)) in by_line {
            if !resolved {
                let range = file.imports.iter().find(|i| i.range.start == start).map(|i| i.range.clone());
                let range = range.unwrap_or(start..start);
                missing.push(
                    Diagnostic::error(Code::ImportMissing, format!("no module provides import `{import}`"))
                        .with_label(file.location(range), "imported here", true)
                        .with_note(self.known_paths_note()),
                );
            }
        }
        (found, missing)
    }

    fn known_paths_note(&self) -> String {
        let mut known: Vec<&str> = self.providers.keys().map(String::as_str).collect();
        known.sort_unstable();
        if known.is_empty() {
            "no file declares `#define_import_path`".to_owned()
        } else {
            format!("known import paths: {}", known.join(", "))
        }
    }

    /// All files `root` depends on, dependencies before dependents (the
    /// order a composer must add them in), without `root` itself. Cycles and
    /// missing imports become diagnostics located at the offending import.
    pub fn dependencies(&self, root: &SourceFile) -> Result<Vec<Arc<SourceFile>>, Vec<Diagnostic>> {
        let mut order = Vec::new();
        let mut state: HashMap<String, bool> = HashMap::new(); // false: on stack, true: done
        let mut errors = Vec::new();
        let mut stack: Vec<String> = Vec::new();
        self.visit(root, &mut state, &mut stack, &mut order, &mut errors);
        order.retain(|f: &Arc<SourceFile>| f.display != root.display);
        if errors.is_empty() { Ok(order) } else { Err(errors) }
    }

    fn visit(
        &self,
        file: &SourceFile,
        state: &mut HashMap<String, bool>,
        stack: &mut Vec<String>,
        order: &mut Vec<Arc<SourceFile>>,
        errors: &mut Vec<Diagnostic>,
    ) {
        state.insert(file.display.clone(), false);
        stack.push(file.display.clone());
        let (deps, missing) = self.direct_imports(file);
        errors.extend(missing);
        for dep in deps {
            match state.get(&dep.display) {
                Some(true) => {}
                Some(false) => {
                    let cycle_start = stack.iter().position(|d| *d == dep.display).unwrap_or(0);
                    let mut chain: Vec<&str> = stack[cycle_start..].iter().map(String::as_str).collect();
                    chain.push(&dep.display);
                    let range = import_range_of(file, &dep).unwrap_or(0..0);
                    errors.push(
                        Diagnostic::error(Code::ImportCycle, "import cycle")
                            .with_label(file.location(range), format!("imports `{}`, which imports this file back", dep.display), true)
                            .with_note(format!("cycle: {}", chain.join(" -> "))),
                    );
                }
                None => self.visit(&dep, state, stack, order, errors),
            }
        }
        stack.pop();
        state.insert(file.display.clone(), true);
        if let Some(f) = self.files.get(&file.display) {
            order.push(f.clone());
        }
    }

    /// The display paths of `root` and the files it can import with every
    /// def of `surely` defined and none outside `maybe` (transitively; an
    /// import under a condition that may hold counts): what a pipeline
    /// composed from `root` with those defs is built from.
    pub fn reachable_under(&self, root: &SourceFile, surely: &BTreeSet<String>, maybe: &BTreeSet<String>) -> BTreeSet<String> {
        let mut out = BTreeSet::from([root.display.clone()]);
        let mut todo = vec![root.display.clone()];
        while let Some(display) = todo.pop() {
            let file = if display == root.display { Some(root) } else { self.files.get(&display).map(|f| &**f) };
            let Some(file) = file else { continue };
            for import in &file.imports {
                if !import.guards.iter().all(|g| g.may_hold(surely, maybe)) {
                    continue;
                }
                if let Some(dep) = self.resolve(&import.module)
                    && out.insert(dep.display.clone())
                {
                    todo.push(dep.display.clone());
                }
            }
        }
        out
    }

    /// Display paths of every file that (transitively) imports `display`,
    /// plus `display` itself: what a change to it invalidates.
    pub fn dependents(&self, display: &str) -> BTreeSet<String> {
        let mut out = BTreeSet::from([display.to_owned()]);
        let mut changed = true;
        while changed {
            changed = false;
            for f in self.files.values() {
                if out.contains(&f.display) {
                    continue;
                }
                let (deps, _) = self.direct_imports(f);
                if deps.iter().any(|d| out.contains(&d.display)) {
                    out.insert(f.display.clone());
                    changed = true;
                }
            }
        }
        out
    }
}

fn import_range_of(file: &SourceFile, dep: &SourceFile) -> Option<Range<usize>> {
    let (dep_path, _) = dep.import_path.as_ref()?;
    file.imports.iter().find(|i| i.module == *dep_path || i.module.starts_with(&format!("{dep_path}::"))).map(|i| i.range.clone())
}

/// The readable `*.wgsl` files under `root`, as a library. Unreadable ones
/// are left out here: whoever builds from them reports the missing file.
pub fn read_tree(root: &Path) -> Result<Library, String> {
    load_tree(root).map(|(lib, _)| lib)
}

/// [`read_tree`], and a warning at each file left out because its name is
/// not UTF-8: the daemon could neither watch it (the watcher matches names
/// as text) nor name it in a URL, so it is left out loudly.
pub fn load_tree(root: &Path) -> Result<(Library, Vec<Diagnostic>), String> {
    let (named, unnamed): (Vec<PathBuf>, Vec<PathBuf>) =
        discover(std::slice::from_ref(&root.to_path_buf()))?.into_iter().partition(|p| p.to_str().is_some());
    let files = named.iter().filter_map(|p| SourceFile::read(p, display_path(p)).ok()).collect::<Vec<_>>();
    let skipped = unnamed.iter().map(|p| name_not_utf8(p)).collect();
    Ok((Library::new(files), skipped))
}

/// Why a file whose name is not UTF-8 is left out of the library, at the
/// file: found at start-up or saved while serving alike.
pub fn name_not_utf8(path: &Path) -> Diagnostic {
    Diagnostic::warning(Code::Encoding, "the file name is not valid UTF-8: the file is not loaded (it cannot be named in a URL); rename it")
        .at(Location::file_start(&display_path(path)))
}

/// Every `*.wgsl` file under `roots` (files named directly are taken as
/// they are), sorted, deduplicated.
pub fn discover(roots: &[PathBuf]) -> Result<Vec<PathBuf>, String> {
    discover_with(roots, |_, p| p.extension().is_some_and(|e| e == "wgsl"))
}

/// Every file under `roots` that `wanted(root, path)` accepts, where `root`
/// is the directory being searched (files named directly are taken as they
/// are); sorted, deduplicated. Hidden files and directories are skipped.
pub fn discover_with(roots: &[PathBuf], wanted: impl Fn(&Path, &Path) -> bool) -> Result<Vec<PathBuf>, String> {
    let mut out = BTreeSet::new();
    for root in roots {
        let meta = std::fs::metadata(root).map_err(|e| format!("{}: {e}", root.display()))?;
        if meta.is_file() {
            out.insert(root.clone());
            continue;
        }
        let mut stack = vec![root.clone()];
        while let Some(dir) = stack.pop() {
            let entries = std::fs::read_dir(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
            for entry in entries.flatten() {
                let p = entry.path();
                let name = entry.file_name();
                if name.to_string_lossy().starts_with('.') {
                    continue;
                }
                match entry.file_type() {
                    Ok(t) if t.is_dir() => stack.push(p),
                    Ok(_) if wanted(root, &p) => {
                        out.insert(p);
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(out.into_iter().collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diag::display_uri;

    /// A name that is not UTF-8 shows escaped, never as U+FFFD, its URI
    /// holds the real bytes, and the daemon's loader says why it skips it.
    #[cfg(unix)]
    #[test]
    fn names_that_are_not_utf8_are_escaped_and_reported() {
        use std::os::unix::ffi::OsStrExt;
        let dir = std::env::temp_dir().join(format!("loupe-lib-names-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let latin1 = dir.join(std::ffi::OsStr::from_bytes(b"caf\xe9.wgsl"));
        std::fs::write(&latin1, "fn f() {}\n").unwrap();
        std::fs::write(dir.join("caf\u{e9} x.wgsl"), "fn g() {}\n").unwrap();
        let shown = display_path(&latin1);
        assert!(shown.ends_with("/caf\\xE9.wgsl"), "{shown}");
        assert!(display_uri(&shown).ends_with("/caf%E9.wgsl"), "{}", display_uri(&shown));
        assert_eq!(display_uri("shaders/caf\u{e9} x.wgsl"), "shaders/caf%C3%A9%20x.wgsl");
        assert_eq!(display_uri("c:/a.wgsl"), "c%3A/a.wgsl");

        let (lib, skipped) = load_tree(&dir).unwrap();
        assert_eq!(lib.files().map(|f| f.display.rsplit('/').next().unwrap().to_owned()).collect::<Vec<_>>(), ["caf\u{e9} x.wgsl"]);
        assert_eq!(skipped.len(), 1);
        assert_eq!((skipped[0].code, skipped[0].file()), (Code::Encoding, Some(shown.as_str())));
        assert!(skipped[0].message.contains("not valid UTF-8"), "{}", skipped[0].message);
        let _ = std::fs::remove_dir_all(&dir);
    }

    fn file(name: &str, text: &str) -> SourceFile {
        SourceFile::from_text(name.to_owned(), PathBuf::from(name), text.into())
    }

    #[test]
    fn import_forms() {
        assert_eq!(import_modules("a::b"), ["a::b"]);
        assert_eq!(import_modules("a::b as c"), ["a::b"]);
        assert_eq!(import_modules("a::b::{x, y}"), ["a::b", "a::b::x", "a::b::y"]);
        assert_eq!(import_modules("\"lib.wgsl\""), ["lib.wgsl"]);
    }

    /// The lighting's shape: one material module per class def, chosen by
    /// an `#ifdef` / `#else ifdef` / `#else` chain, one more behind
    /// `#ifndef` nested in it, one behind an `#if` expression.
    #[test]
    fn a_pipeline_is_built_from_the_imports_its_defs_reach() {
        let lib = Library::new([
            file("simple.wgsl", "#define_import_path simple\n"),
            file("single.wgsl", "#define_import_path single\n"),
            file("full.wgsl", "#define_import_path full\n#import deep\n"),
            file("deep.wgsl", "#define_import_path deep\n"),
            file("rect.wgsl", "#define_import_path rect\n"),
            file("count.wgsl", "#define_import_path count\n"),
            file(
                "light.wgsl",
                "#ifdef SIMPLE\n#import simple\n#else ifdef SINGLE\n#import single\n#else\n  #ifndef NO_RECT\n  #import rect\n  #endif\n#import full::{x}\n#endif\n#if COUNT == 2\n#import count\n#endif\n",
            ),
        ]);
        let light = lib.get("light.wgsl").unwrap();
        let reach = |surely: &[&str], maybe: &[&str]| {
            let set = |d: &[&str]| d.iter().map(|s| s.to_string()).collect::<BTreeSet<_>>();
            let (surely, maybe) = (set(surely), set(maybe));
            let mut all = maybe.clone();
            all.extend(surely.iter().cloned());
            let out = lib.reachable_under(light, &surely, &all);
            out.into_iter().filter(|d| d != "light.wgsl").map(|d| d.trim_end_matches(".wgsl").to_owned()).collect::<Vec<_>>()
        };
        assert_eq!(reach(&["SIMPLE"], &[]), ["count", "simple"]);
        assert_eq!(reach(&["SINGLE"], &[]), ["count", "single"]);
        assert_eq!(reach(&[], &[]), ["count", "deep", "full", "rect"]);
        assert_eq!(reach(&["NO_RECT"], &[]), ["count", "deep", "full"]);
        // A def that may be on (a module implies it) keeps both branches.
        assert_eq!(reach(&[], &["SIMPLE"]), ["count", "deep", "full", "rect", "simple"]);
    }

    #[test]
    fn dependencies_come_first_and_dependents_are_transitive() {
        let lib = Library::new([
            file("a.wgsl", "#define_import_path a\nfn fa() {}\n"),
            file("b.wgsl", "#define_import_path b\n#import a::fa\nfn fb() {}\n"),
            file("main.wgsl", "#import b::{fb}\n#import a\n"),
            file("other.wgsl", "fn x() {}\n"),
        ]);
        let main = lib.get("main.wgsl").unwrap();
        let deps: Vec<_> = lib.dependencies(main).unwrap().iter().map(|f| f.display.clone()).collect();
        assert_eq!(deps, ["a.wgsl", "b.wgsl"]);
        let dependents: Vec<_> = lib.dependents("a.wgsl").into_iter().collect();
        assert_eq!(dependents, ["a.wgsl", "b.wgsl", "main.wgsl"]);
    }

    #[test]
    fn cycles_and_missing_imports_are_located() {
        let lib = Library::new([
            file("a.wgsl", "#define_import_path a\n#import b\n"),
            file("b.wgsl", "#define_import_path b\n\n  #import a\n"),
            file("m.wgsl", "#import a\n#import nowhere::thing\n"),
        ]);
        let errs = lib.dependencies(lib.get("m.wgsl").unwrap()).unwrap_err();
        let missing = errs.iter().find(|d| d.code == Code::ImportMissing).unwrap();
        let loc = missing.location.as_ref().unwrap();
        assert_eq!((loc.file.as_str(), loc.line, loc.column), ("m.wgsl", 2, 9));
        let cycle = errs.iter().find(|d| d.code == Code::ImportCycle).unwrap();
        let loc = cycle.location.as_ref().unwrap();
        assert_eq!((loc.file.as_str(), loc.line, loc.column), ("b.wgsl", 3, 11));
    }

    #[test]
    fn duplicate_import_paths_are_reported() {
        let lib = Library::new([file("x.wgsl", "#define_import_path p\n"), file("y.wgsl", "#define_import_path p\n")]);
        assert_eq!(lib.diagnostics.len(), 1);
        assert_eq!(lib.diagnostics[0].code, Code::ImportDuplicate);
    }
}
