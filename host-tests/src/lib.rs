//! Host companion of `imu-ar`: the independent f64 reference every core is tested against,
//! the seeded and real test records, the differential check of the fixed-point lattice, and
//! a NOR flash in RAM with injected power cuts for the persistence tests.
//!
//! The reference is a direct solve of the problem an estimator claims to solve (dense linear
//! algebra from `nalgebra`), never the library's own recursion instantiated at `f64`.
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod campaign;
pub mod composite;
pub mod crc;
pub mod differential;
pub mod fixtures;
pub mod flash;
pub mod reference;
pub mod thermal;
