//! Composition: an entry shader plus the modules it imports, under one set
//! of shader defs, becomes one validated `naga::Module`.
//!
//! The composer sits behind `Compose` so naga_oil can be swapped (for WESL,
//! say) without touching callers. Every error comes back as `Diagnostic`s
//! located in the original files, never in composed text.

use std::collections::{BTreeSet, HashMap};
use std::ops::Range;
use std::sync::{Arc, Mutex};

use naga::valid::{Capabilities, ValidationFlags, Validator};
use naga_oil::compose::{ComposableModuleDescriptor, Composer, ComposerError, ComposerErrorInner, NagaModuleDescriptor, ShaderDefValue};

use super::library::{Library, SourceFile};
use crate::diag::{Code, Diagnostic, LineIndex, Location};

/// A set of boolean shader defs (`#ifdef NAME`). Ordered, so it can key caches.
pub type ShaderDefs = BTreeSet<String>;

/// `A,B,C` — how a permutation is named in reports, caches and the API.
pub fn defs_key(defs: &ShaderDefs) -> String {
    defs.iter().map(String::as_str).collect::<Vec<_>>().join(",")
}

/// A composed, validated module and the files it was built from.
#[derive(Debug, Clone)]
pub struct Composed {
    pub module: naga::Module,
    pub info: naga::valid::ModuleInfo,
    /// Display paths of the entry file and every module it pulled in.
    pub files: Vec<String>,
}

pub trait Compose: Send + Sync {
    fn compose(&self, lib: &Library, entry: &SourceFile, defs: &ShaderDefs, caps: Capabilities) -> Result<Composed, Vec<Diagnostic>>;
}

/// The naga_oil composer. Plain files (no preprocessor lines, no imports)
/// go straight to naga's front end: nothing to compose, and naga's spans are
/// then exact byte offsets into the user's file.
#[derive(Debug, Default, Clone, Copy)]
pub struct NagaOil;

impl Compose for NagaOil {
    fn compose(&self, lib: &Library, entry: &SourceFile, defs: &ShaderDefs, caps: Capabilities) -> Result<Composed, Vec<Diagnostic>> {
        compose_and_validate(lib, entry, defs, caps, |deps| compose_with_naga_oil(deps, entry, defs, caps))
    }
}

/// The naga_oil composer with composers kept warm between compiles: each
/// imported module is parsed and composed once per text and set of defs,
/// so an edit to a file nobody imports recomposes that file alone.
///
/// A composer is reused only while every module a compile needs is the same
/// text in it as in the compile's library: an import whose text changed
/// gets a fresh composer, because naga_oil numbers a re-added module as if
/// it were new, which can collide with another module's number and put
/// error spans in the wrong file. Failures are reported from a fresh
/// composer, exactly as [`NagaOil`] reports them. One composer is kept per
/// compile that ran at once (at most [`ComposeCache::MAX_IDLE`]).
#[derive(Default)]
pub struct ComposeCache {
    idle: Mutex<Vec<Warm>>,
}

struct Warm {
    composer: Composer,
    caps: Capabilities,
    /// Every module added, by import path: the file's display path and the
    /// hash of the text it was added from.
    modules: HashMap<String, (String, blake3::Hash)>,
}

impl Warm {
    fn new(caps: Capabilities) -> Self {
        Warm { composer: Composer::default().with_capabilities(caps), caps, modules: HashMap::new() }
    }

    /// Whether this composer holds no other version of `deps` than theirs.
    fn current_for(&self, caps: Capabilities, deps: &[Arc<SourceFile>]) -> bool {
        self.caps == caps
            && deps.iter().all(|d| {
                let Some((name, _)) = &d.import_path else { return true };
                self.modules.get(name).is_none_or(|(display, hash)| *display == d.display && *hash == d.hash)
            })
    }

