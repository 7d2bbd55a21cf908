//! ROS 2 recordings: a rosbag2 folder (what `ros2 bag record` writes: `metadata.yaml` and its
//! storage files, <https://github.com/ros2/rosbag2>), and a bare SQLite storage file (`.db3`).
//!
//! A folder is read through its `metadata.yaml`: `storage_identifier` (`mcap` or `sqlite3`)
//! and `relative_file_paths`, the storage files in recording order, each read in turn by the
//! MCAP reader ([`super::mcap`]) or by [`read_db3`]. A folder compressed file by file
//! (`compression_mode: FILE`) is refused with what to run (`ros2 bag decompress`); one
//! compressed message by message in zstd (`compression_mode: MESSAGE`) is read, each
//! message's data decompressed. Up to metadata version 3 (ROS 2 Dashing and Eloquent) the
//! files' paths start with the folder's name, which is left out. A folder's `metadata.yaml`
//! given for the folder reads the folder.
//!
//! A `.db3` file is the rosbag2 SQLite storage (`rosbag2_storage_default_plugins`, the default
//! of ROS 2 before Iron): a table `topics` (`id`, `name`, `type`, `serialization_format`) and a
//! table `messages` (`topic_id`, `timestamp`, `data`), each message's `data` the CDR
//! serialization of the message, decoded as in an MCAP file. Messages are read in the order of
//! their receive `timestamp` (then of their row), which is the order `ros2 bag play` plays.
//! The database is opened read-only and immutable: nothing is written, in it or beside it.

use std::path::{Path, PathBuf};

use rusqlite::{Connection, OpenFlags};

use crate::csv::DataError;
use crate::frame::{Frame, Select, Skipped, Tally, absent_topic, data_error};
use crate::mcap::{self, IMU_SCHEMA};

/// The name of a rosbag2 folder's metadata file.
pub const METADATA: &str = "metadata.yaml";

/// What a rosbag2 folder's `metadata.yaml` says of its storage.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Metadata {
    /// `storage_identifier`: `mcap` or `sqlite3`.
    pub storage: String,
    /// `relative_file_paths`: the storage files, in order.
    pub files: Vec<String>,
    /// `compression_mode` (`FILE`, `MESSAGE` or empty).
    pub compression_mode: String,
    /// `compression_format` (`zstd` or empty).
    pub compression_format: String,
    /// `version`: the metadata's layout (up to 3, the storage files' paths start with the
    /// folder's name).
    pub version: Option<u64>,
    /// `topics_with_message_count`: each topic's name and the messages recorded on it.
    pub topic_counts: Vec<(String, u64)>,
}

