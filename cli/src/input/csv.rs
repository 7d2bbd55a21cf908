//! Reading one column of CSV sensor logs, with errors that name the file and the line. The file
//! name `-` is standard input.

use std::fmt;
use std::fs::File;
use std::io::{BufReader, IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use crate::error::escaped;

/// A problem with an input file, for a one-line message `FILE[:LINE]: problem`.
#[derive(Debug, Clone, PartialEq)]
pub struct DataError {
    /// The file.
    pub file: PathBuf,
    /// The 1-based line, where one is to blame.
    pub line: Option<u64>,
    /// What is wrong.
    pub problem: String,
}

impl fmt::Display for DataError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        write!(f, ": {}", self.problem)
    }
}

impl std::error::Error for DataError {}

fn error(file: &Path, line: Option<u64>, problem: impl Into<String>) -> DataError {
    DataError {
        file: file.to_path_buf(),
        line,
        problem: problem.into(),
    }
}

/// The file name that stands for standard input.
pub const STDIN: &str = "-";

/// Reads column `column` of each file in turn (a record split over several files is joined in
/// order). Files are CSV with a header row; lines starting with `#` are ignored. The files are
/// streamed row by row; on a terminal, progress goes to stderr every 100,000 rows.
///
/// The file [`STDIN`] (`-`) is standard input, read to its end first (so that an error can
/// name its line); wherever it is named again it gives the same bytes.
///
/// Every cell must be a finite number: a missing column, an empty or non-numeric cell, NaN or
/// infinity is an error naming the file and line, and so is a file without data rows.
pub fn read_column(files: &[PathBuf], column: &str) -> Result<Vec<f64>, DataError> {
    read_cells(files, column, finite(column))
}

/// Reads column `column` of each file as text, as [`read_column`] reads numbers.
pub fn read_text_column(files: &[PathBuf], column: &str) -> Result<Vec<String>, DataError> {
    read_cells(files, column, |cell| Ok(cell.to_string()))
}

/// Reads column `column` of CSV text held in memory, as [`read_column`] reads a file;
/// errors name `label` as the file.
pub fn parse_column(label: &Path, bytes: &[u8], column: &str) -> Result<Vec<f64>, DataError> {
    let mut out = Vec::new();
    let locate = |byte| line_at(bytes, byte);
    read_source(
        label,
        bytes,
        column,
        &finite(column),
        &mut out,
        false,
        &locate,
    )?;
    Ok(out)
}

/// The 1-based line of the record that starts at `byte` of `source` (or at the first line
/// after it that is neither empty nor a comment): a record's own line, however many empty or
/// comment lines come before it.
///
/// Lines are counted as the CSV reader ends records: at `\n`, `\r\n` or a lone `\r`; and, as
/// for the reader, a comment is a line whose first byte is `#` (an indented `#` is a record).
fn line_at(source: impl Read, byte: u64) -> Option<u64> {
    let mut bytes = BufReader::new(source).bytes();
    let mut line = 1u64;
    // Whether the last byte was a '\r' (so that a '\n' after it ends no second line).
    let mut after_cr = false;
    for _ in 0..byte {
        let Some(b) = bytes.next() else {
            return Some(line);
        };
        let b = b.ok()?;
        if b == b'\r' || (b == b'\n' && !after_cr) {
            line += 1;
        }
        after_cr = b == b'\r';
    }
    // Skip the empty and comment lines before the record.
    while let Some(b) = bytes.next() {
        let b = b.ok()?;
        if b == b'\n' && after_cr {
            after_cr = false;
            continue;
        }
        after_cr = false;
        match b {
            b'\r' | b'\n' => {
                after_cr = b == b'\r';
                line += 1;
            }
            b'#' => {
                // The reader's comment runs to the next '\n' (over any lone '\r', each a
                // line of its own); a comment without one is no line before a record.
                let mut ended = false;
                for c in bytes.by_ref() {
                    let c = c.ok()?;
                    if c == b'\r' || (c == b'\n' && !after_cr) {
                        line += 1;
                    }
                    after_cr = c == b'\r';
                    if c == b'\n' {
                        ended = true;
                        break;
                    }
                }
                after_cr = false;
                if !ended {
                    break;
                }
            }
            _ => break,
        }
    }
    Some(line)
}

