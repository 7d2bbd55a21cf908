#![doc = include_str!("../README.md")]
//!
//! ## The guides in this documentation
//!
//! The guides linked above are the modules of [`guide`]:
//!
//! - [What is inside](guide::modules)
//! - [Online estimation on the device](guide::estimators)
//! - [The fixed-point lattice stage](guide::fixed_point)
//! - [Temperature](guide::temperature)
//! - [Noise model and Kalman hand-off](guide::noise_model)
//! - [Recordings in, filter parameters out](guide::recordings)
//! - [Sensors](guide::sensors)
//! - [Persistence](guide::persistence)
//! - [Results](guide::results)
//! - [Performance](guide::performance)
//! - [Reliability](guide::reliability)
//! - [Running firmware](guide::firmware)
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod allan;
pub mod batch;
pub mod guide;
pub mod model;
pub mod noise;
pub mod persist;
pub mod recursive;
pub mod scalar;
pub mod sensor;
pub mod sim;
pub mod thermal;

pub use model::{ArModel, GaussMarkov, ModelError};
pub use recursive::Estimator;
pub use scalar::Scalar;
