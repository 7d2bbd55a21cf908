//! Streaming `sensor_msgs/msg/Imu` messages out of a ROS 2 MCAP file
//! (<https://mcap.dev/spec>, ROS 2 profile <https://mcap.dev/spec/registry>), uncompressed,
//! zstd or lz4 chunks, through the sans-I/O reader of the [`mcap`] crate.
//!
//! The file is read front to back in pieces of 256 KiB and one chunk is decompressed at a
//! time (its CRC, when it has one, checked before any of its messages is delivered). Messages
//! are delivered in the order of their log times, as the MCAP readers play them: each chunk's
//! messages on the topic are held and sorted, and those logged before every chunk still to
//! come (the start times of the chunk index in the file's summary) are delivered. Memory is
//! bounded by the largest chunk and the topic's messages of one chunk (some 90 bytes each)
//! when the chunks follow each other in time, as recorders write them; when they do not
//! (chunks written out of order, or whose times overlap), the messages are held until the
//! chunks that come before them in time are read. A file without a chunk index (unchunked, or
//! with no summary) is read in file order: a message logged before the one before it, and
//! stamped before it too, is refused as the file being out of log-time order. A channel is
//! checked when its record is read, which is before any of its messages.
//!
//! A message is decoded by hand from its CDR serialization (OMG CDR, XCDR version 1: OMG DDS-XTypes
//! 1.3 section 7.4.3, <https://www.omg.org/spec/DDS-XTypes/1.3>, as the ROS 2 middleware writes
//! it, <https://design.ros2.org/articles/generated_interfaces_cpp.html> and
//! <https://github.com/eProsima/Fast-CDR>): a 4-byte encapsulation header (CDR_LE `00 01` or
//! CDR_BE `00 00`, then two option bytes), then `sensor_msgs/msg/Imu`
//! (<https://docs.ros2.org/latest/api/sensor_msgs/msg/Imu.html>): builtin_interfaces/Time
//! (int32 sec, uint32 nanosec), string frame_id (uint32 length counting its NUL, then the bytes),
//! then 37 float64 (orientation, its covariance, angular_velocity, its covariance,
//! linear_acceleration, its covariance), the first aligned to 8 bytes counted from the end of
//! the encapsulation header. A channel of ROS 1 messages (schema `sensor_msgs/Imu` in
//! `ros1msg`, message encoding `ros1`: what `mcap convert` writes of a ROS 1 bag) is decoded
//! as a bag's message is.

use crate::frame::open_head;
use std::cmp::Ordering;
use std::collections::binary_heap::PeekMut;
use std::collections::{BinaryHeap, HashMap};
use std::fs::File;
use std::io::{BufReader, ErrorKind, Read, Seek, SeekFrom};
use std::path::Path;

use ::mcap::records::{Record, op};
use ::mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use crate::csv::DataError;
use crate::frame::{
    Decoded, Frame, Select, Skipped, Tally, absent_topic, bytes_at, data_error, imu_axes, stamp_ns,
    u32_at,
};

/// The schema name of the IMU channels.
pub const IMU_SCHEMA: &str = "sensor_msgs/msg/Imu";

/// The one message encoding read.
const CDR: &str = "cdr";
/// The IMU's ROS 1 type, as an MCAP file converted from a ROS 1 bag names its schema.
const ROS1_IMU_SCHEMA: &str = "sensor_msgs/Imu";
/// That schema's encoding.
const ROS1_SCHEMA_ENCODING: &str = "ros1msg";
/// The message encoding of ROS 1 messages (their ROS 1 serialization, as in a bag).
const ROS1: &str = "ros1";

/// The schema encodings of ROS 2 message definitions.
const SCHEMA_ENCODINGS: [&str; 2] = ["ros2msg", "ros2idl"];

/// The schema encodings read, for a refusal: ROS 2's, and ROS 1's with its type name.
const READ_ENCODINGS: &str = "ros2msg, ros2idl, or ros1msg for the ROS 1 type sensor_msgs/Imu";

/// How much of the file is asked for at a time, at least.
const READ_SIZE: usize = 256 * 1024;

/// The longest record (or decompressed chunk) read when the file is shorter: longer ones are
/// corrupt lengths, not allocated.
const MIN_RECORD_LIMIT: u64 = 64 * 1024 * 1024;

