//! Diagnostics: the one shape every error and warning takes on its way to the
//! user, whatever produced it (naga's parser or validator, the composer, the
//! file system, wgpu pipeline creation, the scene loader).
//!
//! Architecture Invariant: a `Diagnostic` always points into an original
//! source file as the user wrote it (never into composed or preprocessed
//! text), with 1-based lines and 1-based columns counted in characters.

mod path;
mod source;

pub use path::{display_path, display_uri};
pub use source::{LineIndex, SourceFiles};

use serde::Serialize;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Severity {
    Error,
    Warning,
    Note,
}

impl Severity {
    pub fn as_str(self) -> &'static str {
        match self {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Note => "note",
        }
    }
}

/// A range in an original file. Lines and columns are 1-based; columns count
/// characters (Unicode scalar values). `end_*` is exclusive and equals the
/// start for a point location.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub struct Location {
    pub file: String,
    pub line: u32,
    pub column: u32,
    pub end_line: u32,
    pub end_column: u32,
}

impl Location {
    /// The whole file, for problems that have no better place (unreadable,
    /// empty, too large).
    pub fn file_start(file: &str) -> Self {
        Location { file: file.to_owned(), line: 1, column: 1, end_line: 1, end_column: 1 }
    }
}

impl std::fmt::Display for Location {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}:{}", self.file, self.line, self.column)
    }
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Label {
    #[serde(flatten)]
    pub location: Location,
    pub message: String,
    pub primary: bool,
}

/// Stable, machine-readable diagnostic codes. They appear in every output
/// format (JSON `code`, SARIF `ruleId`, GitHub `title`), so never rename one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
pub enum Code {
    #[serde(rename = "io")]
    Io,
    #[serde(rename = "encoding")]
    Encoding,
    #[serde(rename = "empty-file")]
    EmptyFile,
    #[serde(rename = "file-too-large")]
    FileTooLarge,
    #[serde(rename = "preprocess")]
    Preprocess,
    #[serde(rename = "import-missing")]
    ImportMissing,
    #[serde(rename = "import-cycle")]
    ImportCycle,
    #[serde(rename = "import-duplicate")]
    ImportDuplicate,
    #[serde(rename = "parse")]
    Parse,
    #[serde(rename = "validation")]
    Validation,
    #[serde(rename = "compiler-panic")]
    CompilerPanic,
    #[serde(rename = "pipeline")]
    Pipeline,
    #[serde(rename = "binding-mismatch")]
    BindingMismatch,
    #[serde(rename = "device-missing")]
    DeviceMissing,
    #[serde(rename = "scene")]
    Scene,
    #[serde(rename = "unused-module")]
    UnusedModule,
    #[serde(rename = "project-file")]
    ProjectFile,
    #[serde(rename = "gpu")]
    Gpu,
    #[serde(rename = "weights")]
    Weights,
    #[serde(rename = "image")]
    Image,
    #[serde(rename = "material")]
    Material,
    #[serde(rename = "image-mismatch")]
    ImageMismatch,
    #[serde(rename = "reference-missing")]
    ReferenceMissing,
    #[serde(rename = "printf-syntax")]
    PrintfSyntax,
    #[serde(rename = "printf-format")]
    PrintfFormat,
    #[serde(rename = "printf-arguments")]
    PrintfArguments,
    #[serde(rename = "printf-type")]
    PrintfType,
    #[serde(rename = "printf-denied")]
    PrintfDenied,
}