impl Metadata {
    /// Parses the keys read here out of a `metadata.yaml` (block style, as rosbag2 writes it:
    /// `key: value` lines and `- item` lists; values plain or quoted).
    pub fn parse(text: &str) -> Result<Self, String> {
        let mut meta = Metadata {
            storage: String::new(),
            files: Vec::new(),
            compression_mode: String::new(),
            compression_format: String::new(),
            version: None,
            topic_counts: Vec::new(),
        };
        let mut in_files = false;
        let mut seen_files = false;
        // Within `topics_with_message_count`: its key's indent, its items' indent, and the
        // item being read (its topic's name and count, each the first given).
        let mut topics: Option<(usize, Option<usize>)> = None;
        let mut entry: (Option<String>, Option<u64>) = (None, None);
        let mut base: Option<usize> = None;
        for line in text.lines() {
            let trimmed = line.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            let indent = line.len() - line.trim_start().len();
            if let Some((key, item)) = topics {
                let inside = indent > key || indent == key && trimmed.starts_with("- ");
                let begins = trimmed.starts_with("- ") && item.is_none_or(|i| i == indent);
                if (!inside || begins)
                    && let (Some(name), Some(count)) = std::mem::take(&mut entry)
                {
                    meta.topic_counts.push((name, count));
                }
                if inside {
                    topics = Some((key, item.or(begins.then_some(indent))));
                    let pair = trimmed.strip_prefix("- ").unwrap_or(trimmed);
                    if let Some((k, v)) = pair.split_once(':') {
                        let v = unquoted(uncommented(v));
                        match unquoted(k.trim()).as_ref() {
                            "name" if entry.0.is_none() => entry.0 = Some(v.to_string()),
                            "message_count" if entry.1.is_none() => {
                                entry.1 = Some(v.parse().map_err(|_| {
                                    format!(
                                        "its message_count '{}' is not a count",
                                        crate::error::escaped(&v)
                                    )
                                })?);
                            }
                            _ => {}
                        }
                    }
                    continue;
                }
                topics = None;
            }
            if in_files && let Some(item) = trimmed.strip_prefix("- ") {
                meta.files.push(unquoted(uncommented(item)).to_string());
                continue;
            }
            in_files = false;
            // (A second document is not the bag's.)
            if indent == 0 && (trimmed == "---" || trimmed == "...") && base.is_some() {
                break;
            }
            let Some((key, value)) = trimmed.split_once(':') else {
                continue;
            };
            let key = unquoted(key.trim());
            // The keys of the bag's information: those at the first key's indent under it
            // (not those of `custom_data` or any other map within).
            if key == "rosbag2_bagfile_information" && base.is_none() {
                continue;
            }
            if *base.get_or_insert(indent) != indent {
                continue;
            }
            let value = unquoted(uncommented(value));
            let value = value.as_ref();
            match key.as_ref() {
                "storage_identifier" => meta.storage = value.to_string(),
                "compression_mode" => meta.compression_mode = value.to_string(),
                "compression_format" => meta.compression_format = value.to_string(),
                "version" if meta.version.is_none() => meta.version = value.parse().ok(),
                "topics_with_message_count" if value.is_empty() => topics = Some((indent, None)),
                "relative_file_paths" => {
                    seen_files = true;
                    if let Some(list) = value.strip_prefix('[').and_then(|v| v.strip_suffix(']')) {
                        meta.files.extend(
                            list.split(',')
                                .map(|f| unquoted(f.trim()).to_string())
                                .filter(|f| !f.is_empty()),
                        );
                    } else {
                        in_files = value.is_empty();
                    }
                }
                _ => {}
            }
        }
        if let (Some(name), Some(count)) = entry {
            meta.topic_counts.push((name, count));
        }
        if meta.storage.is_empty() {
            return Err("it has no storage_identifier".into());
        }
        if !seen_files {
            return Err("it has no relative_file_paths".into());
        }
        Ok(meta)
    }
}

/// `v` trimmed, without a comment after it (from a `#` after a space, outside quotes: a
/// file named `- b_0.db3  # first file`).
fn uncommented(v: &str) -> &str {
    let v = v.trim();
    let end = closing(v).map_or(0, |i| i + 1);
    let cut = v[end..]
        .char_indices()
        .find(|&(i, c)| c == '#' && (end + i == 0 || v[..end + i].ends_with([' ', '\t'])))
        .map_or(v.len(), |(i, _)| end + i);
    v[..cut].trim_end()
}

/// Where the quote that opens `v` closes (a single-quoted scalar's `''` is a quote within
/// it, a double-quoted one's `\"`); none where `v` opens with none, or it does not close.
fn closing(v: &str) -> Option<usize> {
    let q = v.chars().next().filter(|c| matches!(c, '\'' | '"'))?;
    let mut chars = v.char_indices().skip(1).peekable();
    while let Some((i, c)) = chars.next() {
        match c {
            '\\' if q == '"' => {
                chars.next();
            }
            '\'' if q == '\'' && chars.peek().is_some_and(|&(_, n)| n == '\'') => {
                chars.next();
            }
            c if c == q => return Some(i),
            _ => {}
        }
    }
    None
}