/// Calls `each` with every finite `sensor_msgs/msg/Imu` message on `topic` of the MCAP file
/// `path`, in the order of their log times (stable), and returns what was skipped.
///
/// Messages that cannot be decoded, and those with a NaN or an infinite axis, are counted and
/// not delivered; those that mark their gyro or accelerometer as not provided (the first
/// element of its covariance -1) are delivered and counted ([`Skipped::not_provided`]). An error (after the frames already delivered, when the damage is found
/// midway) when the file is not an MCAP file, is truncated or corrupt, has no channel on
/// `topic`, has one with another schema, another schema encoding than ros2msg or ros2idl
/// (ros1msg with message encoding ros1 for the ROS 1 type), or another message encoding than
/// cdr, has no finite message on it, or has no chunk index and its messages out of log-time
/// order (their header stamps too).
pub fn read(path: &Path, topic: &str, each: &mut dyn FnMut(Frame)) -> Result<Skipped, DataError> {
    read_selected(path, &Select::topic(topic), each)
}

/// [`read`] of the messages `select` asks for: on its topic, from the IMU of its header
/// frame_id (the others counted as skipped). An error too when the topic carries more than one
/// IMU (frame_ids) and `select` names none, or when two channels send one frame_id at
/// interleaved times.
pub fn read_selected(
    path: &Path,
    select: &Select,
    each: &mut dyn FnMut(Frame),
) -> Result<Skipped, DataError> {
    read_compressed(path, select, each, false)
}

/// The most bytes one message decompresses to: an IMU message is some 330 bytes and its
/// frame_id.
const MESSAGE_LIMIT: usize = 1 << 20;

/// A message's data compressed as one zstd frame (a rosbag2 folder recorded with
/// `--compression-mode message`), decompressed; `None` when it is no such frame or holds
/// more than [`MESSAGE_LIMIT`] bytes.
pub(crate) fn unzstd_message(data: &[u8]) -> Option<Vec<u8>> {
    zstd::bulk::decompress(data, MESSAGE_LIMIT).ok()
}

