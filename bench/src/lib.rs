//! The host benchmark of `imu-ar` (`benches/per_sample.rs`): `cargo bench -p imu-ar-bench
//! --bench per_sample`. This library is empty; the package exists so that the bench's
//! dependency, criterion, stays out of `cargo test --workspace`.
