//! The readers' fuzz corpora (`fuzz/recordings/corpus/<target>/`) replayed on the stable
//! toolchain through the fuzz targets' own checks (`fuzz/recordings/checks.rs`): every input
//! libFuzzer kept, and the inputs of its past findings, read without a panic and with the
//! targets' properties.

#[path = "../../fuzz/recordings/checks.rs"]
mod checks;

use std::path::{Path, PathBuf};

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
fn the_ros_corpus_reads_without_a_panic() {
    replay("ros_read", 290, checks::ros_read);
}

/// Two MCAP inputs on which the sanitised `ros_read` runs out of its 2 GB: read here (no limit)
/// without a panic; their allocation is still to be bounded.
#[test]
fn the_inputs_that_exhaust_the_fuzzers_memory_read_without_a_panic() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../fuzz/recordings/oom");
    for file in std::fs::read_dir(dir)
        .expect("the folder")
        .map(|e| e.expect("an entry").path())
    {
        checks::ros_read(&std::fs::read(file).expect("the file"));
    }
}

#[test]
fn the_metadata_corpus_reads_without_a_panic() {
    replay("rosbag2_metadata", 550, checks::rosbag2_metadata);
}