/// [`read_selected`], each message's data a zstd frame where `zstd_messages`.
pub(crate) fn read_compressed(
    path: &Path,
    select: &Select,
    each: &mut dyn FnMut(Frame),
    zstd_messages: bool,
) -> Result<Skipped, DataError> {
    let topic = select.topic;
    let fail = |problem: String| data_error(path, problem);
    let (mut file, len, head) = open_head(path, ::mcap::MAGIC.len() as u64)?;
    if head.as_slice() != ::mcap::MAGIC {
        if ::mcap::MAGIC.starts_with(&head) {
            return Err(fail(format!(
                "truncated or corrupt MCAP file: {len} bytes, shorter than the magic"
            )));
        }
        return Err(fail(not_mcap(&head)));
    }
    let limit = usize::try_from(len.max(MIN_RECORD_LIMIT)).unwrap_or(usize::MAX);
    let starts = chunk_starts(&mut file, len);
    let indexed = !starts.is_empty();
    // The earliest start time of the chunks from the k-th on (in file order): the messages
    // logged before it are all read once k chunks are.
    let mut later = starts;
    let mut earliest = u64::MAX;
    for t in later.iter_mut().rev() {
        earliest = earliest.min(*t);
        *t = earliest;
    }
    later.push(u64::MAX);
    file.seek(SeekFrom::Start(::mcap::MAGIC.len() as u64))
        .map_err(|e| fail(format!("cannot read: {e}")))?;
    // Chunks are handed over whole and opened here: the reader trusts the lengths of the
    // records inside an uncompressed chunk.
    let mut reader = LinearReader::new_with_options(
        LinearReaderOptions::default()
            .with_skip_start_magic(true)
            .with_emit_chunks(true)
            .with_record_length_limit(limit),
    );
    let mut state = State {
        channels: Channels::default(),
        counted: None,
        found: 0,
        messages: 0,
        tally: Tally::new(select, each),
        zstd_messages,
        held: BinaryHeap::new(),
        frame_ids: Vec::new(),
        last: Vec::new(),
        indexed,
    };
    // The chunks read so far.
    let mut chunks = 0usize;
    let corrupt = |what: &dyn std::fmt::Display, messages: u64| {
        fail(format!(
            "truncated or corrupt MCAP file: {what} (after {messages} messages)"
        ))
    };
    let refused = |r: Refusal, messages: u64| match r {
        Refusal::Corrupt(e) => corrupt(&e, messages),
        Refusal::Channel(e) => fail(e),
    };
    while let Some(event) = reader.next_event() {
        let event = event.map_err(|e| match e {
            ::mcap::McapError::UnexpectedEof => corrupt(&cut_where(path, len), state.messages),
            e => corrupt(&e, state.messages),
        })?;
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need.max(READ_SIZE));
                let n = loop {
                    match file.read(buf) {
                        Ok(n) => break n,
                        Err(e) if e.kind() == ErrorKind::Interrupted => continue,
                        Err(e) => return Err(fail(format!("cannot read: {e}"))),
                    }
                };
                reader.notify_read(n);
            }
            LinearReadEvent::Record {
                opcode: op::CHUNK,
                data,
            } => {
                let records = match parse(op::CHUNK, data) {
                    Ok(Record::Chunk { header, data }) => chunk_records(&header, data, limit),
                    Ok(_) => Err("a chunk record that is not one".into()),
                    Err(e) => Err(e),
                }
                .map_err(|e| corrupt(&e, state.messages))?;
                let mut rest: &[u8] = &records;
                while !rest.is_empty() {
                    let (opcode, body, after) = split_record(rest)
                        .ok_or_else(|| corrupt(&"a record overruns its chunk", state.messages))?;
                    let messages = state.messages;
                    state
                        .record(opcode, body, topic)
                        .map_err(|r| refused(r, messages))?;
                    rest = after;
                }
                chunks = chunks.saturating_add(1);
                let before = later.get(chunks).copied().unwrap_or(u64::MAX);
                state.release(before, topic).map_err(fail)?;
            }
            LinearReadEvent::Record { opcode, data } => {
                let messages = state.messages;
                state
                    .record(opcode, data, topic)
                    .map_err(|r| refused(r, messages))?;
                let before = later.get(chunks).copied().unwrap_or(u64::MAX);
                state.release(before, topic).map_err(fail)?;
            }
        }
    }
    state.release(u64::MAX, topic).map_err(fail)?;
    let State {
        channels,
        counted,
        found,
        tally,
        ..
    } = state;
    if let (true, Some((name, _))) = (channels.wanted.is_empty(), channels.others.first()) {
        return Err(fail(format!(
            "topic '{topic}' has type {name}, not {IMU_SCHEMA}"
        )));
    }
    if channels.wanted.is_empty() {
        return Err(fail(absent_topic(
            IMU_SCHEMA,
            topic,
            &channels.imu_topics,
            &channels.all_topics,
        )));
    }
    if let Some(counts) = counted {
        let expected: u64 = channels
            .wanted
            .iter()
            .filter_map(|c| counts.get(c))
            .fold(0u64, |a, &n| a.saturating_add(n));
        if found != expected {
            return Err(fail(format!(
                "truncated or corrupt MCAP file: its statistics count {expected} messages on \
                 '{topic}' and its chunks hold {found}: {}",
                if found < expected {
                    "a chunk is damaged"
                } else {
                    "the summary is damaged"
                }
            )));
        }
    }
    tally.finish(path, topic, &|id| format!("channel {id}"))
}

/// What a read has found so far.
struct State<'a> {
    channels: Channels,
    /// The messages per channel that the summary's statistics count: a chunk that holds
    /// fewer is damaged.
    counted: Option<std::collections::BTreeMap<u16, u64>>,
    /// Messages found on the topic's channels.
    found: u64,
    /// Messages found on every channel.
    messages: u64,
    tally: Tally<'a>,
    /// Whether each message's data is a zstd frame.
    zstd_messages: bool,
    /// The topic's messages read and not yet delivered, the earliest logged on top.
    held: BinaryHeap<Held>,
    /// The frame_ids of the held messages, which name them by index.
    frame_ids: Vec<Vec<u8>>,
    /// The log time and header stamp of the last message delivered of each frame_id (up to
    /// [`CHECKED_FRAME_IDS`] of them).
    last: Vec<(Vec<u8>, u64, i64)>,
    /// Whether the file's summary has a chunk index.
    indexed: bool,
}

