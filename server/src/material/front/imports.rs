//! Reading a material file and, transitively, the files it imports: paths
//! are relative to the importing file, each file is read once (with the
//! shader files' size cap), and a cycle or a chain deeper than
//! `MAX_IMPORT_DEPTH` is an error at the `import` that closes it.

use std::path::{Path, PathBuf};

use super::ast::File;
use super::parse::parse;
use crate::diag::{Code, Diagnostic, display_path};
use crate::files::read_capped;
use crate::shader::SourceFile;
use crate::shader::library::MAX_FILE_BYTES;

/// How many files deep imports may nest.
pub const MAX_IMPORT_DEPTH: usize = 16;

/// One parsed file.
pub struct Unit {
    pub source: SourceFile,
    pub ast: File,
    /// Its imports' prefixes, each with the index of the unit it names.
    pub imports: Vec<(String, usize)>,
}

/// Reads a file as the root or an import: every way it can be unusable is a
/// diagnostic at the file's start.
pub fn read(path: &Path) -> Result<SourceFile, Diagnostic> {
    let display = display_path(path);
    let bytes = read_capped(path, MAX_FILE_BYTES)
        .map_err(|e| e.diagnostic("file", MAX_FILE_BYTES).at(crate::diag::Location::file_start(&display)))?;
    SourceFile::from_bytes(path, display, bytes)
}

/// Parses `root` and everything it imports: units in the order first read,
/// the root first; every error of every file.
pub fn load_all(root: SourceFile) -> (Vec<Unit>, Vec<Diagnostic>) {
    let mut loader = Loader { units: Vec::new(), keys: Vec::new(), errors: Vec::new() };
    loader.add(root, &mut Vec::new());
    (loader.units, loader.errors)
}

struct Loader {
    units: Vec<Unit>,
    /// Each unit's canonical path, to read a file imported twice once.
    keys: Vec<PathBuf>,
    errors: Vec<Diagnostic>,
}

impl Loader {
    /// Adds a unit and, depth first, its imports; `chain` holds the units
    /// importing it, outermost first.
    fn add(&mut self, source: SourceFile, chain: &mut Vec<usize>) -> usize {
        let (ast, syntax) = parse(&source.text);
        for e in syntax {
            self.errors.push(Diagnostic::error(Code::Material, e.message).with_label(source.location(e.span), e.label, true));
        }
        let index = self.units.len();
        self.keys.push(canonical(&source.path));
        let imports = ast.imports.clone();
        self.units.push(Unit { source, ast, imports: Vec::new() });
        chain.push(index);
        for import in imports {
            let here = self.units[index].source.location(import.path_span.clone());
            let dir = self.units[index].source.path.parent().map(Path::to_path_buf).unwrap_or_default();
            let path = dir.join(&import.path);
            let key = canonical(&path);
            if let Some(pos) = chain.iter().position(|&u| self.keys[u] == key) {
                let first = self.units[chain[pos]].source.display.clone();
                let names: Vec<String> =
                    chain[pos..].iter().map(|&u| self.units[u].source.display.clone()).chain([first.clone()]).collect();
                self.errors.push(
                    Diagnostic::error(Code::ImportCycle, "import cycle")
                        .with_label(here, format!("imports `{first}`, which imports this file"), true)
                        .with_note(format!("cycle: {}", names.join(" -> "))),
                );
                continue;
            }
            let target = match self.keys.iter().position(|k| *k == key) {
                Some(existing) => existing,
                None if chain.len() >= MAX_IMPORT_DEPTH => {
                    self.errors.push(
                        Diagnostic::error(Code::Material, format!("imports nest more than {MAX_IMPORT_DEPTH} files deep")).with_label(
                            here,
                            "import limit reached here",
                            true,
                        ),
                    );
                    continue;
                }
                None if !path.exists() => {
                    self.errors.push(
                        Diagnostic::error(Code::ImportMissing, format!("cannot find `{}`", import.path))
                            .with_label(here, format!("no file at {}", display_path(&path)), true)
                            .with_note("import paths are relative to the importing file"),
                    );
                    continue;
                }
                None => match read(&path) {
                    Ok(source) => self.add(source, chain),
                    Err(d) => {
                        self.errors.push(d.with_label(here, "imported here", false));
                        continue;
                    }
                },
            };
            self.units[index].imports.push((import.prefix.name, target));
        }
        chain.pop();
        index
    }
}

fn canonical(path: &Path) -> PathBuf {
    path.canonicalize().unwrap_or_else(|_| path.to_owned())
}
