//! The guides: one page per topic, from `docs/` in the repository. Their examples are tested
//! with the crate's documentation.
//!
//! - [`modules`]: what is inside, the conventions, the repository's layout
//! - [`estimators`]: online estimation on the device, `f32` accuracy, the SFTF head to head,
//!   fixed point, batch against recursive
//! - [`fixed_point`]: the fixed-point lattice stage, what it costs and why it is written as it is
//! - [`temperature`]: the thermal stage
//! - [`noise_model`]: the composite noise model and the Kalman hand-off
//! - [`recordings`]: recordings in, filter parameters out, and the `imu-ar` host tool
//! - [`sensors`]: the readers and what they guarantee
//! - [`persistence`]: models that survive a power cycle
//! - [`results`]: the paper's comparison, rerun, and its plots
//! - [`performance`]: on the target and on the host
//! - [`reliability`]: what is tested
//! - [`firmware`]: running firmware on QEMU and on a real board
//!
//! Links between the pages are relative to `docs/`: they work in the repository.

#[doc = include_str!("../docs/modules.md")]
pub mod modules {}

#[doc = include_str!("../docs/estimators.md")]
pub mod estimators {}

#[doc = include_str!("../docs/fixed-point.md")]
pub mod fixed_point {}

#[doc = include_str!("../docs/temperature.md")]
pub mod temperature {}

#[doc = include_str!("../docs/noise-model.md")]
pub mod noise_model {}

#[doc = include_str!("../docs/recordings.md")]
pub mod recordings {}

#[doc = include_str!("../docs/sensors.md")]
pub mod sensors {}

#[doc = include_str!("../docs/persistence.md")]
pub mod persistence {}

#[doc = include_str!("../docs/results.md")]
pub mod results {}

#[doc = include_str!("../docs/performance.md")]
pub mod performance {}

#[doc = include_str!("../docs/reliability.md")]
pub mod reliability {}

#[doc = include_str!("../docs/firmware.md")]
pub mod firmware {}
