//! The integration tests of `imu-ar-host`, one module per subject, in one test binary (one
//! link, one set of generic instances): `cargo test -p imu-ar-host --test host`, and one
//! subject with a filter, e.g. `cargo test -p imu-ar-host --test host -- differential::`.
//!
//! `common` holds the checks the chip readers' tests share; `sim` is the register-level
//! simulator of the chips.

mod common;
mod sim;

mod batch;
mod campaign;
mod differential;
mod estimator_hostile;
mod fixed;
mod fixed_edges;
mod gate;
mod levinson;
mod model;
mod noise;
mod noise_drift;
mod noise_edges;
mod noise_kalman;
mod online_hostile;
mod persist;
mod prior;
mod properties;
mod recursive_behaviour;
mod recursive_edges;
mod recursive_exact;
mod recursive_f32;
mod redteam_cancel;
mod redteam_sweep;
mod redteam_targeted;
mod sensor;
mod sensor_faults;
mod sensor_icm42688;
mod sensor_mpu6050;
mod sftf;
mod soak;
mod thermal;
