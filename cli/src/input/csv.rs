//! Reading one column of CSV sensor logs, with errors that name the file and the line. The file
//! name `-` is standard input.

use std::fmt;
use std::fs::File;
use std::io::{BufReader, IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Mutex, OnceLock};

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

/// Picks the indices of the columns to read from a file's header, or says what is wrong.
pub type Select<'a> = dyn FnMut(&[String]) -> Result<Vec<usize>, String> + 'a;

/// Whether another display shows the progress (`characterise`'s bar).
static QUIET: AtomicBool = AtomicBool::new(false);

/// Leaves the progress display to the caller: no "read N rows" lines from here on.
pub fn quiet_progress() {
    QUIET.store(true, Ordering::Relaxed);
}

/// The file name that stands for standard input.
pub const STDIN: &str = "-";

/// Reads column `column` of each file in turn (a record split over several files is joined in
/// order). Files are CSV with a header row; lines starting with `#` are ignored, but for a
/// header written as a comment (`#timestamp [ns],w_RS_S_x [rad s^-1],...`, as in EuRoC, ASL
/// and TUM-VI files): when the first line that is not a comment holds only numbers, the last
/// comment line before it, without its `#`, is the header. A column is named as in the header,
/// by its name without a unit bracket (`w_RS_S_x`), or by its 0-based index. The files are
/// streamed row by row; on a terminal, progress goes to stderr every 100,000 rows.
///
/// The file [`STDIN`] (`-`) is standard input, read to its end first (so that an error can
/// name its line); wherever it is named again it gives the same bytes. A named pipe or a
/// process substitution is read once the same way ([`read_once`]).
///
/// Every cell must be a finite number: a missing column, an empty or non-numeric cell, NaN or
/// infinity is an error naming the file and line, and so is a file without data rows.
pub fn read_column(files: &[PathBuf], column: &str) -> Result<Vec<f64>, DataError> {
    let parse = finite(column);
    let mut out = Vec::new();
    read_rows(
        files,
        &mut |header| Ok(vec![position(header, column)?]),
        &mut |cells| {
            out.push(parse(cells[0])?);
            Ok(())
        },
    )?;
    Ok(out)
}

/// Reads column `column` of each file as text, as [`read_column`] reads numbers.
pub fn read_text_column(files: &[PathBuf], column: &str) -> Result<Vec<String>, DataError> {
    let mut out = Vec::new();
    read_rows(
        files,
        &mut |header| Ok(vec![position(header, column)?]),
        &mut |cells| {
            out.push(cells[0].to_string());
            Ok(())
        },
    )?;
    Ok(out)
}

/// Reads column `column` of CSV text held in memory, as [`read_column`] reads a file;
/// errors name `label` as the file.
pub fn parse_column(label: &Path, bytes: &[u8], column: &str) -> Result<Vec<f64>, DataError> {
    let parse = finite(column);
    let mut out = Vec::new();
    let locate = |byte| line_at(bytes, byte);
    let header = comment_header(bytes).map_err(|e| error(label, None, e))?;
    read_source(
        label,
        (bytes, header),
        &mut |header| Ok(vec![position(header, column)?]),
        &mut |cells| {
            out.push(parse(cells[0])?);
            Ok(())
        },
        &locate,
    )?;
    Ok(out)
}

/// The cells of the columns that `select` picks from each file's header (by index), row by row,
/// to `each`, in order over all files; an error from either names the file (and, from `each`,
/// the line). Returns the number of rows. What [`read_column`] says of files and headers holds.
pub fn read_rows(
    files: &[PathBuf],
    select: &mut Select,
    each: &mut dyn FnMut(&[&str]) -> Result<(), String>,
) -> Result<u64, DataError> {
    let progress = std::io::stderr().is_terminal() && !QUIET.load(Ordering::Relaxed);
    let mut rows = 0u64;
    let mut counted = |cells: &[&str]| {
        rows += 1;
        if progress && rows.is_multiple_of(100_000) {
            eprint!("\rread {rows} rows");
            let _ = std::io::stderr().flush();
        }
        each(cells)
    };
    for path in files {
        if let Some(bytes) = read_once(path) {
            let bytes = bytes.map_err(|e| error(path, None, format!("cannot read: {e}")))?;
            let header = comment_header(bytes).map_err(|e| error(path, None, e))?;
            let locate = |byte| line_at(bytes, byte);
            read_source(path, (bytes, header), select, &mut counted, &locate)?;
            continue;
        }
        let open = || File::open(path).map_err(|e| error(path, None, format!("cannot open: {e}")));
        let header = comment_header(BufReader::new(open()?)).map_err(|e| error(path, None, e))?;
        let source = BufReader::with_capacity(1 << 16, open()?);
        let locate = |byte| line_at(File::open(path).ok()?, byte);
        read_source(path, (source, header), select, &mut counted, &locate)?;
    }
    if progress && rows >= 100_000 {
        eprintln!("\rread {rows} rows");
    }
    Ok(rows)
}

