//! Opening a problem's file at its line in the user's editor: `$VISUAL`,
//! else `$EDITOR`, with the line convention its program understands.

use std::path::Path;

/// The command line that opens `file` at `line:column` with `editor` (the
/// variable's value, which may carry arguments: `code --wait`).
///
/// - `+LINE FILE`: vi, vim, nvim, nano, emacs, emacsclient, kak, micro;
/// - `FILE:LINE:COL`: subl, zed; VS Code (`code`) after `--goto`;
/// - any other program gets the file alone.
pub fn command_line(editor: &str, file: &str, line: u32, column: u32) -> Option<Vec<String>> {
    let mut words: Vec<String> = editor.split_whitespace().map(str::to_owned).collect();
    let program = Path::new(words.first()?).file_name()?.to_str()?.to_owned();
    match program.as_str() {
        "vi" | "vim" | "nvim" | "nano" | "emacs" | "emacsclient" | "kak" | "micro" => {
            words.extend([format!("+{line}"), file.to_owned()]);
        }
        "code" | "code-insiders" | "codium" => words.extend(["--goto".to_owned(), format!("{file}:{line}:{column}")]),
        "subl" | "zed" => words.push(format!("{file}:{line}:{column}")),
        _ => words.push(file.to_owned()),
    }
    Some(words)
}

/// `$VISUAL`, else `$EDITOR`, when either is set and not empty.
pub fn from_env() -> Option<String> {
    ["VISUAL", "EDITOR"].into_iter().filter_map(std::env::var_os).filter_map(|v| v.into_string().ok()).find(|v| !v.trim().is_empty())
}

/// Starts the editor without waiting for it: a thread reaps it when it
/// exits, so the window never blocks on an editor left open.
pub fn open(editor: &str, file: &str, line: u32, column: u32) -> Result<(), String> {
    let words = command_line(editor, file, line, column).ok_or_else(|| format!("cannot read the editor command `{editor}`"))?;
    let mut child = std::process::Command::new(&words[0])
        .args(&words[1..])
        .spawn()
        .map_err(|e| format!("cannot start the editor `{}`: {e}", words[0]))?;
    std::thread::spawn(move || {
        let _ = child.wait();
    });
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::command_line;

    fn line(editor: &str) -> Vec<String> {
        command_line(editor, "shaders/a.wgsl", 12, 5).unwrap()
    }

    #[test]
    fn each_editor_gets_its_own_convention() {
        assert_eq!(line("vim"), ["vim", "+12", "shaders/a.wgsl"]);
        assert_eq!(line("/usr/bin/nvim"), ["/usr/bin/nvim", "+12", "shaders/a.wgsl"]);
        assert_eq!(line("emacsclient -t"), ["emacsclient", "-t", "+12", "shaders/a.wgsl"]);
        assert_eq!(line("code --wait"), ["code", "--wait", "--goto", "shaders/a.wgsl:12:5"]);
        assert_eq!(line("zed"), ["zed", "shaders/a.wgsl:12:5"]);
        assert_eq!(line("gedit"), ["gedit", "shaders/a.wgsl"]);
        assert_eq!(command_line("  ", "a", 1, 1), None);
    }
}