/// A cell as shown in an error: cut to its first 40 characters when it is longer.
fn shown(cell: &str) -> String {
    const KEEP: usize = 40;
    match cell.char_indices().nth(KEEP) {
        Some((end, _)) => format!("{}... ({} bytes)", escaped(&cell[..end]), cell.len()),
        None => escaped(cell),
    }
}

/// A cell as a finite number, or what is wrong with it.
fn finite(column: &str) -> impl Fn(&str) -> Result<f64, String> + '_ {
    move |cell| match cell.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!(
            "column '{column}': '{}' is not a finite number",
            shown(cell)
        )),
        Err(_) => Err(format!(
            "column '{column}': '{}' is not a number",
            shown(cell)
        )),
    }
}

/// The cells of `column`, each converted by `parse` (whose error names the problem).
fn read_cells<T>(
    files: &[PathBuf],
    column: &str,
    parse: impl Fn(&str) -> Result<T, String>,
) -> Result<Vec<T>, DataError> {
    let progress = std::io::stderr().is_terminal();
    let mut out = Vec::new();
    for path in files {
        if path.as_os_str() == STDIN {
            let bytes = stdin().map_err(|e| error(path, None, format!("cannot read: {e}")))?;
            let locate = |byte| line_at(bytes, byte);
            read_source(path, bytes, column, &parse, &mut out, progress, &locate)?;
            continue;
        }
        let file = File::open(path).map_err(|e| error(path, None, format!("cannot open: {e}")))?;
        let source = BufReader::with_capacity(1 << 16, file);
        let locate = |byte| line_at(File::open(path).ok()?, byte);
        read_source(path, source, column, &parse, &mut out, progress, &locate)?;
    }
    if progress && out.len() >= 100_000 {
        eprintln!("\rread {} rows", out.len());
    }
    Ok(out)
}

/// All of standard input, read once.
fn stdin() -> Result<&'static [u8], &'static str> {
    static BYTES: OnceLock<Result<Vec<u8>, String>> = OnceLock::new();
    BYTES
        .get_or_init(|| {
            let mut bytes = Vec::new();
            match std::io::stdin().lock().read_to_end(&mut bytes) {
                Ok(_) => Ok(bytes),
                Err(e) => Err(e.to_string()),
            }
        })
        .as_deref()
        .map_err(String::as_str)
}

/// Appends the cells of `column` of one CSV source (named `path` in errors) to `out`;
/// `locate` gives the line of a byte offset, for errors.
fn read_source<T>(
    path: &Path,
    source: impl Read,
    column: &str,
    parse: &impl Fn(&str) -> Result<T, String>,
    out: &mut Vec<T>,
    progress: bool,
    locate: &dyn Fn(u64) -> Option<u64>,
) -> Result<(), DataError> {
    let mut reader = ::csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(::csv::Trim::All)
        .flexible(true)
        .from_reader(source);
    let headers = reader
        .headers()
        .map_err(|e| error(path, None, format!("cannot read the header: {e}")))?
        .clone();
    if headers.is_empty() {
        return Err(error(path, None, "empty file (no header row)"));
    }
    let Some(index) = headers.iter().position(|h| h == column) else {
        let names: Vec<String> = headers.iter().map(shown).collect();
        return Err(error(
            path,
            None,
            format!(
                "no column '{}' (columns: {})",
                escaped(column),
                names.join(", ")
            ),
        ));
    };
    let copies = headers.iter().filter(|h| *h == column).count();
    if copies > 1 {
        return Err(error(
            path,
            None,
            format!("the header names column '{column}' {copies} times"),
        ));
    }
    let start = out.len();
    let mut record = ::csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                let line = e.position().and_then(|p| locate(p.byte()));
                return Err(error(path, line, format!("malformed CSV: {e}")));
            }
        }
        let line = || record.position().and_then(|p| locate(p.byte()));
        let cell = record.get(index).ok_or_else(|| {
            error(
                path,
                line(),
                format!("column '{column}' missing in this row"),
            )
        })?;
        out.push(parse(cell).map_err(|problem| error(path, line(), problem))?);
        if progress && out.len().is_multiple_of(100_000) {
            eprint!("\rread {} rows", out.len());
            let _ = std::io::stderr().flush();
        }
    }
    if out.len() == start {
        return Err(error(path, None, "no data rows"));
    }
    Ok(())
}