/// The header of the first of `files` (a comment header too, as [`read_column`] finds it).
pub fn header(files: &[PathBuf]) -> Result<Vec<String>, DataError> {
    let mut names = Vec::new();
    let stop = "\0";
    let got = read_rows(
        &files[..files.len().min(1)],
        &mut |header| {
            names = header.to_vec();
            Err(stop.into())
        },
        &mut |_| Ok(()),
    );
    match got {
        Err(e) if e.problem == stop => Ok(names),
        Err(e) => Err(e),
        Ok(_) => Ok(names),
    }
}

/// The index of `column` in `header`: the name as written, the name without its unit bracket
/// (`w_RS_S_x` for `w_RS_S_x [rad s^-1]`), or a 0-based index.
pub fn position(header: &[String], column: &str) -> Result<usize, String> {
    let exact: Vec<usize> = (0..header.len()).filter(|&i| header[i] == column).collect();
    let bare: Vec<usize> = (0..header.len())
        .filter(|&i| split_unit(&header[i]).0 == column)
        .collect();
    let found = if exact.is_empty() { bare } else { exact };
    match (found.as_slice(), column.parse::<usize>()) {
        ([i], _) => Ok(*i),
        ([], Ok(i)) if i < header.len() => Ok(i),
        ([], _) => {
            let names: Vec<String> = header.iter().map(|h| shown(h)).collect();
            Err(format!(
                "no column '{}' (columns: {})",
                escaped(column),
                names.join(", ")
            ))
        }
        (copies, _) => Err(format!(
            "the header names column '{}' {} times",
            escaped(column),
            copies.len()
        )),
    }
}

/// A header name split into its name and the unit in a trailing bracket:
/// `w_RS_S_x [rad s^-1]` is `("w_RS_S_x", Some("rad s^-1"))`.
pub fn split_unit(name: &str) -> (&str, Option<&str>) {
    let name = name.trim();
    for (open, close) in [('[', ']'), ('(', ')')] {
        if let Some(inner) = name.strip_suffix(close)
            && let Some(at) = inner.rfind(open)
        {
            let bare = inner[..at].trim_end();
            if !bare.is_empty() {
                return (bare, Some(inner[at + 1..].trim()));
            }
        }
    }
    (name, None)
}

/// Whether a record holds only numbers (empty trailing cells aside: a line that ends in a comma).
fn all_numbers(record: &::csv::StringRecord) -> bool {
    let cells: Vec<&str> = record.iter().map(str::trim).collect();
    let end = cells
        .iter()
        .rposition(|c| !c.is_empty())
        .map_or(0, |i| i + 1);
    end > 0 && cells[..end].iter().all(|c| c.parse::<f64>().is_ok())
}

/// The header of a file whose header is a comment: when the first record that is not a
/// comment holds only numbers and a comment line comes before it, that comment line without
/// its `#`. `None` when the file has an ordinary header row (or no comment before its data).
fn comment_header(source: impl Read) -> Result<Option<Vec<String>>, String> {
    let mut reader = ::csv::ReaderBuilder::new()
        .comment(None)
        .has_headers(false)
        .flexible(true)
        .from_reader(source);
    let mut last_comment = None;
    let mut record = ::csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(true) => {}
            Ok(false) => return Ok(None),
            Err(e) => return Err(format!("cannot read the header: {e}")),
        }
        let first = record.get(0).unwrap_or("");
        if let Some(rest) = first.strip_prefix('#') {
            let mut names = vec![rest.trim().to_string()];
            names.extend(record.iter().skip(1).map(|c| c.trim().to_string()));
            last_comment = Some(names);
            continue;
        }
        let numeric = all_numbers(&record);
        return Ok(if numeric { last_comment } else { None });
    }
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
pub fn shown(cell: &str) -> String {
    const KEEP: usize = 40;
    match cell.char_indices().nth(KEEP) {
        Some((end, _)) => format!("{}... ({} bytes)", escaped(&cell[..end]), cell.len()),
        None => escaped(cell),
    }
}

