//! The readers' fuzz corpora (`fuzz/recordings/corpus/<target>/`) replayed on the stable
//! toolchain through the fuzz targets' own checks (`fuzz/recordings/checks.rs`): every input
//! libFuzzer kept, and the inputs of its past findings, read without a panic and with the
//! targets' properties.

#[path = "../../fuzz/recordings/checks.rs"]
mod checks;

use std::alloc::{GlobalAlloc, Layout, System};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The files of one target's corpus, sorted; at least `at_least` of them.
fn corpus(target: &str, at_least: usize) -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/recordings/corpus")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("a corpus entry").path())
        .collect();
    files.sort();
    assert!(
        files.len() >= at_least,
        "{}: {} files",
        dir.display(),
        files.len()
    );
    files
}

/// Replays `target`'s corpus through `check`, naming the input that fails.
fn replay(target: &str, at_least: usize, check: fn(&[u8])) {
    for file in corpus(target, at_least) {
        let data = std::fs::read(&file).expect("a corpus file");
        if let Err(panic) = std::panic::catch_unwind(|| check(&data)) {
            panic!("{}: {panic:?}", file.display());
        }
    }
}

#[test]
fn the_csv_corpus_reads_without_a_panic() {
    replay("csv_column", 600, checks::csv_column);
}

#[test]
fn the_decimal_corpus_reads_as_the_standard_library_reads_it() {
    replay("decimal_number", 20, checks::decimal_number);
}

#[test]
fn the_timing_corpus_gives_rates_and_gaps_the_span_holds() {
    replay("timing_summary", 1500, checks::timing_summary);
}

#[test]
fn the_ros_corpus_reads_without_a_panic() {
    replay("ros_read", 290, checks::ros_read);
}

/// The largest single allocation of this test binary so far, in bytes.
static LARGEST: AtomicUsize = AtomicUsize::new(0);

/// The system allocator, noting the largest request: a corrupt length that a reader allocates
/// before it reads shows here even where the operating system would never touch its pages
/// (libFuzzer's sanitised runs refuse any request above 2 GB).
struct Noting;

// SAFETY: every call is passed on unchanged to the system allocator.
unsafe impl GlobalAlloc for Noting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        LARGEST.fetch_max(layout.size(), Ordering::Relaxed);
        // SAFETY: the caller's contract, passed on.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller's contract, passed on.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        LARGEST.fetch_max(new_size, Ordering::Relaxed);
        // SAFETY: the caller's contract, passed on.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOCATOR: Noting = Noting;

/// No corpus input makes a reader ask for more at once than the largest record a short file
/// may declare (64 MiB, `MIN_RECORD_LIMIT` of the MCAP reader) and a little: among them, the
/// MCAP files whose chunk header declares a 2.5 and a 3.5 GB compression name.
#[test]
fn no_input_allocates_what_its_lengths_merely_declare() {
    for (target, check) in [
        ("csv_column", checks::csv_column as fn(&[u8])),
        ("ros_read", checks::ros_read),
        ("rosbag2_metadata", checks::rosbag2_metadata),
        ("ulog_read", checks::ulog_read),
        ("dataflash_read", checks::dataflash_read),
    ] {
        replay(target, 1, check);
    }
    let largest = LARGEST.load(Ordering::Relaxed);
    assert!(largest <= 80 << 20, "{largest} bytes allocated at once");
}

#[test]
fn the_metadata_corpus_reads_without_a_panic() {
    replay("rosbag2_metadata", 550, checks::rosbag2_metadata);
}

#[test]
fn the_ulog_corpus_reads_without_a_panic() {
    replay("ulog_read", 100, checks::ulog_read);
}

#[test]
fn the_dataflash_corpus_reads_without_a_panic() {
    replay("dataflash_read", 100, checks::dataflash_read);
}
