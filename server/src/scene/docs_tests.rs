//! `docs/scenes.md` carries the `[post]` and `[quality]` settings table as
//! `settings!` declares it, between two marker comments; this test renders
//! the table and requires the doc to hold it exactly, so the doc cannot
//! drift from the code. `LOUPE_BLESS=1` rewrites the section instead.

use super::settings::{Kind, SETTINGS};

const BEGIN: &str = "<!-- settings table: generated from server/src/scene/settings.rs; LOUPE_BLESS=1 cargo test -p loupe --lib scene::docs_tests rewrites it -->";
const END: &str = "<!-- end of the settings table -->";

/// The table in Markdown: one row per setting, in the browser's order.
fn table() -> String {
    let defaults = super::parse("defaults.toml", "").expect("an empty scene is valid");
    let mut out = String::from("| setting | values | default | control | what it does | affects |\n|---|---|---|---|---|---|\n");
    for s in SETTINGS {
        let values = match s.kind {
            Kind::Toggle => "`true`, `false`".to_owned(),
            Kind::Int { min, max, .. } => format!("whole number, {min} to {max}"),
            Kind::Float { min, max, .. } => format!("number, {min} to {max}"),
            Kind::Choice(options) => options.iter().map(|o| format!("`\"{o}\"`")).collect::<Vec<_>>().join(", "),
        };
        // A group (`@fullscreen`) as the passes it stands for, as the browser shows it.
        let affects = crate::render::passes::affected(s.affects).iter().map(|p| format!("`{p}`")).collect::<Vec<_>>().join(", ");
        let row =
            [format!("`{}`", s.path), values, format!("`{}`", (s.get)(&defaults)), s.label.to_owned(), s.doc.trim().to_owned(), affects];
        out += &format!("| {} |\n", row.map(|cell| cell.replace('|', "\\|")).join(" | "));
    }
    out
}

/// The first row where two tables differ, `None` past the end of one.
fn first_difference<'a>(a: &'a str, b: &'a str) -> (Option<&'a str>, Option<&'a str>) {
    let rows = |t: &'a str| t.lines().map(Some).chain(std::iter::once(None));
    rows(a).zip(rows(b)).find(|(x, y)| x != y).unwrap_or_default()
}

#[test]
fn docs_scenes_md_holds_the_settings_table() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/scenes.md");
    let doc = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let (Some(begin), Some(end)) = (doc.find(BEGIN), doc.find(END)) else {
        panic!("{} lacks the markers {BEGIN:?} … {END:?}", path.display());
    };
    let start = begin + BEGIN.len();
    let (held, wanted) = (doc[start..end].trim_matches('\n'), table());
    if std::env::var_os("LOUPE_BLESS").is_some() {
        std::fs::write(&path, format!("{}\n{wanted}{}", &doc[..start], &doc[end..])).unwrap();
    } else if held != wanted.trim_end() {
        let (doc_row, code_row) = first_difference(held, &wanted);
        panic!(
            "docs/scenes.md's settings table differs from settings! (LOUPE_BLESS=1 to regenerate):\n  doc:  {}\n  code: {}",
            doc_row.unwrap_or("(no row)"),
            code_row.unwrap_or("(no row)")
        );
    }
}