/// A message held to be sorted: its log time, its number among the topic's messages, its
/// channel, and its frame with the sensors it marks as not provided and the index of its
/// frame_id (`None` when it did not decode). Ordered for a max-heap to pop the earliest log
/// time first, and of equal log times the first read.
struct Held {
    log_time: u64,
    number: u64,
    channel: u16,
    decoded: Option<(Frame, u32)>,
}

impl Ord for Held {
    fn cmp(&self, other: &Self) -> Ordering {
        (other.log_time, other.number).cmp(&(self.log_time, self.number))
    }
}

impl PartialOrd for Held {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Held {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Held {}

/// The most frame_ids whose order of log times is checked.
const CHECKED_FRAME_IDS: usize = 16;

/// Why a record was not taken: the file is damaged, or a channel on the topic cannot be read.
enum Refusal {
    Corrupt(String),
    Channel(String),
}

impl State<'_> {
    /// One record of the data section or of a chunk.
    fn record(&mut self, opcode: u8, data: &[u8], topic: &str) -> Result<(), Refusal> {
        match opcode {
            op::SCHEMA | op::CHANNEL => {
                let record = parse(opcode, data).map_err(Refusal::Corrupt)?;
                // The summary repeats schemas and channels: the same again is no news, a
                // different definition of an ID is a damaged file.
                let redefined = match &record {
                    Record::Schema { header, .. } => self
                        .channels
                        .schemas
                        .get(&header.id)
                        .is_some_and(|(n, e)| *n != header.name || *e != header.encoding)
                        .then(|| format!("schema {} is defined twice, differently", header.id)),
                    Record::Channel(c) => self
                        .channels
                        .known
                        .get(&c.id)
                        .is_some_and(|(t, s)| *t != c.topic || *s != c.schema_id)
                        .then(|| format!("channel {} is defined twice, differently", c.id)),
                    _ => None,
                };
                if let Some(e) = redefined {
                    return Err(Refusal::Corrupt(e));
                }
                if let Record::Channel(c) = &record {
                    self.channels
                        .known
                        .insert(c.id, (c.topic.clone(), c.schema_id));
                }
                self.channels.add(record, topic).map_err(Refusal::Channel)
            }
            op::CHUNK => Err(Refusal::Corrupt("a chunk inside a chunk".into())),
            op::STATISTICS => {
                if let Ok(Record::Statistics(stats)) = parse(opcode, data) {
                    self.counted = Some(stats.channel_message_counts);
                }
                Ok(())
            }
            op::MESSAGE => {
                self.messages += 1;
                // channel_id (u16), sequence (u32), log_time, publish_time (u64), data.
                let channel = bytes_at::<2>(data, 0)
                    .map(u16::from_le_bytes)
                    .filter(|_| data.len() >= 22)
                    .ok_or_else(|| {
                        Refusal::Corrupt("a message record shorter than its header".into())
                    })?;
                if !self.channels.known.contains_key(&channel) {
                    return Err(Refusal::Corrupt(format!(
                        "a message on channel {channel}, which the file does not define before it"
                    )));
                }
                if self.channels.wanted.contains(&channel) {
                    self.found += 1;
                    let log_time = bytes_at::<8>(data, 6).map_or(0, u64::from_le_bytes);
                    let plain;
                    let body = match data.get(22..) {
                        Some(b) if self.zstd_messages => {
                            plain = unzstd_message(b);
                            plain.as_deref()
                        }
                        b => b,
                    };
                    let decode = if self.channels.ros1.contains(&channel) {
                        crate::bag::decode
                    } else {
                        decode
                    };
                    let decoded = self.tally.decode(body, decode).map(|(f, id)| {
                        let k = match self.frame_ids.iter().position(|i| i == id) {
                            Some(k) => k,
                            None => {
                                self.frame_ids.push(id.to_vec());
                                self.frame_ids.len() - 1
                            }
                        };
                        (f, u32::try_from(k).unwrap_or(u32::MAX))
                    });
                    self.held.push(Held {
                        log_time,
                        number: self.found,
                        channel,
                        decoded,
                    });
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }
}

impl State<'_> {
    /// Delivers the held messages logged before `before`, in the order of their log times
    /// (stable). An error when the one delivered before a message of its frame_id was logged
    /// and stamped after it: the file is out of log-time order where its chunk index (or its
    /// lack of one) could not put it in order.
    fn release(&mut self, before: u64, topic: &str) -> Result<(), String> {
        while let Some(top) = self.held.peek_mut()
            && top.log_time < before
        {
            let Held {
                log_time,
                channel,
                decoded,
                ..
            } = PeekMut::pop(top);
            let decoded: Option<Decoded<'_>> = decoded.map(|(f, k)| {
                let id = usize::try_from(k)
                    .ok()
                    .and_then(|k| self.frame_ids.get(k))
                    .map_or(&[][..], Vec::as_slice);
                (f, id)
            });
            if let Some((frame, id)) = decoded {
                let full = self.last.len() >= CHECKED_FRAME_IDS;
                match self.last.iter_mut().find(|(i, _, _)| i.as_slice() == id) {
                    Some((_, t, stamp)) if log_time < *t && frame.stamp_ns < *stamp => {
                        return Err(format!(
                            "the file's messages are out of log-time order: a message on \
                             '{topic}' logged at {log_time} ns (stamped {} ns) follows one \
                             logged at {t} ns (stamped {stamp} ns), and {}",
                            frame.stamp_ns,
                            if self.indexed {
                                "its chunk index does not match its chunks"
                            } else {
                                "the file has no chunk index to read them in order by"
                            }
                        ));
                    }
                    Some((_, t, stamp)) => (*t, *stamp) = (log_time, frame.stamp_ns),
                    None if !full => {
                        self.last.push((id.to_vec(), log_time, frame.stamp_ns));
                    }
                    None => {}
                }
            }
            self.tally.offer(u32::from(channel), decoded);
        }
        if self.held.is_empty() {
            self.frame_ids.clear();
        }
        Ok(())
    }
}

/// The start times of the chunks in the chunk index of the summary of the MCAP file `file`
/// (`len` bytes), in the order of the chunks in the file; none when it has no summary or no
/// chunk index, or they cannot be read.
fn chunk_starts(file: &mut File, len: u64) -> Vec<u64> {
    chunk_index(file, len).unwrap_or_default()
}

/// Where the MCAP file `path` (`len` bytes), read to its end, was cut: its records walked
/// from the magic by their lengths, within one (the byte it began at), after its last whole
/// one with no footer, or after its footer (its closing magic short).
fn cut_where(path: &Path, len: u64) -> String {
    let cut = "cut short (a recording not closed, or a copy cut off; `mcap recover` keeps its \
               whole chunks)";
    let Ok(mut file) = File::open(path) else {
        return format!("it ends in the middle of a record: {cut}");
    };
    let mut at = ::mcap::MAGIC.len() as u64;
    let mut head = [0u8; 9];
    while at < len {
        let read = file
            .seek(SeekFrom::Start(at))
            .and_then(|_| file.read_exact(&mut head));
        let end = u64::from_le_bytes(head[1..].try_into().unwrap_or_default())
            .checked_add(at + 9)
            .filter(|&end| read.is_ok() && end <= len);
        match end {
            Some(end) if head[0] == op::FOOTER => {
                return format!(
                    "its closing magic is cut short after its footer (at byte {end}): a copy \
                     cut off"
                );
            }
            Some(end) => at = end,
            None => return format!("it ends in the middle of a record begun at byte {at}: {cut}"),
        }
    }
    "it ends after its last whole record, without its footer and closing magic: a recording \
     not closed (`mcap recover` writes them)"
        .into()
}

/// [`chunk_starts`], `None` where it finds none.
fn chunk_index(file: &mut File, len: u64) -> Option<Vec<u64>> {
    // The footer record (opcode, length 20, summary_start, summary_offset_start, CRC) and the
    // closing magic end the file.
    let magic = ::mcap::MAGIC.len() as u64;
    let footer = len.checked_sub(magic + 9 + 20)?;
    file.seek(SeekFrom::Start(footer)).ok()?;
    let mut record = [0u8; 29];
    file.read_exact(&mut record).ok()?;
    if record[0] != op::FOOTER || bytes_at::<8>(&record, 1).map(u64::from_le_bytes) != Some(20) {
        return None;
    }
    let start = bytes_at::<8>(&record, 9).map(u64::from_le_bytes)?;
    if start < magic || start >= footer {
        return None;
    }
    file.seek(SeekFrom::Start(start)).ok()?;
    let mut summary = BufReader::new(file);
    // Chunk start offset and start time of each chunk index record.
    let mut chunks: Vec<(u64, u64)> = Vec::new();
    let mut at = start;
    while at < footer {
        let mut head = [0u8; 9];
        summary.read_exact(&mut head).ok()?;
        let size = bytes_at::<8>(&head, 1).map(u64::from_le_bytes)?;
        let end = at.checked_add(9)?.checked_add(size)?;
        if end > footer {
            return None;
        }
        let mut skip = size;
        if head[0] == op::CHUNK_INDEX {
            // message_start_time, message_end_time, chunk_start_offset.
            let mut fields = [0u8; 24];
            if size < 24 {
                return None;
            }
            summary.read_exact(&mut fields).ok()?;
            let time = bytes_at::<8>(&fields, 0).map(u64::from_le_bytes)?;
            let offset = bytes_at::<8>(&fields, 16).map(u64::from_le_bytes)?;
            chunks.push((offset, time));
            skip -= 24;
        }
        summary.seek_relative(i64::try_from(skip).ok()?).ok()?;
        at = end;
    }
    chunks.sort_unstable();
    Some(chunks.into_iter().map(|(_, time)| time).collect())
}

/// The record `data` of kind `opcode`, parsed by the [`mcap`] crate once its strings are
/// known to fit in it: the crate allocates the length a string declares before it reads the
/// string, so a corrupt length of 4 GB would be 4 GB allocated.
fn parse(opcode: u8, data: &[u8]) -> Result<Record<'_>, String> {
    // Where the strings start, how many there are, and whether a map of strings follows.
    let (fixed, strings, map) = match opcode {
        op::SCHEMA => (2, 2, false),
        op::CHANNEL => (4, 2, true),
        op::CHUNK => (28, 1, false),
        _ => (0, 0, false),
    };
    let overrun = || "a string overruns its record".to_string();
    let mut rest = data.get(fixed..).unwrap_or_default();
    for _ in 0..strings {
        rest = skip_string(rest).ok_or_else(overrun)?;
    }
    if map {
        // The map's length in bytes, then key and value strings while they are within it.
        let len = bytes_at::<4>(rest, 0).map_or(0, u32::from_le_bytes);
        let start = rest.len().saturating_sub(4);
        rest = rest.get(4..).unwrap_or_default();
        while start - rest.len() < len as usize && !rest.is_empty() {
            rest = skip_string(rest)
                .and_then(skip_string)
                .ok_or_else(overrun)?;
        }
    }
    ::mcap::parse_record(opcode, data).map_err(|e| e.to_string())
}

