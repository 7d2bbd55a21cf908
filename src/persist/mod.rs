//! Fitted models that survive a power cycle: a fixed, versioned byte layout with a CRC-32
//! ([`Record`], for [`ArModel<f32, P>`](crate::ArModel), `ArModel<f64, P>`, arrays of them
//! (the axes of an IMU) and [`NoiseModel<P, G>`](crate::noise::NoiseModel)), and a store in NOR flash that a power cut
//! in the middle of a save cannot damage ([`FlashStore`], over `embedded-storage`'s
//! `NorFlash`). No allocation; no panic on any input.
//!
//! ```
//! use imu_ar::ArModel;
//! use imu_ar::persist::{DecodeError, Record};
//!
//! let model = ArModel::new([0.9f32, -0.2, 0.05, 0.01], 1e-4, 0.02, 0.01)?;
//! let mut buf = [0u8; ArModel::<f32, 4>::LEN];
//! assert_eq!(model.encode(&mut buf)?, 44);
//! assert_eq!(ArModel::<f32, 4>::decode(&buf), Ok(model));
//! // Saved at order 4, loaded at order 8: a typed error, never a wrong model.
//! let other = ArModel::<f32, 8>::decode(&buf);
//! assert_eq!(other, Err(DecodeError::Order { stored: 4, expected: 8 }));
//! buf[20] ^= 0x10; // a flipped bit
//! assert!(matches!(ArModel::<f32, 4>::decode(&buf), Err(DecodeError::Crc { .. })));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Layout (version 1)
//!
//! Integers are little-endian and unsigned; values are IEEE 754 bit patterns, little-endian.
//! Every record starts with the same 12-byte header and ends with a CRC-32:
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 0 | 4 | magic `IMAR` (`49 4D 41 52`) |
//! | 4 | 1 | layout version, [`VERSION`] (1) |
//! | 5 | 1 | kind: 1 `ArModel<f32, P>`, 2 `ArModel<f64, P>`, 3 `NoiseModel<P, G>`, 4 `[ArModel<f32, P>; N]`, 5 `[ArModel<f64, P>; N]` |
//! | 6 | 2 | `P`, u16 |
//! | 8 | 2 | `G` of a noise model, `N` of an array, 0 for one AR model; u16 |
//! | 10 | 2 | `L`, the record's length in bytes, header and CRC included, u16 |
//! | 12 | `L - 16` | payload, by kind (below) |
//! | `L - 4` | 4 | CRC-32 of bytes `0..L-4`, u32 (IEEE 802.3, reflected polynomial `0xEDB88320`, initial value and final XOR `0xFFFFFFFF`: zlib's `crc32`) |
//!
//! AR model, `s` = 4 bytes per value (`f32`) or 8 (`f64`); `L = 16 + s (P + 3)`, 44 bytes
//! for `ArModel<f32, 4>`, 72 for `ArModel<f64, 4>`:
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 12 | `s P` | `a_1 .. a_P` ([`ArModel::a`](crate::ArModel::a)) |
//! | `12 + s P` | `s` | innovation variance |
//! | `12 + s (P + 1)` | `s` | mean |
//! | `12 + s (P + 2)` | `s` | `dt`, s |
//!
//! Array of `N >= 1` AR models: their `N` payloads one after the other, `L = 16 + N s (P + 3)`
//! (184 bytes for the six axes' `[ArModel<f32, 4>; 6]`).
//!
//! Noise model, every value `f64`; `L = 88 + 40 G + 8 P`, 200 bytes for `NoiseModel<4, 2>`:
//!
//! | offset | bytes | field |
//! |---|---|---|
//! | 12 | 2 | number of Gauss-Markov terms `n_gm <= G`, u16 |
//! | 14 | 2 | number of oscillators `n_osc <= G`, u16 |
//! | 16 | 4 | AR part: 1 present, 0 absent, u32 |
//! | 20 | 8 | `dt`, s |
//! | 28 | 32 | [`Coefficients`](crate::noise::Coefficients) `Q`, `N`, `K`, `R` |
//! | 60 | `16 G` | `G` slots of [`GmTerm`](crate::noise::GmTerm) (`sigma`, correlation time); slots from `n_gm` on all zero bytes |
//! | `60 + 16 G` | `24 G` | `G` slots of [`Oscillator`](crate::noise::Oscillator) (`sigma`, frequency, decay time); slots from `n_osc` on all zero bytes |
//! | `60 + 40 G` | `8 (P + 3)` | the AR part: `a_1 .. a_P`, variance, mean, `dt`; all zero bytes when absent |
//!
//! A model has exactly one encoding, so a record decoded and encoded again is the same bytes.
//!
//! # Decoding
//!
//! [`Record::decode`] checks, in this order, and returns the first failure as a
//! [`DecodeError`]:
//!
//! 1. the magic ([`DecodeError::Magic`]), at least 12 bytes ([`DecodeError::Truncated`]),
//!    the version ([`DecodeError::Version`]) and `L >= 16` ([`DecodeError::Length`]);
//! 2. at least `L` bytes ([`DecodeError::Truncated`]; bytes after the `L`-th are not read);
//! 3. the CRC-32 ([`DecodeError::Crc`]);
//! 4. the kind, `P`, `G` and `L` of the type asked for ([`DecodeError::Kind`],
//!    [`DecodeError::Order`], [`DecodeError::Capacity`], [`DecodeError::Length`]);
//! 5. the values: zero where the layout says so and a flag of 0 or 1
//!    ([`DecodeError::Field`]); then the model's own constructor
//!    ([`ArModel::new`](crate::ArModel::new) and stationarity, [`DecodeError::Ar`];
//!    [`NoiseModel::new`](crate::noise::NoiseModel::new), [`DecodeError::Noise`]).
//!
//! [`Record::encode`] refuses what decoding would refuse, so every record written decodes.
//!
//! # Flash
//!
//! [`FlashStore`] keeps a log of records in two slots of erase units with sequence numbers,
//! and documents what each fault leaves. The entry of an `ArModel<f32, 4>` is 52 bytes (the
//! record and an 8-byte sequence number), padded to the flash's `WRITE_SIZE`.

