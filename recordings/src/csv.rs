//! Reading one column of CSV sensor logs, with errors that name the file and the line. The file
//! name `-` is standard input.

use std::fmt;
use std::fs::File;
use std::io::{BufRead, BufReader, IsTerminal, Read, Seek, SeekFrom, Write};
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
    let header = comment_header(Source::Held(bytes)).map_err(|e| error(label, None, e))?;
    read_source(
        label,
        (Source::Held(bytes), header),
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
            let header = comment_header(Source::Held(bytes)).map_err(|e| error(path, None, e))?;
            let locate = |byte| line_at(bytes, byte);
            read_source(
                path,
                (Source::Held(bytes), header),
                select,
                &mut counted,
                &locate,
            )?;
            continue;
        }
        // Opened first, for the error of a file that cannot be.
        File::open(path).map_err(|e| error(path, None, format!("cannot open: {e}")))?;
        let header = comment_header(Source::File(path)).map_err(|e| error(path, None, e))?;
        let locate = |byte| line_at(File::open(path).ok()?, byte);
        read_source(
            path,
            (Source::File(path), header),
            select,
            &mut counted,
            &locate,
        )?;
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
/// comment holds only numbers and comment lines come before it, the last of them with as many
/// fields as that record (else the last of them), without its `#`: a line of prose after the
/// header is passed over.
/// `None` when the file has an ordinary header row (or no such comment before its data).
///
/// Read line by line as the row reader reads them: a comment is a line whose first byte is `#`
/// (after a UTF-8 byte order mark on the first line), running to the next `\n`, and whatever
/// it holds (a quote too) stays in it; empty lines are skipped.
fn comment_header(source: Source) -> Result<Option<Vec<String>>, String> {
    let cannot = |e: &dyn fmt::Display| format!("cannot read the header: {e}");
    // One line's first record, as the CSV reader reads it.
    let record_of = |line: &[u8]| -> Result<Option<::csv::StringRecord>, String> {
        let mut reader = ::csv::ReaderBuilder::new()
            .comment(None)
            .has_headers(false)
            .flexible(true)
            .from_reader(line);
        let mut record = ::csv::StringRecord::new();
        match reader.read_record(&mut record) {
            Ok(true) => Ok(Some(record)),
            Ok(false) => Ok(None),
            Err(e) => Err(cannot(&e)),
        }
    };
    let mut lines = BufReader::new(source.open_at(0).map_err(|e| cannot(&e))?);
    // The last comment of each width.
    let mut comments: Vec<Vec<String>> = Vec::new();
    let mut line = Vec::new();
    let mut first = true;
    loop {
        line.clear();
        if lines.read_until(b'\n', &mut line).map_err(|e| cannot(&e))? == 0 {
            return Ok(None);
        }
        let mut text = &line[..];
        if std::mem::take(&mut first) {
            text = text.strip_prefix(BOM).unwrap_or(text);
        }
        if let Some(rest) = text.strip_prefix(b"#") {
            if let Some(record) = record_of(rest)? {
                let names: Vec<String> = record.iter().map(|c| c.trim().to_string()).collect();
                comments.retain(|c| c.len() != names.len());
                comments.push(names);
            }
            continue;
        }
        // The first record: from this line on (a quoted cell may run over lines).
        let Some(record) = record_of(text)? else {
            // An empty line (or one of carriage returns only).
            continue;
        };
        if !all_numbers(&record) {
            return Ok(None);
        }
        // As wide as the data, else the last (a header shorter or longer than its rows is
        // refused as such when the rows are read).
        let same = comments.iter().rposition(|c| c.len() == record.len());
        return Ok(same
            .or(comments.len().checked_sub(1))
            .map(|i| comments.swap_remove(i)));
    }
}

/// The UTF-8 byte order mark some editors put first in a text file.
const BOM: &[u8] = b"\xef\xbb\xbf";

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

/// A cell as a number, as `str::parse::<f64>` reads it (the same values and the same
/// refusals), faster.
fn number(cell: &str) -> Option<f64> {
    crate::decimal::plain(cell.as_bytes()).or_else(|| fast_float2::parse::<f64, _>(cell).ok())
}