/// `v` without the quotes around it, if it has them, its escaped quotes and backslashes
/// read (`''` in single quotes, `\"` and `\\` in double).
fn unquoted(v: &str) -> std::borrow::Cow<'_, str> {
    match (v.chars().next(), closing(v)) {
        (Some('\''), Some(end)) if end + 1 == v.len() => v[1..end].replace("''", "'").into(),
        (Some('"'), Some(end)) if end + 1 == v.len() => {
            v[1..end].replace("\\\"", "\"").replace("\\\\", "\\").into()
        }
        _ => v.into(),
    }
}

/// The storage files of the rosbag2 folder `dir`, in order, and whether they are MCAP
/// (else SQLite). An error when the metadata cannot be read, names a storage this tool does
/// not read, is compressed file by file, or names a file that is not in the folder.
pub fn storage_files(dir: &Path) -> Result<(Vec<PathBuf>, bool), DataError> {
    Ok(storage(dir)?.files_and_kind())
}

/// A rosbag2 folder's storage: its files in order, whether they are MCAP, and whether each
/// message is compressed by zstd (`compression_mode: MESSAGE`).
struct Storage {
    files: Vec<PathBuf>,
    mcap: bool,
    zstd_messages: bool,
    /// The messages the metadata counts on each topic.
    topic_counts: Vec<(String, u64)>,
}

impl Storage {
    fn files_and_kind(self) -> (Vec<PathBuf>, bool) {
        (self.files, self.mcap)
    }
}

/// The folder `path` names: itself, or the folder of its `metadata.yaml`.
pub fn folder(path: &Path) -> &Path {
    match path.parent() {
        Some(parent) if path.file_name() == Some(METADATA.as_ref()) && path.is_file() => parent,
        _ => path,
    }
}

/// [`storage_files`], and whether the messages are compressed one by one.
fn storage(dir: &Path) -> Result<Storage, DataError> {
    let dir = folder(dir);
    let path = dir.join(METADATA);
    let fail = |p: String| data_error(&path, p);
    let text = std::fs::read_to_string(&path).map_err(|e| fail(format!("cannot read: {e}")))?;
    let meta = Metadata::parse(&text).map_err(|e| fail(format!("not rosbag2 metadata: {e}")))?;
    let mcap = match meta.storage.as_str() {
        "mcap" => true,
        "sqlite3" => false,
        other => {
            return Err(fail(format!(
                "storage '{}': the storages read are mcap and sqlite3",
                crate::error::escaped(other)
            )));
        }
    };
    if meta.compression_mode.eq_ignore_ascii_case("file") {
        return Err(fail(format!(
            "the bag's files are compressed whole ({}); `ros2 bag decompress` writes a folder \
             that can be read",
            if meta.compression_format.is_empty() {
                "compression_mode FILE"
            } else {
                meta.compression_format.as_str()
            }
        )));
    }
    // Compressed message by message: each message's data a zstd frame.
    let zstd_messages = meta.compression_mode.eq_ignore_ascii_case("message");
    if zstd_messages && !meta.compression_format.eq_ignore_ascii_case("zstd") {
        return Err(fail(format!(
            "the bag's messages are compressed one by one in '{}', which is not read (zstd is)",
            crate::error::escaped(&meta.compression_format)
        )));
    }
    if meta.files.is_empty() {
        return Err(fail(
            "it names no storage file (relative_file_paths is empty)".into(),
        ));
    }
    if let Some(twice) = meta
        .files
        .iter()
        .enumerate()
        .find_map(|(i, f)| meta.files[..i].contains(f).then_some(f))
    {
        return Err(fail(format!(
            "relative_file_paths lists '{}' twice",
            crate::error::escaped(twice)
        )));
    }
    // Up to version 3, each path starts with the folder's name (as it was when recorded;
    // rosbag2 reads it from the folder's parent): the folder is where the rest lies.
    let prefixed = meta.version.is_some_and(|v| v <= 3);
    let mut files = Vec::with_capacity(meta.files.len());
    for f in &meta.files {
        let rel = Path::new(f);
        if rel.is_absolute()
            || rel
                .components()
                .any(|c| c == std::path::Component::ParentDir)
        {
            return Err(fail(format!(
                "storage file '{}' is not inside the folder",
                crate::error::escaped(f)
            )));
        }
        let mut parts = rel.components();
        let file = match (prefixed, parts.next(), parts.as_path()) {
            (true, Some(_), rest) if !rest.as_os_str().is_empty() => dir.join(rest),
            _ => dir.join(rel),
        };
        let problem = match std::fs::metadata(&file) {
            Ok(m) if m.is_file() => None,
            Ok(_) => Some("is not a regular file"),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                Some("is missing from the folder")
            }
            Err(_) => Some("cannot be read"),
        };
        if let Some(p) = problem {
            return Err(fail(format!(
                "storage file '{}' {p}",
                crate::error::escaped(f)
            )));
        }
        files.push(file);
    }
    Ok(Storage {
        files,
        mcap,
        zstd_messages,
        topic_counts: meta.topic_counts,
    })
}

