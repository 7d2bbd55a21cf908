//! The tests of the `imu-ar` tool, one module per subject, in one test binary (one link):
//! `cargo test -p imu-ar-cli --test cli`, and one subject with a filter, e.g.
//! `cargo test -p imu-ar-cli --test cli -- bags::`.
//!
//! `common` runs the tool and checks its output; `ros` holds the committed ROS fixtures and the
//! frames they hold.

mod common;
mod ros;

mod arguments;
mod bags;
mod characterise;
mod edges;
mod export;
mod hostile;
mod misuse;
mod noise;
mod outputs;
mod recordings;
mod report;
mod report_prior;
mod streams;
mod thermal;
