//! Why a record could not be written or read.

use core::fmt;

use crate::model::ModelError;
use crate::noise::NoiseError;

/// Why bytes are not a record of the type asked for; the checks run in the order of the
/// [module docs](super#decoding), so the first one that fails names the error.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DecodeError {
    /// Fewer bytes than the header (12) or than the length the header states.
    Truncated {
        /// The bytes needed.
        needed: usize,
        /// The bytes given.
        given: usize,
    },
    /// The bytes do not start with the magic `IMAR`.
    Magic,
    /// A layout version this library does not read (it reads [`VERSION`](super::VERSION)).
    Version {
        /// The version byte found.
        stored: u8,
    },
    /// The stated length is shorter than a header and a CRC (16 bytes), or is not the length
    /// the record's kind and orders give.
    Length {
        /// The length the header states.
        stated: usize,
    },
    /// The CRC-32 of the record does not match the one stored in it: the record is damaged
    /// (or was never completely written).
    Crc {
        /// The CRC stored in the record.
        stored: u32,
        /// The CRC of the bytes read.
        computed: u32,
    },
    /// A record of another kind (1 `ArModel<f32, P>`, 2 `ArModel<f64, P>`, 3 `NoiseModel`,
    /// 4 and 5 arrays of `f32` and `f64` AR models).
    Kind {
        /// The kind stored.
        stored: u8,
        /// The kind asked for.
        expected: u8,
    },
    /// A model of another order `P`.
    Order {
        /// The order stored.
        stored: usize,
        /// The order asked for.
        expected: usize,
    },
    /// A noise model of another capacity `G`, an array of another length `N`, or one AR model
    /// with a non-zero `G` field.
    Capacity {
        /// The capacity stored.
        stored: usize,
        /// The capacity asked for.
        expected: usize,
    },
    /// The field at this byte offset breaks the layout: an unused term slot or an absent AR
    /// part that is not all zero bytes, or an AR-part flag other than 0 and 1.
    Field {
        /// Offset of the field in the record.
        offset: usize,
    },
    /// The bytes are intact but make no valid AR model (of an array, the first invalid one): a
    /// NaN or infinite value, a negative variance, a `dt` that is not positive, or a model
    /// that is not stationary.
    Ar(ModelError),
    /// The bytes are intact but make no valid noise model (see
    /// [`NoiseModel::new`](crate::noise::NoiseModel::new)).
    Noise(NoiseError),
}

impl fmt::Display for DecodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Truncated { needed, given } => {
                write!(f, "record truncated: {given} bytes, {needed} needed")
            }
            Self::Magic => f.write_str("not a model record (wrong magic bytes)"),
            Self::Version { stored } => write!(f, "record layout version {stored} not supported"),
            Self::Length { stated } => write!(f, "record length {stated} is invalid"),
            Self::Crc { stored, computed } => write!(
                f,
                "record damaged: CRC-32 0x{computed:08x}, stored 0x{stored:08x}"
            ),
            Self::Kind { stored, expected } => {
                write!(f, "record of kind {stored}, kind {expected} expected")
            }
            Self::Order { stored, expected } => {
                write!(f, "model of order {stored}, order {expected} expected")
            }
            Self::Capacity { stored, expected } => {
                write!(f, "noise model of capacity {stored}, {expected} expected")
            }
            Self::Field { offset } => write!(f, "record field at byte {offset} is invalid"),
            Self::Ar(e) => write!(f, "stored AR model is invalid: {e}"),
            Self::Noise(e) => write!(f, "stored noise model is invalid: {e}"),
        }
    }
}

impl core::error::Error for DecodeError {}

/// Why a model was not encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum EncodeError {
    /// The buffer is shorter than the record.
    Buffer {
        /// The record's length.
        needed: usize,
        /// The buffer's length.
        given: usize,
    },
    /// The AR model is not stationary: a record holds only a model that decodes.
    Ar(ModelError),
    /// The noise model is not one [`NoiseModel::new`](crate::noise::NoiseModel::new) accepts
    /// (a fitted model always is).
    Noise(NoiseError),
}

impl fmt::Display for EncodeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Self::Buffer { needed, given } => {
                write!(f, "buffer of {given} bytes, the record needs {needed}")
            }
            Self::Ar(e) => write!(f, "AR model not stored: {e}"),
            Self::Noise(e) => write!(f, "noise model not stored: {e}"),
        }
    }
}

impl core::error::Error for EncodeError {}