/// Calls `each` with every finite `sensor_msgs/msg/Imu` message on `select`'s topic (and
/// frame_id) of the rosbag2 folder `dir`, file after file, and returns what was skipped.
/// Errors as [`super::mcap::read_selected`] and [`read_db3`], and [`storage_files`]'; and
/// where a file's first header stamp is before the first of the file listed before it (the
/// metadata lists them out of order), or the files hold fewer of the topic's messages than
/// the metadata counts on it (a storage file left off its list, or damaged), naming the
/// storage files in the folder it does not list.
pub fn read_folder(
    dir: &Path,
    select: &Select,
    each: &mut dyn FnMut(Frame),
) -> Result<Skipped, DataError> {
    let Storage {
        files,
        mcap: is_mcap,
        zstd_messages,
        topic_counts,
    } = storage(dir)?;
    let meta = folder(dir).join(METADATA);
    let name =
        |f: &Path| crate::error::escaped(&f.file_name().unwrap_or_default().to_string_lossy());
    let mut skipped = Skipped::default();
    let mut found = false;
    let mut last_err = None;
    // The messages on the topic, and the first header stamp of the file before (and its
    // name).
    let mut held = 0u64;
    let mut before: Option<(i64, String)> = None;
    for file in &files {
        let mut first: Option<i64> = None;
        let mut misordered: Option<i64> = None;
        let mut take = |frame: Frame| {
            held += 1;
            if misordered.is_some() {
                return;
            }
            if frame.stamp_ns != 0 && first.is_none() {
                first = Some(frame.stamp_ns);
                if let Some((t, _)) = &before
                    && frame.stamp_ns < *t
                {
                    misordered = Some(frame.stamp_ns);
                    return;
                }
            }
            each(frame);
        };
        let read = if is_mcap {
            mcap::read_compressed(file, select, &mut take, zstd_messages)
        } else {
            read_db3_compressed(file, select, &mut take, zstd_messages)
        };
        if let (Some(t), Some((earlier, listed))) = (misordered, &before) {
            return Err(data_error(
                &meta,
                format!(
                    "its storage file '{}' begins at {t} ns, before '{listed}', listed before \
                     it, begins ({earlier} ns): relative_file_paths lists the files out of \
                     order (rosbag2 reads them in its order)",
                    name(file)
                ),
            ));
        }
        match read {
            Ok(s) => {
                found = true;
                held += s.undecodable + s.other_frame_id;
                if !select.non_finite {
                    held += s.non_finite;
                }
                skipped.undecodable += s.undecodable;
                skipped.non_finite += s.non_finite;
                skipped.other_frame_id += s.other_frame_id;
                skipped.gyro_not_provided += s.gyro_not_provided;
                skipped.accel_not_provided += s.accel_not_provided;
            }
            // A split bag's file may hold none of the topic's messages; the others must.
            Err(e) if files.len() > 1 && e.problem.starts_with("no ") => last_err = Some(e),
            Err(e) => return Err(e),
        }
        if let Some(t) = first {
            before = Some((t, name(file)));
        }
    }
    if let (false, Some(e)) = (found, last_err) {
        return Err(e);
    }
    let counted = topic_counts
        .iter()
        .filter(|(t, _)| t == select.topic)
        .map(|&(_, n)| n)
        .max()
        .unwrap_or(0);
    if held < counted {
        let listed: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
        let mut others: Vec<String> = std::fs::read_dir(folder(dir))
            .into_iter()
            .flatten()
            .flatten()
            .map(|e| e.path())
            .filter(|p| {
                !listed.contains(&p.as_path())
                    && p.extension().is_some_and(|x| x == "db3" || x == "mcap")
            })
            .map(|p| format!("'{}'", name(&p)))
            .collect();
        others.sort();
        return Err(data_error(
            &meta,
            format!(
                "it counts {counted} messages on '{}' and its storage files hold {held}: {}",
                crate::error::escaped(select.topic),
                if others.is_empty() {
                    "a storage file is damaged or cut short".to_string()
                } else {
                    format!(
                        "the folder holds {}, which relative_file_paths does not list",
                        others.join(", ")
                    )
                }
            ),
        ));
    }
    Ok(skipped)
}

