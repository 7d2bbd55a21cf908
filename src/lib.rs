#![doc = include_str!("../README.md")]
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod allan;
pub mod batch;
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
