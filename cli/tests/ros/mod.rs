//! What the tests of the ROS readers (`tests/bags.rs`) share: seeded frames, the fixture
//! script (Python `rosbags`), reading back and comparing bit for bit.

// Each test file uses some of these.
#![allow(dead_code)]

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Once;
use std::sync::atomic::{AtomicUsize, Ordering};

use imu_ar_cli::input::csv::DataError;
use imu_ar_cli::input::frame::{Frame, Skipped};
use imu_ar_cli::input::{bag, mcap as mcap_reader};
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};

/// `bag::read` or `mcap::read`.
pub type Reader = fn(&Path, &str, &mut dyn FnMut(Frame)) -> Result<Skipped, DataError>;

/// Fails, with what to install, when Python cannot import `rosbags`.
pub fn require_rosbags() {
    static CHECK: Once = Once::new();
    CHECK.call_once(|| {
        let ok = Command::new("python3")
            .args(["-c", "import rosbags"])
            .status()
            .is_ok_and(|s| s.success());
        assert!(
            ok,
            "the fixtures of these tests are written by the Python package rosbags: \
             `pip install rosbags` (python3 -c 'import rosbags' failed)"
        );
    });
}

/// An empty directory for one test's files.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("imu-ar-bags-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `n` frames from `seed`: stamps 2.5 ms apart with a jitter, axes of all magnitudes, with
/// negative zeros, subnormals and extremes among them.
pub fn frames(n: usize, seed: u64) -> Vec<Frame> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
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
            let jitter = (rng.next_u32() % 100_000) as i64;
            let stamp_ns = 1_700_000_000_123_456_789 + i as i64 * 2_500_000 + jitter;
            let axes = std::array::from_fn(|_| {
                let r = rng.next_u64();
                if r % 97 == 0 {
                    specials[(r >> 32) as usize % specials.len()]
                } else {
                    let unit = (r >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0;
                    unit * 10f64.powi((r % 9) as i32 - 4)
                }
            });
            Frame { stamp_ns, axes }
        })
        .collect()
}

/// A CSV of `frames` for the script (`{:?}` round-trips every f64).
pub fn write_csv(path: &Path, frames: &[Frame]) {
    let mut s = String::from("t_ns,gx,gy,gz,ax,ay,az\n");
    for f in frames {
        write!(s, "{}", f.stamp_ns).unwrap();
        for v in f.axes {
            write!(s, ",{v:?}").unwrap();
        }
        s.push('\n');
    }
    std::fs::write(path, s).unwrap();
}

/// `write_imu.py OUT FORMAT TOPIC COMPRESSION CSV EXTRA...` into `dir`, the file `name`.
pub fn fixture(dir: &Path, name: &str, args: [&str; 3], csv: &Path, extra: &[&str]) -> PathBuf {
    require_rosbags();
    let out = dir.join(name);
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/write_imu.py");
    let status = Command::new("python3")
        .arg(script)
        .arg(&out)
        .args(args)
        .arg(csv)
        .args(extra)
        .status()
        .expect("run python3");
    assert!(status.success(), "write_imu.py {name} {args:?} {extra:?}");
    out
}

/// `frames` written as `format` with `compression` on `/imu`.
pub fn imu_file(dir: &Path, format: &str, compression: &str, frames: &[Frame]) -> PathBuf {
    let csv = dir.join("frames.csv");
    write_csv(&csv, frames);
    static FILES: AtomicUsize = AtomicUsize::new(0);
    let k = FILES.fetch_add(1, Ordering::Relaxed);
    let name = format!("{k}-{compression}.{}", extension(format));
    fixture(dir, &name, [format, "/imu", compression], &csv, &[])
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