/// The first bytes of an SQLite 3 database.
pub const SQLITE_MAGIC: &[u8] = b"SQLite format 3\0";

/// Calls `each` with every finite `sensor_msgs/msg/Imu` message on `select`'s topic (and
/// frame_id) of the rosbag2 SQLite file `path`, in the order of their receive timestamps, and
/// returns what was skipped. Errors as [`super::mcap::read_selected`]'s: not a rosbag2
/// database, no such topic, another type or serialization, no finite message.
pub fn read_db3(
    path: &Path,
    select: &Select,
    each: &mut dyn FnMut(Frame),
) -> Result<Skipped, DataError> {
    read_db3_compressed(path, select, each, false)
}

/// The SQLite database `path` opened read-only. Opened immutable (a URI with `immutable=1`):
/// SQLite takes no lock and writes nothing, neither the database nor a `-shm` or `-wal` file
/// beside it, so a database in WAL mode (rosbag2's `resilient` storage preset) is read where
/// its reader may not write and leaves its folder as it was. A database with a write-ahead log
/// beside it that holds changes (`<file>-wal`, not empty: a recording that was not closed) is
/// opened read-only and not immutable, for SQLite to read them from the log.
fn open(path: &Path) -> rusqlite::Result<Connection> {
    let flags = OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX;
    let mut wal = path.as_os_str().to_owned();
    wal.push("-wal");
    if std::fs::metadata(&wal).is_ok_and(|m| m.len() > 0) {
        return Connection::open_with_flags(path, flags);
    }
    Connection::open_with_flags(immutable_uri(path), flags | OpenFlags::SQLITE_OPEN_URI)
}

/// The SQLite URI (<https://www.sqlite.org/uri.html>) of the file `path`, immutable: `file:`,
/// the path with every byte but an ASCII letter, digit, `/`, `-`, `.`, `_` or `~`
/// percent-escaped (`?`, `#`, `%` and the rest are the file name's), then `?immutable=1`. An
/// absolute path is given an empty authority (`file:///...`), so that one starting with `//`
/// is not read as a host.
fn immutable_uri(path: &Path) -> String {
    use std::fmt::Write as _;
    let bytes = path.as_os_str().as_encoded_bytes();
    let mut uri = String::from("file:");
    if bytes.starts_with(b"/") {
        uri.push_str("//");
    }
    for &b in bytes {
        if b.is_ascii_alphanumeric() || b"/-._~".contains(&b) {
            uri.push(char::from(b));
        } else {
            let _ = write!(uri, "%{b:02X}");
        }
    }
    uri.push_str("?immutable=1");
    uri
}