/// A cell as a finite number, or what is wrong with it.
pub fn finite(column: &str) -> impl Fn(&str) -> Result<f64, String> + '_ {
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

/// All of standard input, read once.
/// The bytes of standard input, or of a file that can be read only once (a named pipe, a
/// process substitution such as `<(cat f.csv)`, a character device): read to its end the
/// first time it is asked for, and the same bytes every time after. `None` for a regular file
/// (and a folder), which is read where it lies.
pub fn read_once(path: &Path) -> Option<Result<&'static [u8], String>> {
    type Cache = Mutex<Vec<(PathBuf, Result<&'static [u8], String>)>>;
    static READ: OnceLock<Cache> = OnceLock::new();
    let is_stdin = path.as_os_str() == STDIN;
    if !is_stdin {
        match std::fs::metadata(path) {
            Ok(m) if m.is_file() || m.is_dir() => return None,
            Ok(_) => {}
            // Cannot even be looked at: opening it gives the error.
            Err(_) => return None,
        }
    }
    let mut cache = READ
        .get_or_init(Mutex::default)
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner);
    if let Some((_, bytes)) = cache.iter().find(|(p, _)| p == path) {
        return Some(bytes.clone());
    }
    let mut bytes = Vec::new();
    let read = if is_stdin {
        std::io::stdin().lock().read_to_end(&mut bytes)
    } else {
        File::open(path).and_then(|mut f| f.read_to_end(&mut bytes))
    };
    // Leaked: read once per process, and kept to its end like the file it stands for.
    let got = read.map(|_| &*Vec::leak(bytes)).map_err(|e| e.to_string());
    cache.push((path.to_path_buf(), got.clone()));
    Some(got)
}

/// Passes the cells that `select` picks of each row of one CSV source (named `path` in errors,
/// with its header if that is a comment line) to `each`; `locate` gives the line of a byte
/// offset, for errors.
fn read_source(
    path: &Path,
    (source, comment_header): (impl Read, Option<Vec<String>>),
    select: &mut Select,
    each: &mut dyn FnMut(&[&str]) -> Result<(), String>,
    locate: &dyn Fn(u64) -> Option<u64>,
) -> Result<(), DataError> {
    // Cells are trimmed here, the selected ones only (the reader's own trimming allocates a
    // record per row).
    let mut reader = ::csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .flexible(true)
        .has_headers(comment_header.is_none())
        .from_reader(source);
    let header: Vec<String> = match comment_header {
        Some(names) => names,
        None => reader
            .headers()
            .map_err(|e| error(path, None, format!("cannot read the header: {e}")))?
            .iter()
            .map(|h| h.trim().to_string())
            .collect(),
    };
    if header.is_empty() {
        return Err(error(path, None, "empty file (no header row)"));
    }
    if header.len() > 1 && all_numbers(&::csv::StringRecord::from(header.clone())) {
        return Err(error(
            path,
            Some(1),
            "the first line holds only numbers: a header row naming the columns is needed",
        ));
    }
    let indices = select(&header).map_err(|problem| error(path, None, problem))?;
    let mut record = ::csv::StringRecord::new();
    let mut rows = 0u64;
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
        if record.len() != header.len() {
            return Err(error(
                path,
                line(),
                format!(
                    "{} fields, the header has {}: a shifted row would read the wrong columns",
                    record.len(),
                    header.len()
                ),
            ));
        }
        // Up to 16 selected cells on the stack, more in a vector.
        let mut small = [""; 16];
        let mut large = Vec::new();
        let cells: &mut [&str] = if indices.len() <= small.len() {
            &mut small[..indices.len()]
        } else {
            large.resize(indices.len(), "");
            &mut large
        };
        for (cell, &i) in cells.iter_mut().zip(&indices) {
            match record.get(i) {
                Some(c) => *cell = c.trim(),
                None => {
                    let name = header.get(i).map_or(String::new(), |h| escaped(h));
                    return Err(error(
                        path,
                        line(),
                        format!("column '{name}' missing in this row"),
                    ));
                }
            }
        }
        each(cells).map_err(|problem| error(path, line(), problem))?;
        rows += 1;
    }
    if rows == 0 {
        return Err(error(path, None, "no data rows"));
    }
    Ok(())
}
