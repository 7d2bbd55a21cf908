//! What the tests of the ROS readers share: the committed fixtures (written by the Python
//! package `rosbags`, cli/tests/fixtures/write_ros.py), the frames they hold, byte edits of
//! them, reading back and comparing bit for bit. No test runs Python.

// Each test file uses some of these.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use imu_ar_cli::input::csv::DataError;
use imu_ar_cli::input::frame::{Frame, Skipped};
use imu_ar_cli::input::{bag, mcap as mcap_reader};

/// `bag::read` or `mcap::read`.
pub type Reader = fn(&Path, &str, &mut dyn FnMut(Frame)) -> Result<Skipped, DataError>;

/// The committed fixture `name` (cli/tests/fixtures/ros/; cli/tests/fixtures/write_ros.py wrote
/// it, and its table says which frames each file holds).
pub fn fixture(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/ros")
        .join(name);
    assert!(path.is_file(), "no fixture {}", path.display());
    path
}

/// The committed fixture folder `name` (a rosbag2 folder).
pub fn fixture_dir(name: &str) -> PathBuf {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/ros")
        .join(name);
    assert!(path.is_dir(), "no fixture folder {}", path.display());
    path
}

/// The bytes of the committed fixture `name`.
pub fn fixture_bytes(name: &str) -> Vec<u8> {
    std::fs::read(fixture(name)).unwrap()
}

/// An empty directory for one test's files.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = crate::common::temp_path(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Steele, Lea and Flood's splitmix64: the fixture script's generator, step for step.
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// The generator seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
}

/// The fixture script's `frames(n, seed)`: stamps 2.5 ms apart with a jitter, axes of random
/// bits (magnitudes 2^-14 to 2^14, both signs), one in 97 a special value (negative zero,
/// subnormals, extremes).
pub fn frames(n: usize, seed: u64) -> Vec<Frame> {
    let mut rng = SplitMix64::new(seed);
    let specials = [
        -0.0,
        5e-324,
        -2.2e-308,
        f64::MAX,
        f64::MIN_POSITIVE,
        1e300,
        -1e-300,
    ];
    (0..n)
        .map(|i| {
            let jitter = (rng.next_u64() % 100_000) as i64;
            let stamp_ns = 1_700_000_000_123_456_789 + i as i64 * 2_500_000 + jitter;
            let axes = std::array::from_fn(|_| {
                let r = rng.next_u64();
                if r.is_multiple_of(97) {
                    specials[(r >> 32) as usize % specials.len()]
                } else {
                    let exponent = 1009 + (r >> 52) % 28;
                    f64::from_bits((r & 1 << 63) | exponent << 52 | (r & ((1 << 52) - 1)))
                }
            });
            Frame {
                stamp_ns,
                axes,
                ..Frame::default()
            }
        })
        .collect()
}

/// The fixture script's `noise(n, seed)`: a static IMU at 100 Hz (white noise, a random walk
/// and a Gauss-Markov term about a mean, gravity on z) in integer counts of 2^-18 rad/s and
/// 2^-15 m/s^2.
pub fn noise(n: usize, seed: u64) -> Vec<Frame> {
    const MEAN: [i64; 6] = [3, -5, 1, 13, -26, 5024];
    const GYRO_LSB: f64 = 1.0 / 4096.0;
    const ACCEL_LSB: f64 = 1.0 / 512.0;
    let mut rng = SplitMix64::new(seed);
    let (mut walk, mut gm) = ([0i64; 6], [0i64; 6]);
    (0..n)
        .map(|i| {
            let jitter = (rng.next_u64() % 40_001) as i64 - 20_000;
            let stamp_ns = 1_403_636_579_758_555_392 + i as i64 * 10_000_000 + jitter;
            let axes = std::array::from_fn(|k| {
                let white = (0..4).map(|_| (rng.next_u64() % 33) as i64).sum::<i64>() - 64;
                walk[k] += (rng.next_u64() % 3) as i64 - 1;
                gm[k] += ((rng.next_u64() % 9) as i64 - 4) * 16 - (gm[k] >> 5);
                let counts = MEAN[k] * 64 + white * 4 + walk[k] + (gm[k] >> 4);
                let lsb = if k < 3 { GYRO_LSB } else { ACCEL_LSB };
                counts as f64 * lsb / 64.0
            });
            Frame {
                stamp_ns,
                axes,
                ..Frame::default()
            }
        })
        .collect()
}