    /// Adds the modules of `deps` it does not hold yet, then composes
    /// `entry`. The error is boxed: naga_oil's is a few hundred bytes, and
    /// this is the hot path of every reload.
    fn compose(&mut self, deps: &[Arc<SourceFile>], entry: &SourceFile, defs: &ShaderDefs) -> Result<naga::Module, Box<ComposerError>> {
        for dep in deps {
            let name = dep.import_path.as_ref().map(|(name, _)| name);
            if name.is_some_and(|name| self.modules.contains_key(name)) {
                continue;
            }
            self.composer
                .add_composable_module(ComposableModuleDescriptor {
                    source: &dep.prints.text,
                    file_path: &dep.display,
                    ..Default::default()
                })
                .map_err(Box::new)?;
            if let Some(name) = name {
                self.modules.insert(name.clone(), (dep.display.clone(), dep.hash));
            }
        }
        self.composer
            .make_naga_module(NagaModuleDescriptor {
                source: &entry.prints.text,
                file_path: &entry.display,
                shader_defs: naga_oil_defs(&with_implied(defs, deps)),
                ..Default::default()
            })
            .map_err(Box::new)
    }
}

impl ComposeCache {
    /// The most idle composers kept.
    pub const MAX_IDLE: usize = 8;

    /// A composer current for `deps` (outdated ones are dropped), or a new one.
    fn take(&self, caps: Capabilities, deps: &[Arc<SourceFile>]) -> Warm {
        let mut idle = self.idle.lock().unwrap_or_else(|e| e.into_inner());
        idle.retain(|w| w.caps != caps || w.current_for(caps, deps));
        match idle.iter().rposition(|w| w.caps == caps) {
            Some(at) => idle.swap_remove(at),
            None => Warm::new(caps),
        }
    }

    fn give_back(&self, warm: Warm) {
        let mut idle = self.idle.lock().unwrap_or_else(|e| e.into_inner());
        if idle.len() < Self::MAX_IDLE {
            idle.push(warm);
        }
    }
}

impl Compose for ComposeCache {
    fn compose(&self, lib: &Library, entry: &SourceFile, defs: &ShaderDefs, caps: Capabilities) -> Result<Composed, Vec<Diagnostic>> {
        compose_and_validate(lib, entry, defs, caps, |deps| {
            let mut warm = self.take(caps, deps);
            match warm.compose(deps, entry, defs) {
                Ok(module) => {
                    self.give_back(warm);
                    Ok(module)
                }
                // The composer may hold half an attempt: not kept.
                Err(_) => compose_with_naga_oil(deps, entry, defs, caps),
            }
        })
    }
}

/// What every composer shares: resolving the imports, plain files straight
/// to naga, and validation with the `ModuleInfo` kept.
fn compose_and_validate(
    lib: &Library,
    entry: &SourceFile,
    defs: &ShaderDefs,
    caps: Capabilities,
    compose: impl FnOnce(&[Arc<SourceFile>]) -> Result<naga::Module, Vec<Diagnostic>>,
) -> Result<Composed, Vec<Diagnostic>> {
    let deps = lib.dependencies(entry)?;
    // What the module is built from: the imports its defs can reach (an
    // edit to a module only other defs import leaves it alone). The defs
    // the imports imply may be on as well.
    let reachable = lib.reachable_under(entry, defs, &with_implied(defs, &deps));
    let files: Vec<String> =
        deps.iter().map(|f| f.display.clone()).chain([entry.display.clone()]).filter(|d| reachable.contains(d)).collect();
    let problems: Vec<Diagnostic> =
        deps.iter().map(|d| &**d).chain([entry]).filter(|f| reachable.contains(&f.display)).flat_map(SourceFile::print_problems).collect();
    if !problems.is_empty() {
        return Err(problems);
    }
    let module = if !entry.has_directives {
        naga::front::wgsl::parse_str(&entry.prints.text).map_err(|e| {
            let labels = e.labels().map(|(s, m)| (s.to_range().unwrap_or(0..0), m.to_owned())).collect();
            vec![located(Code::Parse, e.message().to_owned(), labels, Vec::new(), entry)]
        })?
    } else {
        compose(&deps)?
    };
    // naga_oil validates too, but keeps the ModuleInfo to itself; the
    // renderer and the binding check need it, so validate here once more
    // (cheap next to parsing) and report against the entry on failure.
    let info = Validator::new(ValidationFlags::all(), caps).validate(&module).map_err(|e| {
        let (message, notes) = root_cause(e.as_inner());
        let labels = validation_labels(e.spans().map(|(s, m)| (s.to_range().unwrap_or(0..0), m.clone())));
        vec![located(Code::Validation, message, labels, notes, entry)]
    })?;
    let sources = deps.iter().map(|d| &**d).chain([entry]).filter(|f| !f.prints.sites.is_empty());
    let problems: Vec<Diagnostic> =
        sources.flat_map(|f| f.prints.type_problems(&module).into_iter().map(|p| f.print_problem(&p))).collect();
    if !problems.is_empty() {
        return Err(problems);
    }
    Ok(Composed { module, info, files })
}