/// [`read_db3`], each message's data a zstd frame where `zstd_messages`.
fn read_db3_compressed(
    path: &Path,
    select: &Select,
    each: &mut dyn FnMut(Frame),
    zstd_messages: bool,
) -> Result<Skipped, DataError> {
    let topic = select.topic;
    let fail = |p: String| data_error(path, p);
    let sql = |e: rusqlite::Error| fail(format!("not a readable rosbag2 database: {e}"));
    let db = open(path).map_err(sql)?;
    let mut topics = db
        .prepare("SELECT id, name, type, serialization_format FROM topics")
        .map_err(sql)?;
    let rows = topics
        .query_map([], |r| {
            Ok((
                r.get::<_, i64>(0)?,
                r.get::<_, String>(1)?,
                r.get::<_, String>(2)?,
                r.get::<_, String>(3)?,
            ))
        })
        .map_err(sql)?;
    let (mut ids, mut imu_topics, mut all_topics) = (Vec::new(), Vec::new(), Vec::new());
    // The topic's rows of another type: the type, and the row's id.
    let mut others: Vec<(String, i64)> = Vec::new();
    for row in rows {
        let (id, name, ty, format) = row.map_err(sql)?;
        if name == topic && ty != IMU_SCHEMA {
            others.push((ty, id));
            continue;
        }
        if name == topic {
            if format != "cdr" {
                return Err(fail(format!(
                    "unknown encoding '{}' on topic '{topic}' (supported: cdr)",
                    crate::error::escaped(&format)
                )));
            }
            ids.push(id);
        }
        if ty == IMU_SCHEMA && !imu_topics.contains(&name) {
            imu_topics.push(name.clone());
        }
        if !all_topics.contains(&name) {
            all_topics.push(name);
        }
    }
    if let Some((ty, _)) = others.first() {
        return Err(fail(if ids.is_empty() {
            format!("topic '{topic}' has type {ty}, not {IMU_SCHEMA}")
        } else {
            let list = |ids: &mut dyn Iterator<Item = i64>| {
                ids.map(|id| id.to_string()).collect::<Vec<_>>().join(", ")
            };
            let rows = others
                .iter()
                .map(|(_, id)| id.to_string())
                .collect::<Vec<_>>()
                .join(", ");
            format!(
                "topic '{topic}' carries {IMU_SCHEMA} (topic row {}) and {}: one topic, one \
                 type of message; in a copy of the file, delete the others' messages (sqlite3: \
                 DELETE FROM messages WHERE topic_id IN ({rows})) and read the copy",
                list(&mut ids.iter().copied()),
                others
                    .iter()
                    .map(|(ty, id)| format!("{ty} (topic row {id})"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }));
    }
    if ids.is_empty() {
        return Err(fail(absent_topic(
            IMU_SCHEMA,
            topic,
            &imu_topics,
            &all_topics,
        )));
    }
    // One topic row per publisher's QoS profile: all of them, told apart by their frame_id.
    let list: Vec<String> = ids.iter().map(i64::to_string).collect();
    let untimed: i64 = db
        .query_row(
            &format!(
                "SELECT COUNT(*) FROM messages WHERE topic_id IN ({}) AND \
                 typeof(timestamp) != 'integer'",
                list.join(",")
            ),
            [],
            |r| r.get(0),
        )
        .map_err(sql)?;
    if untimed > 0 {
        return Err(fail(format!(
            "{untimed} messages on '{topic}' have a receive timestamp that is not an integer \
             (nanoseconds): not a rosbag2 database as ROS 2 writes it"
        )));
    }
    let mut messages = db
        .prepare(&format!(
            "SELECT topic_id, data FROM messages WHERE topic_id IN ({}) ORDER BY timestamp, id",
            list.join(",")
        ))
        .map_err(sql)?;
    let mut rows = messages.query([]).map_err(sql)?;
    let mut tally = Tally::new(select, each);
    while let Some(row) = rows.next().map_err(sql)? {
        let source = row.get::<_, i64>(0).map_err(sql)?;
        let data = row.get_ref(1).map_err(sql)?;
        let plain;
        let data = match data.as_blob().ok() {
            Some(b) if zstd_messages => {
                plain = mcap::unzstd_message(b);
                plain.as_deref()
            }
            b => b,
        };
        tally.offer_data(
            u32::try_from(source).unwrap_or(u32::MAX),
            data,
            mcap::decode,
        );
    }
    tally.finish(path, topic, &|id| format!("topic row {id}"))
}