/// The frames of the fixtures `frames-{none,bz2,lz4}.bag` and `frames-{none,zstd,lz4}.mcap`.
pub fn round_trip_frames() -> Vec<Frame> {
    frames(300, 1)
}

/// The frames of the fixtures `noise.bag` (with three messages on `/chatter`),
/// `noise-bz2.bag` and `noise-zstd.mcap`, all on `/imu0`.
pub fn noise_frames() -> Vec<Frame> {
    noise(1200, 2)
}

/// Where the frame_id `imu_link` of each IMU message starts, in file order, in an
/// uncompressed fixture. In both serializations the header stamp's seconds and nanoseconds are
/// the two u32 before the string's length (`id - 12` and `id - 8`).
pub fn frame_ids(bytes: &[u8]) -> Vec<usize> {
    find_all(bytes, b"imu_link")
}

/// Sets the header stamp of the message whose frame_id starts at `id` (little-endian).
pub fn set_stamp(bytes: &mut [u8], id: usize, stamp_ns: i64) {
    let sec = stamp_ns.div_euclid(1_000_000_000) as u32;
    let nsec = stamp_ns.rem_euclid(1_000_000_000) as u32;
    bytes[id - 12..id - 8].copy_from_slice(&sec.to_le_bytes());
    bytes[id - 8..id - 4].copy_from_slice(&nsec.to_le_bytes());
}

/// Sets axis `k` (gx, gy, gz, ax, ay, az) of the ROS 1 message whose frame_id starts at `id`:
/// after the 8 bytes of `imu_link` come the orientation (4 float64) and its covariance (9),
/// angular_velocity (3), its covariance (9), then linear_acceleration.
pub fn set_ros1_axis(bytes: &mut [u8], id: usize, k: usize, value: f64) {
    let at = id + [112, 120, 128, 208, 216, 224][k];
    bytes[at..at + 8].copy_from_slice(&value.to_le_bytes());
}

/// `frames` written as the fixture `name` would hold them after [`set_stamp`] and
/// [`set_ros1_axis`] edits: the uncompressed bag `base` with each frame's stamp and axes
/// replaced, into `dir/name`.
pub fn edited_bag(dir: &Path, base: &str, name: &str, frames: &[Frame]) -> PathBuf {
    let mut bytes = fixture_bytes(base);
    let ids = frame_ids(&bytes);
    assert_eq!(ids.len(), frames.len(), "{base}: one message per frame");
    for (&id, f) in ids.iter().zip(frames) {
        set_stamp(&mut bytes, id, f.stamp_ns);
        for (k, &v) in f.axes.iter().enumerate() {
            set_ros1_axis(&mut bytes, id, k, v);
        }
    }
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

/// The file extension of `format`.
pub fn extension(format: &str) -> &str {
    if format == "ros1" { "bag" } else { "mcap" }
}

/// The reader of `format`.
pub fn reader(format: &str) -> Reader {
    if format == "ros1" {
        bag::read
    } else {
        mcap_reader::read
    }
}

/// The frames `read` delivers from `path` on `topic`, and its result.
pub fn collect(read: Reader, path: &Path, topic: &str) -> (Vec<Frame>, Result<Skipped, DataError>) {
    let mut got = Vec::new();
    let result = read(path, topic, &mut |f| got.push(f));
    (got, result)
}

/// The error's problem, asserting that it names the file and is one line.
pub fn problem(path: &Path, result: Result<Skipped, DataError>) -> String {
    let e = result.expect_err("an error");
    assert_eq!(e.file, path);
    assert!(!e.problem.contains('\n'), "{e}");
    e.problem
}

/// `got` is `want`, stamps and the bits of every axis.
pub fn assert_bits(got: &[Frame], want: &[Frame], what: &str) {
    assert_eq!(got.len(), want.len(), "{what}: number of frames");
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert_eq!(g.stamp_ns, w.stamp_ns, "{what}: stamp of frame {i}");
        let bits = |f: &Frame| f.axes.map(f64::to_bits);
        assert_eq!(bits(g), bits(w), "{what}: axes of frame {i}");
    }
}

/// Where `needle` starts in `hay`.
pub fn find_all(hay: &[u8], needle: &[u8]) -> Vec<usize> {
    hay.windows(needle.len())
        .enumerate()
        .filter(|(_, w)| *w == needle)
        .map(|(i, _)| i)
        .collect()
}

/// The largest anonymous (heap) memory of this process so far, in kB, from
/// /proc/self/status (RssAnon: the mapped bag's pages are file pages, not counted).
pub fn rss_anon_kb() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("RssAnon:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap_or(0)
}