/// How a module implies a def for the shaders importing it, a line of its
/// own: `// loupe: implies NAME`. naga_oil reads `#define` only in the
/// entry shader, so a module cannot define for its importers what it
/// provides (the generated material module's transmission code).
pub const IMPLIES: &str = "// loupe: implies ";

/// `defs` and those the imported modules imply (`IMPLIES`).
fn with_implied(defs: &ShaderDefs, deps: &[Arc<SourceFile>]) -> ShaderDefs {
    let implied =
        deps.iter().flat_map(|d| d.text.lines().filter_map(|l| l.strip_prefix(IMPLIES)).map(|n| n.trim().to_owned()).collect::<Vec<_>>());
    defs.iter().cloned().chain(implied).collect()
}

fn naga_oil_defs(defs: &ShaderDefs) -> HashMap<String, ShaderDefValue> {
    defs.iter().map(|d| (d.clone(), ShaderDefValue::Bool(true))).collect()
}

fn compose_with_naga_oil(
    deps: &[Arc<SourceFile>],
    entry: &SourceFile,
    defs: &ShaderDefs,
    caps: Capabilities,
) -> Result<naga::Module, Vec<Diagnostic>> {
    let mut fresh = Warm::new(caps);
    fresh.compose(deps, entry, defs).map_err(|e| vec![from_composer(&fresh.composer, *e, deps, entry)])
}

/// Checks a library module on its own: parsed and validated as a shader
/// that imports the whole module and nothing else, so errors in functions
/// no entry point uses yet are found too.
pub fn check_library(lib: &Library, file: &Arc<SourceFile>, defs: &ShaderDefs, caps: Capabilities) -> Result<(), Vec<Diagnostic>> {
    let Some((path, _)) = &file.import_path else { return Ok(()) };
    let mut deps = lib.dependencies(file)?;
    deps.push(file.clone());
    let problems: Vec<Diagnostic> = file.print_problems().collect();
    if !problems.is_empty() {
        return Err(problems);
    }
    let probe = SourceFile::from_text(file.display.clone(), file.path.clone(), format!("#import {path}\n").into());
    compose_with_naga_oil(&deps, &probe, defs, caps).map(|_| ())
}

/// Maps a naga_oil error to a diagnostic in the file it came from. naga_oil
/// keeps the line structure of every file through preprocessing (removed
/// lines become blanks) and tags spans with a module index in the high bits,
/// so masking and subtracting the module's start offset gives a byte offset
/// into text with the same lines as the original.
/// Spans in the composed text and their messages.
type Labels = Vec<(Range<usize>, String)>;

