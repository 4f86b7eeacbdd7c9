//! GitHub Actions workflow commands; the runner turns each line into an
//! annotation on the pull request's diff.

use std::io;

use super::super::report::CheckReport;
use crate::diag::Severity;

pub fn write(report: &CheckReport, out: &mut dyn io::Write) -> io::Result<()> {
    for d in report.diagnostics() {
        let command = match d.severity {
            Severity::Error => "error",
            Severity::Warning => "warning",
            Severity::Note => "notice",
        };
        let mut properties = Vec::new();
        if let Some(l) = &d.location {
            properties.push(format!("file={}", property(&l.file)));
            properties.push(format!("line={}", l.line));
            properties.push(format!("col={}", l.column));
            properties.push(format!("endLine={}", l.end_line));
            properties.push(format!("endColumn={}", l.end_column));
        }
        properties.push(format!("title={}", property(d.code.as_str())));
        // An annotation has no room for notes, so they follow the message.
        let mut message = d.message.clone();
        for note in &d.notes {
            message.push('\n');
            message.push_str(note);
        }
        writeln!(out, "::{command} {}::{}", properties.join(","), data(&message))?;
    }
    Ok(())
}

/// The runner's escaping for a command's message.
fn data(s: &str) -> String {
    s.replace('%', "%25").replace('\r', "%0D").replace('\n', "%0A")
}

/// Property values additionally must not contain the `:` and `,` that
/// delimit them.
fn property(s: &str) -> String {
    data(s).replace(':', "%3A").replace(',', "%2C")
}

#[cfg(test)]
mod tests {
    use super::super::fixture;
    use super::*;
    use crate::diag::{Code, Diagnostic};

    fn render(report: &CheckReport) -> String {
        let mut out = Vec::new();
        write(report, &mut out).unwrap();
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn annotations() {
        assert_eq!(
            render(&fixture::report()),
            "::error file=shaders/lib/util.wgsl,line=5,col=7,endLine=5,endColumn=10,title=validation::\
             cannot add \"f32\" & \"vec3<f32>\"%0Aboth operands must have the same type\n\
             ::warning file=shaders/main.wgsl,line=3,col=1,endLine=3,endColumn=22,title=binding-mismatch::\
             binding 0 is never used\n"
        );
    }

    #[test]
    fn escaping_and_no_location() {
        let mut d = Diagnostic::error(Code::DeviceMissing, "100% gone\r\nreally").with_note("a:b,c");
        d.severity = Severity::Note;
        let report = CheckReport { general: vec![d], ..CheckReport::default() };
        assert_eq!(render(&report), "::notice title=device-missing::100%25 gone%0D%0Areally%0Aa:b,c\n");
        assert_eq!(property("C:\\a,b%"), "C%3A\\a%2Cb%25");
    }
}
