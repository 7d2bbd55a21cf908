//! One-line errors: what the tool prints on stderr before it exits with status 2.

use std::fmt::Display;
use std::path::PathBuf;

/// A one-line error for stderr; the tool exits with status 2.
pub struct Fail(pub String);

impl<E: Display> From<E> for Fail {
    fn from(e: E) -> Self {
        Fail(e.to_string())
    }
}

/// `e` after the names of the record's files, joined by `+` (`a.csv+b.csv: e`).
pub fn with_file(files: &[PathBuf], e: impl Display) -> Fail {
    let names: Vec<String> = files.iter().map(|f| f.display().to_string()).collect();
    Fail(format!("{}: {e}", names.join("+")))
}

/// `text` with every control character escaped (`\n`, `\r`, `\t`, `\u{..}`), so that echoed
/// input keeps an error message on one line.
pub fn escaped(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() {
            out.extend(c.escape_default());
        } else {
            out.push(c);
        }
    }
    out
}
