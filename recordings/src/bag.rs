//! Streaming `sensor_msgs/Imu` messages out of a ROS 1 bag (format 2.0,
//! <http://wiki.ros.org/Bags/Format/2.0>), uncompressed, bz2 or lz4 chunks, through the
//! [`rosbag`] crate.
//!
//! The bag is memory-mapped by [`rosbag::RosBag`] and read one chunk at a time (a compressed
//! chunk is decompressed into one buffer, dropped before the next): memory is bounded by the
//! largest chunk, whatever the length of the bag (unless its chunks are out of time order:
//! then the topic's messages are held to be sorted). The connections come from the index section
//! at the end of the bag, so the topic and its type are checked before any message is read.
//!
//! A message is decoded by hand from its ROS 1 serialization
//! (<http://wiki.ros.org/msg#Serialization>, <http://wiki.ros.org/ROS/TCPROS>: little-endian,
//! no alignment) of `sensor_msgs/Imu`
//! (<http://docs.ros.org/en/noetic/api/sensor_msgs/html/msg/Imu.html>): the `std_msgs/Header`
//! (uint32 seq, time stamp as uint32 secs and uint32 nsecs, string frame_id as a uint32 length
//! and its bytes), then 37 float64 (orientation, its covariance, angular_velocity, its
//! covariance, linear_acceleration, its covariance).

use crate::frame::open_head;
use std::path::Path;

use rosbag::{ChunkRecord, IndexRecord, MessageRecord, RosBag};

use crate::csv::DataError;
use crate::error::escaped;
use crate::frame::{
    Decoded, Frame, IMU_F64S, Select, Skipped, Tally, absent_topic, data_error, imu_axes, stamp_ns,
    u32_at,
};

/// The message type of the IMU connections.
pub const IMU_TYPE: &str = "sensor_msgs/Imu";

/// The MD5 sum of the `sensor_msgs/Imu` definition, `6a62c6daae103f4ff57a132d6f95cec2`.
const IMU_MD5: [u8; 16] = [
    0x6a, 0x62, 0xc6, 0xda, 0xae, 0x10, 0x3f, 0x4f, 0xf5, 0x7a, 0x13, 0x2d, 0x6f, 0x95, 0xce, 0xc2,
];

/// The first bytes of a bag of format 2.0.
const MAGIC: &[u8] = b"#ROSBAG V2.0\n";

/// Calls `each` with every finite `sensor_msgs/Imu` message on `topic` of the ROS 1 bag `path`,
/// in the order of their receive times, and returns what was skipped. A bag whose chunks
/// follow each other in time (the index's chunk records say so) is streamed chunk by chunk,
/// each chunk's messages sorted; one written out of time order is read whole and its
/// messages on the topic sorted (56 bytes each held).
///
/// Messages that cannot be decoded, and those with a NaN or an infinite axis, are counted and
/// not delivered; those that mark their gyro or accelerometer as not provided (the first
/// element of its covariance -1) are delivered and counted ([`Skipped::not_provided`]). An error (after the frames already delivered, when the damage is found
/// midway) when the file is not a bag of format 2.0, is truncated or corrupt, has no
/// connection on `topic`, has one of another type (or another definition of `sensor_msgs/Imu`),
/// or has no finite message on it.
pub fn read(path: &Path, topic: &str, each: &mut dyn FnMut(Frame)) -> Result<Skipped, DataError> {
    read_selected(path, &Select::topic(topic), each)
}