fn from_composer(composer: &Composer, err: ComposerError, deps: &[Arc<SourceFile>], entry: &SourceFile) -> Diagnostic {
    const SPAN_SHIFT: usize = 21; // naga_oil's module-index shift
    let path = err.source.path(composer).clone();
    let text = err.source.source(composer).into_owned();
    let offset = err.source.offset();
    let map = |r: Range<usize>| {
        let mask = (1 << SPAN_SHIFT) - 1;
        (r.start & mask).saturating_sub(offset)..(r.end & mask).saturating_sub(offset)
    };
    let point = |p: usize| vec![(p..p, String::new())];
    let (code, labels, notes): (Code, Labels, Vec<String>) = match &err.inner {
        ComposerErrorInner::WgslParseError(e) => {
            (Code::Parse, e.labels().map(|(s, m)| (map(s.to_range().unwrap_or(0..0)), m.to_owned())).collect(), Vec::new())
        }
        ComposerErrorInner::ShaderValidationError(v) | ComposerErrorInner::HeaderValidationError(v) => {
            let (_, notes) = root_cause(v.as_inner());
            let labels = validation_labels(v.spans().map(|(s, m)| (map(s.to_range().unwrap_or(0..0)), m.clone())));
            (Code::Validation, labels, notes)
        }
        ComposerErrorInner::ImportNotFound(_, pos) => (Code::ImportMissing, point(*pos), Vec::new()),
        ComposerErrorInner::DecorationInSource(r) => (Code::Preprocess, vec![(r.clone(), String::new())], Vec::new()),
        ComposerErrorInner::InvalidIdentifier { at, .. } => {
            (Code::Preprocess, vec![(map(at.to_range().unwrap_or(0..0)), String::new())], Vec::new())
        }
        ComposerErrorInner::ImportParseError(_, pos)
        | ComposerErrorInner::NotEnoughEndIfs(pos)
        | ComposerErrorInner::TooManyEndIfs(pos)
        | ComposerErrorInner::ElseWithoutCondition(pos)
        | ComposerErrorInner::UnknownShaderDef { pos, .. }
        | ComposerErrorInner::UnknownShaderDefOperator { pos, .. }
        | ComposerErrorInner::InvalidShaderDefComparisonValue { pos, .. }
        | ComposerErrorInner::OverrideNotVirtual { pos, .. }
        | ComposerErrorInner::DefineInModule(pos)
        | ComposerErrorInner::InvalidShaderDefDefinitionValue { pos, .. }
        | ComposerErrorInner::InvalidWgslDirective { position: pos, .. } => (Code::Preprocess, point(*pos), Vec::new()),
        _ => (Code::Preprocess, point(0), Vec::new()),
    };
    let message = match &err.inner {
        ComposerErrorInner::WgslParseError(e) => e.message().to_owned(),
        ComposerErrorInner::ShaderValidationError(v) | ComposerErrorInner::HeaderValidationError(v) => root_cause(v.as_inner()).0,
        other => other.to_string(),
    };
    // Prefer the original file's text for line/column: same lines as
    // naga_oil's, and excerpts then show what the user wrote.
    let original = deps.iter().map(|d| &**d).chain(std::iter::once(entry)).find(|f| f.display == path);
    let lines = LineIndex::new(&text);
    let loc = |r: Range<usize>| -> Location {
        let r = r.start.min(text.len())..r.end.min(text.len()).max(r.start.min(text.len()));
        match original {
            Some(f) => f.composed_location(original_range(&text, &f.prints.text, r)),
            None => lines.location(&path, &text, r),
        }
    };
    build(code, undecorate(&message), labels.into_iter().map(|(r, m)| (loc(r), undecorate(&m))), notes.iter().map(|n| undecorate(n)))
}

/// Maps a byte range in naga_oil's preprocessed text to the original text
/// by line and character column (lines are preserved one to one).
fn original_range(pre: &str, orig: &str, r: Range<usize>) -> Range<usize> {
    let conv = |at: usize| -> usize {
        let pre_lines = LineIndex::new(pre);
        let (line, col) = pre_lines.line_col(pre, at);
        let Some(start) = line_start(orig, line) else { return orig.len() };
        let rest = &orig[start..];
        let line_len = rest.find('\n').unwrap_or(rest.len());
        let byte = rest[..line_len].char_indices().nth(col as usize - 1).map_or(line_len, |(b, _)| b);
        start + byte
    };
    conv(r.start)..conv(r.end)
}