impl Code {
    pub fn as_str(self) -> &'static str {
        match self {
            Code::Io => "io",
            Code::Encoding => "encoding",
            Code::EmptyFile => "empty-file",
            Code::FileTooLarge => "file-too-large",
            Code::Preprocess => "preprocess",
            Code::ImportMissing => "import-missing",
            Code::ImportCycle => "import-cycle",
            Code::ImportDuplicate => "import-duplicate",
            Code::Parse => "parse",
            Code::Validation => "validation",
            Code::CompilerPanic => "compiler-panic",
            Code::Pipeline => "pipeline",
            Code::BindingMismatch => "binding-mismatch",
            Code::DeviceMissing => "device-missing",
            Code::Scene => "scene",
            Code::UnusedModule => "unused-module",
            Code::ProjectFile => "project-file",
            Code::Gpu => "gpu",
            Code::Weights => "weights",
            Code::Image => "image",
            Code::Material => "material",
            Code::ImageMismatch => "image-mismatch",
            Code::ReferenceMissing => "reference-missing",
            Code::PrintfSyntax => "printf-syntax",
            Code::PrintfFormat => "printf-format",
            Code::PrintfArguments => "printf-arguments",
            Code::PrintfType => "printf-type",
            Code::PrintfDenied => "printf-denied",
        }
    }

    /// One line describing the rule, for SARIF's rule table and `--help`.
    pub fn description(self) -> &'static str {
        match self {
            Code::Io => "the file could not be read",
            Code::Encoding => "the file is not valid UTF-8",
            Code::EmptyFile => "the file is empty",
            Code::FileTooLarge => "the file exceeds the size limit",
            Code::Preprocess => "a preprocessor directive (#ifdef, #define, ...) is malformed",
            Code::ImportMissing => "an #import names a module no file defines",
            Code::ImportCycle => "modules import each other in a cycle",
            Code::ImportDuplicate => "two files define the same import path",
            Code::Parse => "the WGSL does not parse",
            Code::Validation => "the module parses but is not valid WGSL",
            Code::CompilerPanic => "the shader compiler crashed on this input",
            Code::Pipeline => "the GPU driver rejected the pipeline",
            Code::BindingMismatch => "the shader's bindings do not match the layout the renderer binds",
            Code::DeviceMissing => "a GPU device was required and none exists",
            Code::Scene => "the scene file is invalid",
            Code::UnusedModule => "a file has no entry point and no #define_import_path: nothing can use it",
            Code::ProjectFile => "the project file loupe.toml is invalid",
            Code::Gpu => "the GPU rejected commands while a frame was recorded or submitted (an error no error scope caught)",
            Code::Weights => "the denoiser's weights file (.tza) is malformed or is not a U-Net loupe can run",
            Code::Image => "an image file is malformed, or does not fit the images it goes with",
            Code::Material => "the material file is invalid",
            Code::ImageMismatch => "an image case renders beyond its FLIP threshold from its reference",
            Code::ReferenceMissing => "an image case has no reference image: bless one with `loupe check --bless`",
            Code::PrintfSyntax => "a debugPrintf call is malformed (not a statement, no string literal, no enable directive)",
            Code::PrintfFormat => "a debugPrintf format string has a placeholder loupe does not know",
            Code::PrintfArguments => "a debugPrintf call passes more or fewer arguments than its format string has placeholders",
            Code::PrintfType => "a debugPrintf argument's type does not fit its placeholder, or cannot be printed",
            Code::PrintfDenied => "a debugPrintf call in a check run with --deny-debug-printf",
        }
    }

    pub const ALL: [Code; 28] = [
        Code::Io,
        Code::Encoding,
        Code::EmptyFile,
        Code::FileTooLarge,
        Code::Preprocess,
        Code::ImportMissing,
        Code::ImportCycle,
        Code::ImportDuplicate,
        Code::Parse,
        Code::Validation,
        Code::CompilerPanic,
        Code::Pipeline,
        Code::BindingMismatch,
        Code::DeviceMissing,
        Code::Scene,
        Code::UnusedModule,
        Code::ProjectFile,
        Code::Gpu,
        Code::Weights,
        Code::Image,
        Code::Material,
        Code::ImageMismatch,
        Code::ReferenceMissing,
        Code::PrintfSyntax,
        Code::PrintfFormat,
        Code::PrintfArguments,
        Code::PrintfType,
        Code::PrintfDenied,
    ];
}

#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Diagnostic {
    pub severity: Severity,
    pub code: Code,
    pub message: String,
    /// Where the primary label points; `None` only for problems with no file
    /// at all (no device).
    pub location: Option<Location>,
    pub labels: Vec<Label>,
    pub notes: Vec<String>,
}

impl Diagnostic {
    pub fn error(code: Code, message: impl Into<String>) -> Self {
        Diagnostic { severity: Severity::Error, code, message: message.into(), location: None, labels: Vec::new(), notes: Vec::new() }
    }

    pub fn warning(code: Code, message: impl Into<String>) -> Self {
        Diagnostic { severity: Severity::Warning, ..Diagnostic::error(code, message) }
    }

    pub fn at(mut self, location: Location) -> Self {
        self.location = Some(location);
        self
    }

    /// Adds a label; the first primary label also becomes the location.
    pub fn with_label(mut self, location: Location, message: impl Into<String>, primary: bool) -> Self {
        if primary && self.location.is_none() {
            self.location = Some(location.clone());
        }
        self.labels.push(Label { location, message: message.into(), primary });
        self
    }

    pub fn with_note(mut self, note: impl Into<String>) -> Self {
        self.notes.push(note.into());
        self
    }

    pub fn file(&self) -> Option<&str> {
        self.location.as_ref().map(|l| l.file.as_str())
    }
}

impl std::fmt::Display for Diagnostic {
    /// One line, `file:line:col: severity[code]: message`, the shape
    /// compilers and editors' problem matchers understand.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if let Some(loc) = &self.location {
            write!(f, "{loc}: ")?;
        }
        write!(f, "{}[{}]: {}", self.severity.as_str(), self.code.as_str(), self.message)
    }
}