mod codec;
mod crc32;
mod error;
mod store;

pub use error::{DecodeError, EncodeError};
pub use store::{FlashStore, StoreError};

/// The layout version this library writes and reads.
pub const VERSION: u8 = 1;

/// The first four bytes of every record.
pub const MAGIC: [u8; 4] = *b"IMAR";

pub(crate) mod sealed {
    /// What identifies a record type in the header; implemented only here.
    pub trait Sealed {
        /// The kind byte.
        const KIND: u8;
        /// `P`.
        const ORDER: usize;
        /// `G` (0 for an AR model).
        const CAPACITY: usize;
    }
}

/// A model with a byte layout: [`ArModel<f32, P>`](crate::ArModel), `ArModel<f64, P>`,
/// arrays `[ArModel<T, P>; N]` of either (one record for the axes of an IMU, saved and loaded
/// together) and [`NoiseModel<P, G>`](crate::noise::NoiseModel); see the
/// [module docs](self) for the layouts. Implemented by this crate only.
pub trait Record: Sized + sealed::Sealed {
    /// The record's length in bytes (`L`): `[0u8; ArModel::<f32, 4>::LEN]` holds one.
    const LEN: usize;

    /// Writes the record into `buf[..LEN]`; returns `LEN`.
    ///
    /// # Errors
    ///
    /// [`EncodeError::Buffer`] for a buffer shorter than [`Record::LEN`];
    /// [`EncodeError::Ar`] for an AR model (of an array, the first) that is not stationary; [`EncodeError::Noise`] for
    /// a noise model [`NoiseModel::new`](crate::noise::NoiseModel::new) refuses (a fitted
    /// one never is). `buf` is untouched then.
    fn encode(&self, buf: &mut [u8]) -> Result<usize, EncodeError>;

    /// The model in the record at the start of `bytes`, after every check of the
    /// [module docs](self#decoding).
    ///
    /// # Errors
    ///
    /// The first check that fails, as a [`DecodeError`].
    fn decode(bytes: &[u8]) -> Result<Self, DecodeError>;
}