fn line_start(text: &str, line: u32) -> Option<usize> {
    if line == 1 {
        return Some(0);
    }
    text.match_indices('\n').nth(line as usize - 2).map(|(i, _)| i + 1)
}

/// naga lists validation spans outermost first (the function, then the
/// expression) and labels them with IR names. The innermost span is where
/// the problem is: it becomes the primary label.
fn validation_labels(spans: impl Iterator<Item = (Range<usize>, String)>) -> Vec<(Range<usize>, String)> {
    let mut labels: Vec<(Range<usize>, String)> = spans.collect();
    labels.reverse();
    for (i, (_, msg)) in labels.iter_mut().enumerate() {
        *msg = if i == 0 {
            "here".to_owned()
        } else if msg.contains("Function") {
            "in this function".to_owned()
        } else {
            msg.trim_start_matches("naga::ir::").to_owned()
        };
    }
    labels
}

/// naga's errors nest: the outermost says which function, the innermost
/// why. The innermost is the message (what a one-line format shows); the
/// outer ones follow as notes, outermost first.
fn root_cause(e: &dyn std::error::Error) -> (String, Vec<String>) {
    let mut chain = vec![e.to_string()];
    let mut cur = e.source();
    while let Some(c) = cur {
        chain.push(c.to_string());
        cur = c.source();
    }
    let message = chain.pop().expect("at least the error itself");
    (message, chain)
}

fn located(code: Code, message: String, labels: Vec<(Range<usize>, String)>, notes: Vec<String>, file: &SourceFile) -> Diagnostic {
    let d = build(code, message, labels.into_iter().map(|(r, m)| (file.composed_location(r), m)), notes.into_iter());
    // Some errors carry no span (naga's recursion limit): the file itself.
    if d.location.is_none() { d.at(Location::file_start(&file.display)) } else { d }
}

fn build(code: Code, message: String, labels: impl Iterator<Item = (Location, String)>, notes: impl Iterator<Item = String>) -> Diagnostic {
    let mut d = Diagnostic::error(code, message);
    for (i, (loc, msg)) in labels.enumerate() {
        d = d.with_label(loc, msg, i == 0);
    }
    for n in notes {
        d = d.with_note(n);
    }
    d
}

/// Turns naga_oil's decorated names (`itemX_naga_oil_mod_X<base32>X`) back
/// into `module::item`, so messages name what the user wrote.
pub fn undecorate(s: &str) -> String {
    const PRE: &str = "X_naga_oil_mod_X";
    let mut out = String::with_capacity(s.len());
    let mut rest = s;
    while let Some(at) = rest.find(PRE) {
        let after = &rest[at + PRE.len()..];
        let enc_len = after.find(|c: char| !(c.is_ascii_uppercase() || ('2'..='7').contains(&c))).unwrap_or(after.len());
        let decoded = after[..enc_len].strip_suffix('X').and_then(base32_decode);
        let Some(module) = decoded else {
            out.push_str(&rest[..at + PRE.len()]);
            rest = after;
            continue;
        };
        let head = &rest[..at];
        let item_start = head.rfind(|c: char| !(c.is_alphanumeric() || c == '_')).map_or(0, |i| i + 1);
        out.push_str(&head[..item_start]);
        out.push_str(&module);
        out.push_str("::");
        out.push_str(&head[item_start..]);
        rest = &after[enc_len..];
    }
    out.push_str(rest);
    out
}

