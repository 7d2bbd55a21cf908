//! A command's result, printed as one JSON object or as text.

use serde::Serialize;

use crate::error::Fail;

/// A command's typed result: one JSON object with `--json`, text without.
pub trait Output: Serialize {
    /// The result as text.
    fn text(&self) -> String;
}

/// `out` as one line of JSON (`json`) or as its text.
pub fn render(out: &impl Output, json: bool) -> Result<String, Fail> {
    if json { json_line(out) } else { Ok(out.text()) }
}

/// `v` as one JSON object on one line: keys in alphabetical order, `null` for a number that is
/// not finite.
pub fn json_line(v: &impl Serialize) -> Result<String, Fail> {
    Ok(format!("{}\n", serde_json::to_value(v)?))
}

/// A number or an array in text output, written as `--json` writes it (`null` for a number
/// that is not finite).
pub fn json(v: &impl Serialize) -> String {
    serde_json::to_string(v).expect("numbers and arrays serialise")
}

/// `v` when it is finite: a criterion or an error that is undefined is `null`.
pub fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}