/// What follows the string (length u32, then its bytes) at the start of `bytes`; `None` when
/// its length overruns `bytes`.
fn skip_string(bytes: &[u8]) -> Option<&[u8]> {
    let len = usize::try_from(u32::from_le_bytes(bytes_at::<4>(bytes, 0)?)).ok()?;
    bytes.get(4..)?.get(len..)
}

/// The first record of `bytes` (opcode u8, length u64, body): its opcode, body and what
/// follows it; `None` when it overruns `bytes`.
fn split_record(bytes: &[u8]) -> Option<(u8, &[u8], &[u8])> {
    let opcode = *bytes.first()?;
    let len = usize::try_from(u64::from_le_bytes(bytes_at::<8>(bytes, 1)?)).ok()?;
    let end = 9usize.checked_add(len)?;
    Some((opcode, bytes.get(9..end)?, bytes.get(end..)?))
}

/// The records of a chunk: its data decompressed (none, zstd or lz4), of exactly the size it
/// declares (at most `limit`), with the CRC it declares (0: none).
fn chunk_records<'a>(
    header: &::mcap::records::ChunkHeader,
    data: std::borrow::Cow<'a, [u8]>,
    limit: usize,
) -> Result<std::borrow::Cow<'a, [u8]>, String> {
    use std::borrow::Cow;
    let size = usize::try_from(header.uncompressed_size)
        .ok()
        .filter(|&s| s <= limit)
        .ok_or_else(|| {
            format!(
                "a chunk declares {} bytes, more than the file could hold",
                header.uncompressed_size
            )
        })?;
    let cap = u64::try_from(size).unwrap_or(u64::MAX).saturating_add(1);
    let inflate = |reader: &mut dyn Read| -> Result<Vec<u8>, String> {
        let mut out = Vec::new();
        reader
            .take(cap)
            .read_to_end(&mut out)
            .map_err(|e| format!("a chunk does not decompress: {e}"))?;
        Ok(out)
    };
    let records: Cow<'a, [u8]> = match header.compression.as_str() {
        "" => data,
        "zstd" => {
            let mut d = zstd::stream::read::Decoder::new(&data[..])
                .map_err(|e| format!("a chunk does not decompress: {e}"))?;
            Cow::Owned(inflate(&mut d)?)
        }
        "lz4" => {
            let mut d = lz4::Decoder::new(&data[..])
                .map_err(|e| format!("a chunk does not decompress: {e}"))?;
            Cow::Owned(inflate(&mut d)?)
        }
        other => {
            return Err(format!(
                "chunk compression '{}' is not read (zstd, lz4 or none)",
                crate::error::escaped(other)
            ));
        }
    };
    if records.len() != size {
        return Err(format!(
            "a chunk is damaged: it declares {size} bytes and holds {}",
            if records.len() > size {
                "more".to_string()
            } else {
                records.len().to_string()
            }
        ));
    }
    if header.uncompressed_crc != 0 && crc32fast::hash(&records) != header.uncompressed_crc {
        return Err("a chunk's CRC does not match its data".into());
    }
    Ok(records)
}

