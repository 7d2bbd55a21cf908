//! Estimators that see the whole record at once.
//!
//! - [`levinson_durbin`]: the AR models of every order `1..=P` that match given autocovariances
//!   `r(0..=P)` (Levinson 1947; Durbin 1960).

mod levinson;

pub use levinson::{Levinson, LevinsonError, levinson_durbin};
