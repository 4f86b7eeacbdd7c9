//! The front end of the material language ([docs/materials.md]): a `*.mat`
//! file and its imports, read (`imports`), tokenized (`lexer`), parsed
//! (`parse`, to the syntax tree in `ast`) and lowered (`lower`) to one
//! `tree::Definition` per material of the file. Every error is a located
//! diagnostic; as many as can be found are reported at once.

mod ast;
mod imports;
mod lexer;
mod lower;
mod parse;
#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};

use crate::diag::{Diagnostic, Severity, display_path};
use crate::material::tree::Definition;
use crate::shader::SourceFile;

/// A material file, lowered.
#[derive(Debug)]
pub struct Loaded {
    /// One per `material` of the root file, in the order written.
    pub definitions: Vec<Definition>,
    /// Every file read, the root first: what a watcher watches.
    pub files: Vec<PathBuf>,
    /// The images the definitions' texture params name by default
    /// (`Value::Texture` indexes it); not read yet.
    pub textures: Vec<crate::material::tree::TextureSource>,
    pub warnings: Vec<Diagnostic>,
}

/// Loads the material file at `path` and its imports from disk.
pub fn load(path: &Path) -> Result<Loaded, Vec<Diagnostic>> {
    lower_root(imports::read(path).map_err(|d| vec![d])?)
}

/// Loads a material file whose text is already in memory (the watcher's);
/// its imports are read from disk.
pub fn load_text(path: &Path, text: &str) -> Result<Loaded, Vec<Diagnostic>> {
    lower_root(SourceFile::from_bytes(path, display_path(path), text.as_bytes().to_vec()).map_err(|d| vec![d])?)
}

fn lower_root(root: SourceFile) -> Result<Loaded, Vec<Diagnostic>> {
    let (units, mut errors) = imports::load_all(root);
    let files = units.iter().map(|u| u.source.path.clone()).collect();
    if errors.iter().any(|d| d.severity == Severity::Error) {
        // Lowering a file that did not parse would only repeat its errors
        // as unknown names; the parse errors say what to fix.
        return Err(errors);
    }
    let mut lowered = lower::lower(&units);
    errors.append(&mut lowered.errors);
    if errors.is_empty() {
        Ok(Loaded { definitions: lowered.definitions, files, textures: lowered.textures, warnings: lowered.warnings })
    } else {
        Err(errors)
    }
}