/// The schemas and channels read so far.
#[derive(Default)]
struct Channels {
    /// Schema ID to name and encoding.
    schemas: HashMap<u16, (String, String)>,
    /// The IDs of the channels on the topic.
    wanted: Vec<u16>,
    /// The topics of the IMU channels, in the order first seen.
    imu_topics: Vec<String>,
    /// All topics, in the order first seen.
    all_topics: Vec<String>,
    /// Channel ID to topic and schema ID, of every channel.
    known: HashMap<u16, (String, u16)>,
    /// The channels on the topic of another schema: its name, and the channel's ID.
    others: Vec<(String, u16)>,
    /// The IDs of the channels on the topic whose messages are ROS 1's (`mcap convert` of a
    /// ROS 1 bag).
    ros1: Vec<u16>,
}

impl Channels {
    /// Takes in a schema or channel record; an error when it is a channel on `topic` that
    /// cannot be read, or the topic has channels of the IMU's schema and another's.
    fn add(&mut self, record: Record<'_>, topic: &str) -> Result<(), String> {
        self.take(record, topic)?;
        if self.wanted.is_empty() || self.others.is_empty() {
            return Ok(());
        }
        let ids = |ids: &mut dyn Iterator<Item = u16>| {
            ids.map(|id| id.to_string()).collect::<Vec<_>>().join(", ")
        };
        Err(format!(
            "topic '{topic}' carries {IMU_SCHEMA} (channel {}) and {}: one topic, one type of \
             message; copy the IMU's channel into a file of its own (the mcap library's reader \
             and writer) and read that",
            ids(&mut self.wanted.iter().copied()),
            self.others
                .iter()
                .map(|(name, id)| format!("{name} (channel {id})"))
                .collect::<Vec<_>>()
                .join(", ")
        ))
    }