/// [`read`] of the messages `select` asks for: on its topic, from the IMU of its header
/// frame_id (the others counted as skipped). An error too when the topic carries more than one
/// IMU (frame_ids) and `select` names none, or when two connections send one frame_id at
/// interleaved times.
pub fn read_selected(
    path: &Path,
    select: &Select,
    each: &mut dyn FnMut(Frame),
) -> Result<Skipped, DataError> {
    let topic = select.topic;
    let fail = |problem: String| data_error(path, problem);
    let corrupt = |what: String| fail(format!("truncated or corrupt bag: {what}"));
    let declared = check_header(path)?;
    let bag = RosBag::new(path).map_err(|e| corrupt(e.to_string()))?;
    // The connection records the index holds.
    let mut connections = 0u32;

    // The connections, from the index section.
    let mut ids = Vec::new();
    let mut callers: Vec<(u32, String)> = Vec::new();
    // The topic's connections of another type.
    let mut others: Vec<(String, u32, String)> = Vec::new();
    let mut imu_topics = Vec::new();
    let mut all_topics = Vec::new();
    // Each chunk's position, and the receive times of its first and last message.
    let mut chunks: Vec<(u64, u64, u64)> = Vec::new();
    // Each chunk's position and its messages per connection, as the index counts them.
    let mut counted: Vec<(u64, Vec<(u32, u32)>)> = Vec::new();
    for record in bag.index_records() {
        let c = match record.map_err(|e| corrupt(format!("{} (in the index)", text(&e))))? {
            IndexRecord::Connection(c) => c,
            IndexRecord::ChunkInfo(info) => {
                chunks.push((info.chunk_pos, info.start_time, info.end_time));
                let per_connection = info.entries().map(|e| (e.conn_id, e.count)).collect();
                counted.push((info.chunk_pos, per_connection));
                continue;
            }
            _ => continue,
        };
        connections = connections.saturating_add(1);
        let name = c.storage_topic.to_string();
        if c.storage_topic == topic {
            if c.tp != IMU_TYPE {
                others.push((c.tp.to_string(), c.id, c.caller_id.to_string()));
                continue;
            }
            if c.md5sum != IMU_MD5 {
                let md5: String = c.md5sum.iter().map(|b| format!("{b:02x}")).collect();
                return Err(fail(format!(
                    "topic '{topic}' has type {IMU_TYPE} with md5sum {md5}, not \
                     6a62c6daae103f4ff57a132d6f95cec2 (another definition of the message)"
                )));
            }
            ids.push(c.id);
            callers.push((c.id, c.caller_id.to_string()));
        }
        if c.tp == IMU_TYPE && !imu_topics.contains(&name) {
            imu_topics.push(name.clone());
        }
        if !all_topics.contains(&name) {
            all_topics.push(name);
        }
    }
    if let Some(n) = declared.filter(|&n| n > connections) {
        return Err(corrupt(format!(
            "its header declares {n} connection{} and its index holds {connections}: the index \
             is damaged (`rosbag reindex` rebuilds it)",
            if n == 1 { "" } else { "s" }
        )));
    }
    if let Some(other) = others.first() {
        return Err(fail(if ids.is_empty() {
            format!("topic '{topic}' has type {}, not {IMU_TYPE}", other.0)
        } else {
            format!(
                "topic '{topic}' carries {IMU_TYPE} (connection{} {}) and {}: one topic, one \
                 type of message; keep the IMU's connections (rosbag filter) and read those",
                if ids.len() > 1 { "s" } else { "" },
                ids.iter()
                    .map(u32::to_string)
                    .collect::<Vec<_>>()
                    .join(", "),
                others
                    .iter()
                    .map(|(tp, id, caller)| match caller.as_str() {
                        "" => format!("{tp} (connection {id})"),
                        _ => format!("{tp} (connection {id}, from {caller})"),
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        }));
    }
    if ids.is_empty() {
        return Err(fail(absent_topic(
            IMU_TYPE,
            topic,
            &imu_topics,
            &all_topics,
        )));
    }

    let mut tally = Tally::new(select, each);
    let mut messages = 0u64;
    let midway = |e: &rosbag::Error, messages: u64| {
        corrupt(format!(
            "{} (in the chunk section, after {messages} messages)",
            text(e)
        ))
    };
    // Chunks that follow each other in receive time (as a recorder writes them) are streamed
    // chunk by chunk. A bag written out of time order (merged, or filtered by a script) is
    // read whole, its messages on the topic sorted by receive time, the order `rosbag play`
    // plays them in.
    chunks.sort_unstable();
    let in_order = chunks.windows(2).all(|w| w[0].2 <= w[1].1);
    // The topic's messages the index counts (each chunk once), to find a chunk that holds
    // fewer than it should (a compressed chunk whose declared size was damaged reads empty).
    counted.sort_unstable_by_key(|&(pos, _)| pos);
    counted.dedup_by_key(|&mut (pos, _)| pos);
    let expected: u64 = counted
        .iter()
        .flat_map(|(_, entries)| entries)
        .filter(|(conn, _)| ids.contains(conn))
        .fold(0u64, |a, &(_, n)| a.saturating_add(u64::from(n)));
    let mut found = 0u64;
    let mut sorted: Vec<Held> = Vec::new();
    let mut frame_ids: Vec<Vec<u8>> = Vec::new();
    for record in bag.chunk_records() {
        let ChunkRecord::Chunk(chunk) = record.map_err(|e| midway(&e, messages))? else {
            continue;
        };
        for message in chunk.messages() {
            let MessageRecord::MessageData(m) = message.map_err(|e| midway(&e, messages))? else {
                continue;
            };
            messages += 1;
            if !ids.contains(&m.conn_id) {
                continue;
            }
            found += 1;
            let frame = decode(m.data).map(|(f, id)| {
                let k = frame_ids.iter().position(|i| i == id).unwrap_or_else(|| {
                    frame_ids.push(id.to_vec());
                    frame_ids.len() - 1
                });
                (f, u16::try_from(k).unwrap_or(u16::MAX))
            });
            sorted.push((m.time, m.conn_id, frame));
        }
        if in_order {
            // The chunk's messages in receive-time order (as stored, unless the bag was
            // edited), delivered before the next chunk is read.
            deliver(&mut sorted, &frame_ids, &mut tally);
            frame_ids.clear();
        }
    }
    if found < expected {
        return Err(corrupt(format!(
            "the index counts {expected} messages on '{topic}' and the chunks hold {found}: a \
             chunk is damaged"
        )));
    }
    deliver(&mut sorted, &frame_ids, &mut tally);
    let names = |id: u32| {
        let caller = callers.iter().find(|(c, _)| *c == id).map(|(_, n)| n);
        match caller {
            Some(n) if !n.is_empty() => format!("connection {id}, callerid '{}'", escaped(n)),
            _ => format!("connection {id}"),
        }
    };
    tally.finish(path, topic, &names)
}

/// The `held` messages to `tally` in the order of their receive times (stable), `held` left
/// empty; `frame_ids` names their frame_ids by index.
fn deliver(held: &mut Vec<Held>, frame_ids: &[Vec<u8>], tally: &mut Tally) {
    held.sort_by_key(|&(time, _, _)| time);
    for (_, conn, frame) in held.drain(..) {
        let id = |k: u16| frame_ids.get(usize::from(k)).map_or(&[][..], Vec::as_slice);
        tally.offer(conn, frame.map(|(f, k)| (f, id(k))));
    }
}

/// A message held to be sorted: its receive time, connection, and frame with the sensors it
/// marks as not provided and the index of its frame_id (`None` when it did not decode).
type Held = (u64, u32, Option<(Frame, u16)>);

/// The rosbag crate's error text without its `rosbag::Error: ` prefix.
fn text(e: &rosbag::Error) -> String {
    let s = e.to_string();
    s.strip_prefix("rosbag::Error: ").unwrap_or(&s).to_string()
}

/// Checks what [`RosBag`] takes on trust, so that it cannot panic: the magic, and an index
/// position inside the file after the bag header record.
fn check_header(path: &Path) -> Result<Option<u32>, DataError> {
    let fail = |problem: String| data_error(path, problem);
    let corrupt = |what: &str| fail(format!("truncated or corrupt bag: {what}"));
    // The magic, the bag header record's header length; the header record itself is
    // 4096 bytes long in bags written by ROS, 64 KiB is plenty.
    let (_, len, head) = open_head(path, 64 * 1024)?;
    if !head.starts_with(MAGIC) {
        if MAGIC.starts_with(&head) {
            return Err(corrupt(&format!("{len} bytes, shorter than the magic")));
        }
        return Err(fail(not_a_bag(&head)));
    }
    let at = MAGIC.len();
    let header_len = u32_at(&head, at, false).ok_or_else(|| corrupt("no bag header record"))?;
    let fields_at = at + 4;
    let fields = usize::try_from(header_len)
        .ok()
        .and_then(|n| head.get(fields_at..fields_at.checked_add(n)?))
        .ok_or_else(|| corrupt("the bag header record is cut short"))?;
    let index_pos = header_field(fields, b"index_pos")
        .and_then(|v| <[u8; 8]>::try_from(v).ok())
        .map(u64::from_le_bytes)
        .ok_or_else(|| corrupt("the bag header has no index_pos"))?;
    let data_len = u32_at(&head, fields_at + fields.len(), false)
        .ok_or_else(|| corrupt("the bag header record is cut short"))?;
    let start = (fields_at + fields.len() + 4) as u64 + u64::from(data_len);
    if index_pos == 0 {
        return Err(corrupt(
            "no index (index_pos is 0: the recording was not closed; `rosbag reindex` repairs it)",
        ));
    }
    if index_pos < start || index_pos > len {
        return Err(corrupt(&format!(
            "the index is at byte {index_pos}, past the end of the file ({len} bytes) or \
             inside its header"
        )));
    }
    Ok(header_field(fields, b"conn_count")
        .and_then(|v| <[u8; 4]>::try_from(v).ok())
        .map(u32::from_le_bytes))
}

/// The value of field `name` of a record header (`<u32 length><name>=<value>` fields).
fn header_field<'a>(mut fields: &'a [u8], name: &[u8]) -> Option<&'a [u8]> {
    while !fields.is_empty() {
        let n = usize::try_from(u32_at(fields, 0, false)?).ok()?;
        let field = fields.get(4..4usize.checked_add(n)?)?;
        fields = fields.get(4 + n..)?;
        let eq = field.iter().position(|&b| b == b'=')?;
        if field.get(..eq)? == name {
            return field.get(eq + 1..);
        }
    }
    None
}

/// Why a file that does not start with the bag magic is not read.
fn not_a_bag(head: &[u8]) -> String {
    if head.starts_with(b"#ROSBAG V") {
        let version: String = head
            .iter()
            .skip(9)
            .take_while(|b| b.is_ascii_graphic())
            .map(|&b| char::from(b))
            .collect();
        format!("a ROS bag of format {version}: only format 2.0 is read")
    } else if head.starts_with(b"\x89MCAP") {
        "not a ROS 1 bag: an MCAP file (read it as MCAP)".to_string()
    } else {
        "not a ROS 1 bag (it does not start with '#ROSBAG V2.0')".to_string()
    }
}

/// The frame of one serialized `sensor_msgs/Imu`, the sensors it marks as not provided, and
/// its header's frame_id: `None` when its length is not that of the message (the header's
/// frame_id length included).
pub(crate) fn decode(b: &[u8]) -> Option<Decoded<'_>> {
    let secs = u32_at(b, 4, false)?;
    let nsecs = u32_at(b, 8, false)?;
    let frame_id = usize::try_from(u32_at(b, 12, false)?).ok()?;
    let at = 16usize.checked_add(frame_id)?;
    if b.len() != at.checked_add(IMU_F64S * 8)? {
        return None;
    }
    let (axes, marks) = imu_axes(b, at, false)?;
    let frame = Frame {
        stamp_ns: stamp_ns(i64::from(secs), nsecs),
        axes,
        not_provided: marks,
    };
    Some((frame, b.get(16..at)?))
}