/// A cell as a finite number, or what is wrong with it.
pub fn finite(column: &str) -> impl Fn(&str) -> Result<f64, String> + '_ {
    move |cell| match number(cell).ok_or(()) {
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

/// One CSV source's bytes: held in memory (standard input, a pipe, a fuzzer's input), or a
/// file read where it lies.
#[derive(Clone, Copy)]
enum Source<'a> {
    Held(&'a [u8]),
    File(&'a Path),
}

impl<'a> Source<'a> {
    /// The bytes from `byte` on.
    fn open_at(self, byte: u64) -> std::io::Result<Box<dyn Read + Send + 'a>> {
        match self {
            Self::Held(bytes) => {
                let at = usize::try_from(byte).map_or(bytes.len(), |b| b.min(bytes.len()));
                Ok(Box::new(&bytes[at..]))
            }
            Self::File(path) => {
                let mut file = File::open(path)?;
                file.seek(SeekFrom::Start(byte))?;
                Ok(Box::new(file))
            }
        }
    }
}

/// Passes the cells that `select` picks of each row of one CSV source (named `path` in errors,
/// with its header if that is a comment line) to `each`; `locate` gives the line of a byte
/// offset, for errors. Read [`READ_BUFFER`] bytes at a time.
fn read_source(
    path: &Path,
    (source, comment_header): (Source, Option<Vec<String>>),
    select: &mut Select,
    each: &mut dyn FnMut(&[&str]) -> Result<(), String>,
    locate: &dyn Fn(u64) -> Option<u64>,
) -> Result<(), DataError> {
    read_source_in(
        path,
        (source, comment_header),
        select,
        each,
        locate,
        (READ_BUFFER, false),
    )
}

/// Bytes read at a time, and so the text of a batch of records: small enough that a batch's
/// text and fields are still in the cache when the rows are checked and parsed.
const READ_BUFFER: usize = 1 << 18;

/// [`read_source`] with a buffer of `buffer` bytes to start with (lines longer than it
/// enlarge it), scanned on a thread of its own also when the source is short (`force_thread`).
fn read_source_in(
    path: &Path,
    (source, comment_header): (Source, Option<Vec<String>>),
    select: &mut Select,
    each: &mut dyn FnMut(&[&str]) -> Result<(), String>,
    locate: &dyn Fn(u64) -> Option<u64>,
    (buffer, force_thread): (usize, bool),
) -> Result<(), DataError> {
    let cannot_read = |e: std::io::Error| error(path, None, format!("cannot read: {e}"));
    let (header, start) = match comment_header {
        Some(names) => (names, 0),
        None => {
            let mut reader = ::csv::ReaderBuilder::new()
                .comment(Some(b'#'))
                .flexible(true)
                .from_reader(source.open_at(0).map_err(cannot_read)?);
            let names = reader
                .headers()
                .map_err(|e| error(path, None, format!("cannot read the header: {e}")))?
                .iter()
                .map(|h| h.trim().to_string())
                .collect();
            // Where the first record after the header starts.
            (names, reader.position().byte())
        }
    };
    if header.is_empty() {
        return Err(error(path, None, "empty file (no header row)"));
    }
    if let [only] = header.as_slice()
        && let Some((name, symbol)) = [("tabs", '\t'), ("semicolons", ';')]
            .into_iter()
            .find(|&(_, c)| only.contains(c))
    {
        return Err(error(
            path,
            None,
            format!(
                "the header is one field holding {name} ('{}'): the values are separated by \
                 {name}, not commas; the files read are comma-separated (replace the {name} by \
                 commas, e.g. tr '{}' ',')",
                shown(only),
                symbol.escape_default()
            ),
        ));
    }
    if header.len() > 1 && all_numbers(&::csv::StringRecord::from(header.clone())) {
        return Err(error(
            path,
            Some(1),
            "the first line holds only numbers: a header row naming the columns is needed",
        ));
    }
    let indices = select(&header).map_err(|problem| error(path, None, problem))?;
    let mut rows = Rows {
        path,
        header: &header,
        indices: &indices,
        each,
        locate,
        buffer: buffer.max(1),
        count: 0,
    };
    let threaded = match source {
        Source::Held(bytes) => bytes.len() > SCAN_THREAD_FROM || force_thread,
        Source::File(_) => true,
    };
    rows.read(source.open_at(start).map_err(cannot_read)?, start, threaded)?;
    if rows.count == 0 {
        return Err(error(path, None, "no data rows"));
    }
    Ok(())
}

/// `cell` without the white space around it, as [`str::trim`] takes it off (Unicode's), but
/// ASCII's first, fast: the rest only where an end is not ASCII or is a vertical tab (white
/// space to Unicode, not to [`u8::is_ascii_whitespace`]).
fn trimmed(cell: &str) -> &str {
    let ascii = cell.trim_ascii();
    let plain = |b: u8| b.is_ascii() && b != 0x0b;
    match (ascii.bytes().next(), ascii.bytes().next_back()) {
        (Some(a), Some(b)) if !(plain(a) && plain(b)) => ascii.trim(),
        _ => ascii,
    }
}

/// What the CSV reader found wrong with a record (its position is the caller's to give: the
/// reader may have started part way into the file).
fn malformed(e: &::csv::Error) -> String {
    match e.kind() {
        ::csv::ErrorKind::Utf8 { err, .. } => format!(
            "field {} is not UTF-8 text (an invalid byte after its first {} bytes)",
            err.field() + 1,
            err.valid_up_to()
        ),
        ::csv::ErrorKind::Io(io) => format!("cannot read: {io}"),
        _ => format!("malformed CSV: {e}"),
    }
}

/// Records scanned from a source, for [`Rows::take`]: their fields' text in one string.
#[derive(Default)]
struct Batch {
    text: String,
    /// Each field's bounds in `text`.
    fields: Vec<(usize, usize)>,
    /// Each record: the file's byte where it starts, and where its fields end in `fields`
    /// (they start where the record before ends).
    records: Vec<(u64, usize)>,
}

impl Batch {
    fn clear(&mut self) {
        self.text.clear();
        self.fields.clear();
        self.records.clear();
    }

    /// The line `text`, starting at byte `start` of the file, as one record.
    fn line(&mut self, text: &str, start: u64) {
        let base = self.text.len();
        self.text.push_str(text);
        let mut from = 0;
        for comma in memchr::memchr_iter(b',', text.as_bytes()) {
            self.fields.push((base + from, base + comma));
            from = comma + 1;
        }
        self.fields.push((base + from, base + text.len()));
        self.records.push((start, self.fields.len()));
    }
}

/// Text of a batch, bytes, past which it is handed on mid-scan.
const BATCH_TEXT: usize = 1 << 20;

/// Fields of a batch past which it is handed on mid-scan: empty cells hold no text, and each
/// field's bounds take 16 bytes.
const BATCH_FIELDS: usize = 1 << 16;

/// Held sources longer than this, bytes, are scanned on a thread of their own.
const SCAN_THREAD_FROM: usize = 1 << 20;

/// Why a scan stopped early: its consumer stopped it (`None`), or a problem with the file's
/// byte to blame, where there is one.
type Stop = Option<(Option<u64>, String)>;

/// Hands `batch` to `sink` when it holds records, and takes back an empty one.
fn hand_on(batch: &mut Batch, sink: &mut dyn FnMut(Batch) -> Option<Batch>) -> Result<(), Stop> {
    if batch.records.is_empty() {
        return Ok(());
    }
    let mut back = sink(std::mem::take(batch)).ok_or(None)?;
    back.clear();
    *batch = back;
    Ok(())
}

/// The records of `source`, which starts at byte `base` of the file, in batches to `sink`
/// (which hands each back to go on, or `None` to stop), read `buffer` bytes at a time at
/// least: the end, or the problem that ended it, after every record before it.
///
/// Lines are split here, without the CSV reader, while they are plain: no quote, no carriage
/// return but a line's last byte, valid UTF-8. There the CSV reader's records and these lines
/// are one and the same (it ends a record at `\n`, `\r\n` or a lone `\r`, skips empty lines
/// and runs a comment, a line whose first byte is `#`, to the next `\n`). From the first line
/// that is not plain to the end of the source, the CSV reader reads, so that quoting and its
/// errors are its own.
fn scan(
    source: impl Read,
    base: u64,
    buffer: usize,
    sink: &mut dyn FnMut(Batch) -> Option<Batch>,
) -> Result<(), (Option<u64>, String)> {
    let mut batch = Batch::default();
    let end = scan_into(source, base, buffer, &mut batch, sink);
    // The records before a problem go first, so that one of theirs is found first.
    match hand_on(&mut batch, sink).and(end) {
        Ok(()) | Err(None) => Ok(()),
        Err(Some(problem)) => Err(problem),
    }
}

/// [`scan`] into `batch`, handed on at every refill of the buffer.
fn scan_into(
    mut source: impl Read,
    base: u64,
    buffer: usize,
    batch: &mut Batch,
    sink: &mut dyn FnMut(Batch) -> Option<Batch>,
) -> Result<(), Stop> {
    let mut buf = vec![0u8; buffer.max(1)];
    // Bytes held, and the file's byte of `buf[0]`.
    let mut held = 0;
    let mut offset = base;
    let mut end = false;
    // A byte order mark first in the file is no part of its first line.
    let mut bom = base == 0;
    while !(end && held == 0) {
        if !end {
            if held == buf.len() {
                // A line longer than the buffer.
                buf.resize(2 * buf.len(), 0);
            }
            match source.read(&mut buf[held..]) {
                Ok(0) => end = true,
                Ok(n) => held += n,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(Some((None, format!("cannot read: {e}")))),
            }
        }
        let mut at = 0;
        if bom {
            if held < BOM.len() && !end {
                continue;
            }
            bom = false;
            if buf[..held].starts_with(BOM) {
                at = BOM.len();
            }
        }
        loop {
            // The lines before the first quote, carriage return or invalid UTF-8, all at
            // once: one scan of each kind over many lines.
            let rest = &buf[at..held];
            let special = memchr::memchr2(b'"', b'\r', rest).unwrap_or(rest.len());
            let valid = match std::str::from_utf8(&rest[..special]) {
                Ok(text) => text,
                Err(e) => std::str::from_utf8(&rest[..e.valid_up_to()]).unwrap_or_default(),
            };
            // Up to the last line end: a character boundary.
            let clean = memchr::memrchr(b'\n', valid.as_bytes()).map_or(0, |n| n + 1);
            let text = &valid[..clean];
            // Commas and line ends in one pass: the fields of each line.
            let t0 = batch.text.len();
            batch.text.push_str(text);
            let (mut line, mut field) = (0, 0);
            let mut first = batch.fields.len();
            for n in memchr::memchr2_iter(b',', b'\n', text.as_bytes()) {
                batch.fields.push((t0 + field, t0 + n));
                field = n + 1;
                if text.as_bytes()[n] == b'\n' {
                    let record = &text[line..n];
                    if record.is_empty() || record.starts_with('#') {
                        batch.fields.truncate(first);
                    } else {
                        let start = offset + (at + line) as u64;
                        batch.records.push((start, batch.fields.len()));
                    }
                    first = batch.fields.len();
                    line = n + 1;
                }
            }
            at += clean;
            // Then one line as it comes.
            let rest = &buf[at..held];
            let (line, next) = match memchr::memchr(b'\n', rest) {
                Some(n) => (&rest[..n], at + n + 1),
                None if end && !rest.is_empty() => (rest, held),
                None => break,
            };
            if line.first() == Some(&b'#') {
                at = next;
                continue;
            }
            let line = line.strip_suffix(b"\r").unwrap_or(line);
            let plain = memchr::memchr2(b'"', b'\r', line).is_none();
            match std::str::from_utf8(line) {
                Ok(text) if plain => {
                    if !text.is_empty() {
                        batch.line(text, offset + at as u64);
                    }
                }
                _ => {
                    // A line end after the last line: a comment there is one without it
                    // too (the CSV reader would take it for a record).
                    let tail = std::io::Cursor::new(&buf[at..held])
                        .chain(source)
                        .chain(&b"\n"[..]);
                    return scan_quoted(tail, offset + at as u64, batch, sink);
                }
            }
            at = next;
        }
        hand_on(batch, sink)?;
        buf.copy_within(at..held, 0);
        held -= at;
        offset += at as u64;
    }
    Ok(())
}

/// The records from byte `base` on, by the CSV reader, into `batch` (handed on when it is
/// full).
fn scan_quoted(
    source: impl Read,
    base: u64,
    batch: &mut Batch,
    sink: &mut dyn FnMut(Batch) -> Option<Batch>,
) -> Result<(), Stop> {
    let mut reader = ::csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .flexible(true)
        .has_headers(false)
        .from_reader(source);
    let mut record = ::csv::StringRecord::new();
    loop {
        match reader.read_record(&mut record) {
            Ok(false) => return Ok(()),
            Ok(true) => {}
            Err(e) => {
                let at = e.position().map(|p| base + p.byte());
                return Err(Some((at, malformed(&e))));
            }
        }
        let start = base + record.position().map_or(0, |p| p.byte());
        for field in &record {
            let from = batch.text.len();
            batch.text.push_str(field);
            batch.fields.push((from, batch.text.len()));
        }
        batch.records.push((start, batch.fields.len()));
        if batch.text.len() >= BATCH_TEXT || batch.fields.len() >= BATCH_FIELDS {
            hand_on(batch, sink)?;
        }
    }
}

/// The records after a source's header, checked and passed on.
struct Rows<'a> {
    path: &'a Path,
    header: &'a [String],
    indices: &'a [usize],
    each: &'a mut dyn FnMut(&[&str]) -> Result<(), String>,
    locate: &'a dyn Fn(u64) -> Option<u64>,
    /// The buffer's first length, bytes.
    buffer: usize,
    /// Records passed on.
    count: u64,
}