    /// [`Channels::add`] without the check of the topic's schemas.
    fn take(&mut self, record: Record<'_>, topic: &str) -> Result<(), String> {
        match record {
            Record::Schema { header, .. } => {
                self.schemas
                    .insert(header.id, (header.name, header.encoding));
            }
            Record::Channel(c) => {
                let schema = self.schemas.get(&c.schema_id);
                let name = schema.map_or("", |s| s.0.as_str());
                let imu = name == IMU_SCHEMA || name == ROS1_IMU_SCHEMA;
                if c.topic == topic && schema.is_some() && !imu {
                    if !self.others.iter().any(|o| o.1 == c.id) {
                        self.others.push((name.to_string(), c.id));
                    }
                } else if c.topic == topic {
                    let ros1 = check_channel(topic, c.schema_id, schema, &c.message_encoding)?;
                    if !self.wanted.contains(&c.id) {
                        self.wanted.push(c.id);
                    }
                    if ros1 && !self.ros1.contains(&c.id) {
                        self.ros1.push(c.id);
                    }
                }
                if imu && !self.imu_topics.contains(&c.topic) {
                    self.imu_topics.push(c.topic.clone());
                }
                if !self.all_topics.contains(&c.topic) {
                    self.all_topics.push(c.topic);
                }
            }
            _ => {}
        }
        Ok(())
    }
}