fn base32_decode(s: &str) -> Option<String> {
    let mut bits: u64 = 0;
    let mut n = 0;
    let mut out = Vec::new();
    for c in s.bytes() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'2'..=b'7' => c - b'2' + 26,
            _ => return None,
        };
        bits = (bits << 5) | u64::from(v);
        n += 5;
        if n >= 8 {
            n -= 8;
            out.push((bits >> n) as u8);
            bits &= (1 << n) - 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn file(name: &str, text: &str) -> SourceFile {
        SourceFile::from_text(name.to_owned(), PathBuf::from(name), text.into())
    }

    fn compose(lib: &Library, entry: &str, defs: &[&str]) -> Result<Composed, Vec<Diagnostic>> {
        compose_both(&ComposeCache::default(), lib, entry, defs)
    }

    /// Composes `entry` with `NagaOil` and with `cache`, checks that both
    /// give the same WGSL back or the same diagnostics, and returns
    /// `NagaOil`'s result.
    fn compose_both(cache: &ComposeCache, lib: &Library, entry: &str, defs: &[&str]) -> Result<Composed, Vec<Diagnostic>> {
        let defs: ShaderDefs = defs.iter().map(|s| s.to_string()).collect();
        let file = lib.get(entry).unwrap();
        let fresh = NagaOil.compose(lib, file, &defs, Capabilities::all());
        let warm = cache.compose(lib, file, &defs, Capabilities::all());
        match (&fresh, &warm) {
            (Ok(a), Ok(b)) => assert_eq!(wgsl(a), wgsl(b), "{entry} {defs:?}"),
            (Err(a), Err(b)) => assert_eq!(a, b, "{entry} {defs:?}"),
            _ => panic!(
                "the cache disagrees on {entry} {defs:?}: fresh {:?}, cached {:?}",
                fresh.as_ref().map(wgsl),
                warm.as_ref().map(wgsl)
            ),
        }
        fresh
    }

    fn wgsl(c: &Composed) -> String {
        naga::back::wgsl::write_string(&c.module, &c.info, naga::back::wgsl::WriterFlags::empty()).unwrap()
    }

    fn util(body: &str) -> SourceFile {
        file("lib/util.wgsl", &format!("#define_import_path util\n\nfn helper(x: f32) -> f32 {{\n{body}\n}}\n"))
    }

    fn lib_with(util: SourceFile) -> Library {
        let main = "#import util::helper\n\n@fragment\nfn fs() -> @location(0) vec4<f32> {\n    return vec4(helper(1.0));\n}\n";
        let other = "#import util::helper\n\n@compute @workgroup_size(1)\nfn cs() {\n    _ = helper(2.0);\n}\n";
        Library::new([util, file("main.wgsl", main), file("other.wgsl", other)])
    }

    #[test]
    fn the_cache_follows_edits_to_imports_and_reports_like_a_fresh_composer() {
        let cache = ComposeCache::default();
        let v1 = lib_with(util("#ifdef TRIPLE\n    return x * 3.0;\n#else\n    return x * 2.0;\n#endif"));
        let doubled = wgsl(&compose_both(&cache, &v1, "main.wgsl", &[]).unwrap());
        compose_both(&cache, &v1, "other.wgsl", &[]).unwrap();
        let tripled = wgsl(&compose_both(&cache, &v1, "main.wgsl", &["TRIPLE"]).unwrap());
        assert!(doubled.contains("2f") && tripled.contains("3f"), "{doubled}\n{tripled}");

        // The import breaks: the cached module must not stand in for it.
        let v2 = lib_with(util("    let v = 1u;\n    return x + v;"));
        let errs = compose_both(&cache, &v2, "main.wgsl", &[]).unwrap_err();
        let loc = errs[0].location.as_ref().unwrap();
        assert_eq!((loc.file.as_str(), loc.line), ("lib/util.wgsl", 5), "{errs:?}");

        // And is fixed differently.
        let v3 = lib_with(util("    return x * 5.0;"));
        let fixed = wgsl(&compose_both(&cache, &v3, "main.wgsl", &[]).unwrap());
        assert!(fixed.contains("5f"), "{fixed}");
        compose_both(&cache, &v3, "other.wgsl", &[]).unwrap();
    }

    #[test]
    fn one_warm_composer_serves_a_library_and_outdated_ones_are_dropped() {
        let cache = ComposeCache::default();
        let held = |cache: &ComposeCache| -> Vec<Vec<blake3::Hash>> {
            cache.idle.lock().unwrap().iter().map(|w| w.modules.values().map(|(_, hash)| *hash).collect()).collect()
        };
        let v1 = lib_with(util("    return x * 2.0;"));
        for entry in ["main.wgsl", "other.wgsl", "main.wgsl"] {
            compose_both(&cache, &v1, entry, &[]).unwrap();
        }
        assert_eq!(held(&cache), [[v1.get("lib/util.wgsl").unwrap().hash]]);
        let v2 = lib_with(util("    return x * 4.0;"));
        compose_both(&cache, &v2, "other.wgsl", &[]).unwrap();
        assert_eq!(held(&cache), [[v2.get("lib/util.wgsl").unwrap().hash]]);
    }

    #[test]
    fn undecorates_names() {
        // "util" in base32 is OV2GS3A.
        assert_eq!(undecorate("call to fooX_naga_oil_mod_XOV2GS3AX failed"), "call to util::foo failed");
    }

    #[test]
    fn validation_error_inside_an_import_is_located_in_that_file() {
        let lib = Library::new([
            file("lib/util.wgsl", "#define_import_path util\n\nfn helper(x: f32) -> f32 {\n    let v = 1u;\n    return x + v;\n}\n"),
            file("main.wgsl", "#import util::helper\n\n@fragment\nfn fs() -> @location(0) vec4<f32> {\n    return vec4(helper(1.0));\n}\n"),
        ]);
        let errs = compose(&lib, "main.wgsl", &[]).unwrap_err();
        let loc = errs[0].location.as_ref().unwrap();
        assert_eq!(loc.file, "lib/util.wgsl", "{errs:?}");
        assert_eq!(loc.line, 5, "{errs:?}");
        assert_eq!(errs[0].code, Code::Validation);
    }

    #[test]
    fn parse_error_inside_an_import_is_located_in_that_file() {
        let lib = Library::new([
            file("lib/util.wgsl", "#define_import_path util\n\nfn helper(x: f32) -> f32 {\n    return x +* 2.0;\n}\n"),
            file("main.wgsl", "#import util::helper\n@fragment\nfn fs() -> @location(0) vec4<f32> { return vec4(helper(1.0)); }\n"),
        ]);
        let errs = compose(&lib, "main.wgsl", &[]).unwrap_err();
        let loc = errs[0].location.as_ref().unwrap();
        assert_eq!((loc.file.as_str(), loc.line, loc.column), ("lib/util.wgsl", 4, 15), "{errs:?}");
        assert_eq!(errs[0].code, Code::Parse);
    }

    #[test]
    fn shader_defs_select_code() {
        let lib = Library::new([file(
            "m.wgsl",
            "@fragment\nfn fs() -> @location(0) vec4<f32> {\n#ifdef BROKEN\n    return 1u;\n#else\n    return vec4(1.0);\n#endif\n}\n",
        )]);
        assert!(compose(&lib, "m.wgsl", &[]).is_ok());
        let errs = compose(&lib, "m.wgsl", &["BROKEN"]).unwrap_err();
        assert_eq!(errs[0].location.as_ref().unwrap().line, 4, "{errs:?}");
    }

    #[test]
    fn plain_files_skip_the_composer_with_exact_spans() {
        let lib = Library::new([file("p.wgsl", "fn f() -> f32 {\n  return undefined_thing;\n}\n")]);
        let errs = compose(&lib, "p.wgsl", &[]).unwrap_err();
        let loc = errs[0].location.as_ref().unwrap();
        assert_eq!((loc.line, loc.column, loc.end_column), (2, 10, 25), "{errs:?}");
    }
}