impl Rows<'_> {
    /// Reads the records of `source`, which starts at byte `base` of the file; scanned on a
    /// thread of its own (`threaded`) while the records are checked and passed on here, the
    /// batches in order, so that the first problem in the file is the one found.
    fn read(
        &mut self,
        source: impl Read + Send,
        base: u64,
        threaded: bool,
    ) -> Result<(), DataError> {
        let buffer = self.buffer;
        let mut failed = None;
        let end = if threaded {
            std::thread::scope(|scope| {
                // Eight batches ahead (with the two in hand, about 8 MB of a EuRoC file's text
                // and field bounds): with the consumer sharing its core with other threads, a
                // shallower queue leaves the scanner waiting.
                let (send, receive) = std::sync::mpsc::sync_channel::<Batch>(8);
                let (back, spent) = std::sync::mpsc::channel::<Batch>();
                let scanner = scope.spawn(move || {
                    scan(source, base, buffer, &mut |batch| {
                        send.send(batch).ok()?;
                        Some(spent.try_recv().unwrap_or_default())
                    })
                });
                for batch in receive.iter() {
                    if let Err(e) = self.records(&batch) {
                        // The scanner stops at its next batch, the channel closed.
                        failed = Some(e);
                        break;
                    }
                    let _ = back.send(batch);
                }
                drop(receive);
                scanner
                    .join()
                    .unwrap_or_else(|_| Err((None, "the scanner stopped".into())))
            })
        } else {
            scan(
                source,
                base,
                buffer,
                &mut |batch| match self.records(&batch) {
                    Ok(()) => Some(batch),
                    Err(e) => {
                        failed = Some(e);
                        None
                    }
                },
            )
        };
        if let Some(e) = failed {
            return Err(e);
        }
        end.map_err(|(at, problem)| error(self.path, at.and_then(self.locate), problem))
    }

    /// The records of `batch`, in order.
    fn records(&mut self, batch: &Batch) -> Result<(), DataError> {
        let mut from = 0;
        for &(start, to) in &batch.records {
            let fields = &batch.fields[from..to];
            from = to;
            self.take(
                fields.len(),
                |i| fields.get(i).map(|&(a, b)| &batch.text[a..b]),
                start,
            )?;
        }
        Ok(())
    }

    /// Checks a record of `fields` fields (`field(i)` the `i`-th, untrimmed) starting at byte
    /// `start`, and passes its selected cells, trimmed, on.
    fn take<'r>(
        &mut self,
        fields: usize,
        field: impl Fn(usize) -> Option<&'r str>,
        start: u64,
    ) -> Result<(), DataError> {
        let line = || (self.locate)(start);
        if fields != self.header.len() {
            return Err(error(
                self.path,
                line(),
                format!(
                    "{fields} fields, the header has {}: a shifted row would read the wrong \
                     columns",
                    self.header.len()
                ),
            ));
        }
        // Up to 16 selected cells on the stack, more in a vector.
        let mut small = [""; 16];
        let mut large = Vec::new();
        let cells: &mut [&str] = if self.indices.len() <= small.len() {
            &mut small[..self.indices.len()]
        } else {
            large.resize(self.indices.len(), "");
            &mut large
        };
        for (cell, &i) in cells.iter_mut().zip(self.indices) {
            match field(i) {
                Some(c) => *cell = trimmed(c),
                None => {
                    let name = self.header.get(i).map_or(String::new(), |h| escaped(h));
                    return Err(error(
                        self.path,
                        line(),
                        format!("column '{name}' missing in this row"),
                    ));
                }
            }
        }
        (self.each)(cells).map_err(|problem| error(self.path, line(), problem))?;
        self.count += 1;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The selected cells of every record, or the error's line and message: the CSV reader
    /// alone, record by record, as every row was read before plain lines were split apart
    /// (with a line end after the last line, so that a comment there is one).
    fn by_the_csv_reader(
        bytes: &[u8],
        column: usize,
    ) -> Result<Vec<String>, (Option<u64>, String)> {
        let fail = |line, problem: String| Err((line, problem));
        let mut reader = ::csv::ReaderBuilder::new()
            .comment(Some(b'#'))
            .flexible(true)
            .from_reader(bytes.chain(&b"\n"[..]));
        let header = match reader.headers() {
            Ok(h) => h.len(),
            Err(e) => return fail(None, format!("cannot read the header: {e}")),
        };
        let mut out = Vec::new();
        let mut record = ::csv::StringRecord::new();
        loop {
            match reader.read_record(&mut record) {
                Ok(false) => return Ok(out),
                Ok(true) => {}
                Err(e) => {
                    let line = e.position().and_then(|p| line_at(bytes, p.byte()));
                    return fail(line, malformed(&e));
                }
            }
            let line = record.position().and_then(|p| line_at(bytes, p.byte()));
            if record.len() != header {
                return fail(line, format!("{} fields", record.len()));
            }
            out.push(record[column].trim().to_string());
        }
    }

    /// The same by [`read_source_in`], with a buffer of `buffer` bytes, scanned on a thread
    /// of its own (`threaded`) or not.
    fn by_the_reader(
        bytes: &[u8],
        column: usize,
        buffer: usize,
        threaded: bool,
    ) -> Result<Vec<String>, (Option<u64>, String)> {
        let mut out = Vec::new();
        let locate = |byte| line_at(bytes, byte);
        let read = read_source_in(
            Path::new("t.csv"),
            (Source::Held(bytes), None),
            &mut |h| {
                if h.len() > column {
                    Ok(vec![column])
                } else {
                    Err("short header".into())
                }
            },
            &mut |cells| {
                out.push(cells[0].to_string());
                Ok(())
            },
            &locate,
            (buffer, threaded),
        );
        match read {
            Ok(()) => Ok(out),
            Err(e) => {
                // The shifted-row message, cut to its count, as the reference words it.
                let problem = match e.problem.split_once(" fields, the header has") {
                    Some((n, _)) => format!("{n} fields"),
                    None => e.problem,
                };
                Err((e.line, problem))
            }
        }
    }

    /// Plain lines split here and the CSV reader agree on every record and every error line:
    /// random texts of CSV's awkward bytes (quotes, carriage returns, comments, blank lines,
    /// spaces, non-ASCII and invalid UTF-8), 20,000 of them (`IMU_AR_CSV_CASES` for more).
    #[test]
    fn plain_lines_are_the_csv_readers_records() {
        const BYTES: &[u8] = b"0123456789.,,,,\n\n\n\r\"\"# \t\x0b-e\xc3\xa9\xc2\xa0\xff";
        let cases: u64 = std::env::var("IMU_AR_CSV_CASES")
            .ok()
            .and_then(|n| n.parse().ok())
            .unwrap_or(20_000);
        let mut next = crate::xorshift(0x9e37_79b9_7f4a_7c15);
        let mut agreed = [0u64; 2];
        for case in 0..cases {
            let mut text = b"a,b,c\n".to_vec();
            // Rows of three cells mostly, some lines of awkward bytes among them.
            for _ in 0..next() % 12 {
                match next() % 8 {
                    0 => {
                        for _ in 0..next() % 12 {
                            text.push(BYTES[(next() >> 8) as usize % BYTES.len()]);
                        }
                    }
                    1 => text.extend_from_slice(b"# a comment, \"quoted\"\n"),
                    2 => text.extend_from_slice(b"\r\n"),
                    3 => text.extend_from_slice(b" 1.5 ,\"2\", 3\r\n"),
                    4 => text.extend_from_slice(b"\x0b1\x0b,\xc2\xa02,\t3\xc2\xa0\n"),
                    _ => {
                        let r = next();
                        text.extend_from_slice(
                            format!("{},{} ,{}", r % 1000, r % 7, r % 3).as_bytes(),
                        );
                        text.extend_from_slice(if r.is_multiple_of(5) { b"\r\n" } else { b"\n" });
                    }
                }
            }
            if next().is_multiple_of(4) {
                text.pop();
            }
            let column = (next() % 3) as usize;
            let want = by_the_csv_reader(&text, column);
            // Buffers of a few bytes too: lines split over refills, and longer than a buffer.
            let buffer = [1 << 20, 1, 2, 3, 7, 16, 64][(next() % 7) as usize];
            let got = by_the_reader(&text, column, buffer, case % 2 == 1);
            // No rows is the reader's own error; the reference gives an empty list.
            let got = match got {
                Err((None, p)) if p == "no data rows" => Ok(Vec::new()),
                other => other,
            };
            assert_eq!(
                got,
                want,
                "case {case}: {:?}",
                String::from_utf8_lossy(&text)
            );
            agreed[usize::from(want.is_ok())] += 1;
        }
        // Both outcomes were tried, many times.
        assert!(agreed.iter().all(|&n| n > cases / 20), "{agreed:?}");
    }

    /// Scanned on a thread of its own, in many batches: a row the consumer refuses is the
    /// error (at its line), not a line after it that the scanner refused (not UTF-8) when it
    /// reached it first, and nothing after the refused row is passed on; a line the scanner
    /// refuses before it is the error.
    #[test]
    fn the_first_problem_in_the_file_is_the_one_found_when_scanning_ahead() {
        let mut text = b"t,x\n".to_vec();
        for i in 0..50_000 {
            text.extend_from_slice(format!("{i},{}\n", i % 7).as_bytes());
        }
        let malformed = |text: &mut Vec<u8>| text.extend_from_slice(b"1,\"\xff\"\n");
        let read = |text: &[u8], refuse: usize| {
            let mut seen = 0;
            let got = read_source_in(
                Path::new("t.csv"),
                (Source::Held(text), None),
                &mut |_| Ok(vec![0, 1]),
                &mut |cells| {
                    seen += 1;
                    match cells[0].parse::<usize>() {
                        Ok(i) if i == refuse => Err(format!("refused {i}")),
                        _ => Ok(()),
                    }
                },
                &|byte| line_at(text, byte),
                (4096, true),
            );
            (got.map_err(|e| (e.line, e.problem)), seen)
        };
        let mut after = text.clone();
        malformed(&mut after);
        assert_eq!(
            read(&after, 30_000),
            (Err((Some(30_002), "refused 30000".into())), 30_001)
        );
        let mut before = b"t,x\n0,1\n".to_vec();
        malformed(&mut before);
        before.extend_from_slice(&text[4..]);
        let (got, seen) = read(&before, 30_000);
        assert_eq!((got.map_err(|(line, _)| line), seen), (Err(Some(3)), 1));
        // Read to the end, with the rows counted, when nothing is refused.
        assert_eq!(read(&text, usize::MAX), (Ok(()), 50_000));
    }

    /// Past a quote the CSV reader's records are batched by their text and by their fields: a
    /// file of empty cells (no text) was scanned whole into one batch, 24 times the file's size
    /// in memory, before its first row was checked.
    #[test]
    fn a_batch_of_quoted_records_is_bounded_by_its_fields_too() {
        let mut text = b"t,x\n\"0\",\n".to_vec();
        for _ in 0..200_000 {
            text.extend_from_slice(b",\n");
        }
        let (mut batches, mut largest, mut records) = (0, 0, 0);
        let end = scan(&text[4..], 4, 1 << 20, &mut |batch| {
            batches += 1;
            largest = largest.max(batch.fields.len());
            records += batch.records.len();
            Some(batch)
        });
        assert_eq!(end, Ok(()));
        assert_eq!(records, 200_001);
        assert!(largest <= BATCH_FIELDS + 2, "{largest} fields in one batch");
        assert!(batches >= 6, "{batches} batches");
    }

    /// A header row whose first cell is a quoted `"#..."` is a header row, not a comment (the
    /// CSV reader's comments start with the byte `#`); a `#` line before numbers is the header.
    #[test]
    fn only_a_line_that_starts_with_a_hash_is_a_comment_header() {
        let label = Path::new("t.csv");
        let quoted = parse_column(label, b"\"#t [ns]\",x\n1,2\n3,4\n", "x");
        assert_eq!(quoted, Ok(vec![2.0, 4.0]));
        let time = parse_column(label, b"\"#t [ns]\",x\n1,2\n3,4\n", "#t");
        assert_eq!(time, Ok(vec![1.0, 3.0]));
        let comment = parse_column(label, b"# written by a logger\n#t [ns],x\n1,2\n3,4\n", "x");
        assert_eq!(comment, Ok(vec![2.0, 4.0]));
    }

    /// A EuRoC comment header after a byte order mark, after a comment holding a quote, and a
    /// comment as the last line without a line end: read as the header, and ignored.
    #[test]
    fn comments_hold_whatever_they_hold() {
        let label = Path::new("t.csv");
        let bom = parse_column(label, b"\xef\xbb\xbf#t [ns],x\n1,2\n3,4\n", "x");
        assert_eq!(bom, Ok(vec![2.0, 4.0]));
        let quote = b"# by x,\"hello world\n#t [ns],x\n1,2\n3,4\n";
        assert_eq!(parse_column(label, quote, "x"), Ok(vec![2.0, 4.0]));
        let last = parse_column(label, b"t,x\n1,2\n3,4\n# end of log", "x");
        assert_eq!(last, Ok(vec![2.0, 4.0]));
        let last_quoted = parse_column(label, b"t,x\n1,\"2\"\n3,4\n# end, \"of log", "x");
        assert_eq!(last_quoted, Ok(vec![2.0, 4.0]));
        // The header, then a line of prose: the comment as wide as the data is the header.
        let prose = b"#t [ns],x\n# recorded by logger v2\n1,2\n3,4\n";
        assert_eq!(parse_column(label, prose, "x"), Ok(vec![2.0, 4.0]));
    }

    /// The fast parser reads every text as the standard library does: the same bits, or both
    /// refuse. Random texts of a number's characters, a million of them.
    #[test]
    fn numbers_read_as_the_standard_library_reads_them() {
        const CHARS: &[u8] = b"0123456789012345678901234567890123456789..--++eEeE_ xinfINFnaNty";
        let mut next = crate::xorshift(0x1234_5678_9abc_def1);
        let mut text = String::new();
        for case in 0..1_000_000 {
            text.clear();
            for _ in 0..next() % 26 {
                text.push(char::from(CHARS[(next() % CHARS.len() as u64) as usize]));
            }
            let want = text.parse::<f64>().ok();
            let got = number(&text);
            assert_eq!(
                got.map(f64::to_bits),
                want.map(f64::to_bits),
                "case {case}: {text:?}"
            );
        }
        // And the shortest, longest and nearest-to-halfway decimals.
        for text in [
            "4.9406564584124654e-324",
            "2.2250738585072011e-308",
            "1.7976931348623157e308",
            "9007199254740993",
            "0.015574726745215603",
            "-0.06183358072315851",
            "1e400",
            "-1e-400",
            "2.47032822920623272088e-324",
        ] {
            assert_eq!(
                number(text).map(f64::to_bits),
                text.parse::<f64>().ok().map(f64::to_bits),
                "{text}"
            );
        }
    }
}