/// A channel on `topic` (its schema, and its message encoding) that this reader can decode:
/// whether its messages are ROS 1's.
fn check_channel(
    topic: &str,
    schema_id: u16,
    schema: Option<&(String, String)>,
    message_encoding: &str,
) -> Result<bool, String> {
    let Some((name, encoding)) = schema else {
        return Err(if schema_id == 0 {
            format!("topic '{topic}' has no schema, not {IMU_SCHEMA}")
        } else {
            format!("topic '{topic}' names schema {schema_id}, which the file does not define")
        });
    };
    if name == ROS1_IMU_SCHEMA {
        return if encoding == ROS1_SCHEMA_ENCODING && message_encoding == ROS1 {
            Ok(true)
        } else {
            Err(format!(
                "topic '{topic}' has the ROS 1 type {name} in schema encoding '{encoding}' and \
                 message encoding '{message_encoding}' (read: {ROS1_SCHEMA_ENCODING} and {ROS1})"
            ))
        };
    }
    if name != IMU_SCHEMA {
        return Err(format!("topic '{topic}' has type {name}, not {IMU_SCHEMA}"));
    }
    if !SCHEMA_ENCODINGS.contains(&encoding.as_str()) {
        return Err(format!(
            "unknown schema encoding '{encoding}' on topic '{topic}' (supported: \
             {READ_ENCODINGS})"
        ));
    }
    if message_encoding != CDR {
        return Err(format!(
            "unknown encoding '{message_encoding}' on topic '{topic}' (supported: {CDR})"
        ));
    }
    Ok(false)
}

/// Why a file that does not start with the MCAP magic is not read.
fn not_mcap(head: &[u8]) -> String {
    if head.starts_with(b"#ROSBAG") {
        "not an MCAP file: a ROS 1 bag (read it as a bag)".to_string()
    } else if head.starts_with(b"SQLite format 3") {
        "not an MCAP file: an SQLite database (a rosbag2 .db3 file?)".to_string()
    } else {
        "not an MCAP file (it does not start with the MCAP magic)".to_string()
    }
}

/// The frame of one CDR-serialized `sensor_msgs/msg/Imu`, the sensors it marks as not
/// provided, and its header's frame_id (without its NUL): `None` when the encapsulation is not
/// CDR_LE or CDR_BE, or the message is too short.
pub(crate) fn decode(b: &[u8]) -> Option<Decoded<'_>> {
    let big = match b.get(..2)? {
        [0, 1] => false,
        [0, 0] => true,
        _ => return None,
    };
    // Offsets past the encapsulation header, where CDR alignment counts from.
    let body = b.get(4..)?;
    let sec = u32_at(body, 0, big)? as i32;
    let nanosec = u32_at(body, 4, big)?;
    let frame_id = usize::try_from(u32_at(body, 8, big)?).ok()?;
    let end = 12usize.checked_add(frame_id)?;
    let at = end.checked_add(7)? & !7;
    let (axes, marks) = imu_axes(body, at, big)?;
    let frame = Frame {
        stamp_ns: stamp_ns(i64::from(sec), nanosec),
        axes,
        not_provided: marks,
    };
    let id = body.get(12..end)?;
    Some((frame, id.strip_suffix(&[0]).unwrap_or(id)))
}
