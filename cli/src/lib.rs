//! The `imu-ar` command-line tool: AR models, order criteria, Allan deviation and the Kalman
//! hand-off of recorded sensor logs, computed by the estimators of the `imu-ar` library.
//!
//! One module per command ([`fit`], [`order`], [`adev`], [`compare`], [`report`], [`kalman`],
//! [`parity`], [`simulate`], [`noise`]), each with its arguments (`Args`), a `run` that checks them and
//! returns a typed result, and that result's text. What the commands share: [`input`] reads a
//! record ([`input::csv`] is the CSV reader), [`method`] names the estimators, [`predict`] runs
//! them for `compare` and `report`, [`output`] prints a result as JSON or text, [`error`] is
//! the one-line error. [`thermal`] fits the autopilots' thermal calibrations (bins, a robust cubic,
//! PX4's and ArduPilot's parameters and corrections). The binary (`src/main.rs`) parses the
//! command line and dispatches.
#![deny(missing_docs)]
#![forbid(unsafe_code)]

pub mod adev;
pub mod characterise;
pub mod chart;
pub mod compare;
pub mod error;
pub mod export;
pub mod fit;
pub mod input;
pub mod kalman;
pub mod method;
pub mod noise;
pub mod order;
pub mod output;
pub mod parity;
pub mod predict;
pub mod report;
pub mod simulate;
pub mod thermal;
