//! The record layouts of the [module docs](super): header, payloads and CRC.
//!
//! Every read and write goes through [`In`] and [`Out`], which index with `get` and never
//! panic; lengths are checked once, up front.

use crate::Scalar;
use crate::model::ArModel;
use crate::noise::{Coefficients, GmTerm, NoiseError, NoiseModel, Oscillator};

use super::crc32::crc32;
use super::sealed::Sealed;
use super::{DecodeError, EncodeError, MAGIC, Record, VERSION};

/// Bytes of the header.
pub(super) const HEADER: usize = 12;
/// Bytes of the CRC.
const CRC: usize = 4;
/// The shortest record: a header and a CRC.
pub(super) const MIN_LEN: usize = HEADER + CRC;
/// Offset of the noise record's AR-part flag.
const AR_FLAG: usize = 16;

/// A record's header, read by [`Head::read`].
#[derive(Clone, Copy, Debug)]
pub(super) struct Head {
    kind: u8,
    order: usize,
    capacity: usize,
    /// The record's length `L`, at least [`MIN_LEN`].
    pub(super) len: usize,
}

impl Head {
    /// The header at the start of `bytes`, with the checks that come before the CRC: the
    /// magic, at least a header's bytes, the version and a length of at least [`MIN_LEN`].
    pub(super) fn read(bytes: &[u8]) -> Result<Self, DecodeError> {
        let n = bytes.len().min(MAGIC.len());
        if bytes.get(..n) != MAGIC.get(..n) {
            return Err(DecodeError::Magic);
        }
        let Some(&[_, _, _, _, version, kind, p0, p1, g0, g1, l0, l1]) =
            bytes.first_chunk::<HEADER>()
        else {
            return Err(DecodeError::Truncated {
                needed: HEADER,
                given: bytes.len(),
            });
        };
        if version != VERSION {
            return Err(DecodeError::Version { stored: version });
        }
        let len = usize::from(u16::from_le_bytes([l0, l1]));
        if len < MIN_LEN {
            return Err(DecodeError::Length { stated: len });
        }
        Ok(Self {
            kind,
            order: usize::from(u16::from_le_bytes([p0, p1])),
            capacity: usize::from(u16::from_le_bytes([g0, g1])),
            len,
        })
    }

    /// Whether the header is that of an `M`: kind, order, capacity, then length.
    pub(super) fn expect<M: Record>(&self) -> Result<(), DecodeError> {
        if self.kind != M::KIND {
            Err(DecodeError::Kind {
                stored: self.kind,
                expected: M::KIND,
            })
        } else if self.order != M::ORDER {
            Err(DecodeError::Order {
                stored: self.order,
                expected: M::ORDER,
            })
        } else if self.capacity != M::CAPACITY {
            Err(DecodeError::Capacity {
                stored: self.capacity,
                expected: M::CAPACITY,
            })
        } else if self.len != M::LEN {
            Err(DecodeError::Length { stated: self.len })
        } else {
            Ok(())
        }
    }
}

/// The record at the start of `bytes` with its header, if it is intact: [`Head::read`], then
/// `L` bytes, then the CRC.
pub(super) fn open(bytes: &[u8]) -> Result<(Head, &[u8]), DecodeError> {
    let head = Head::read(bytes)?;
    let Some(record) = bytes.get(..head.len) else {
        return Err(DecodeError::Truncated {
            needed: head.len,
            given: bytes.len(),
        });
    };
    let Some((body, stored)) = record.split_last_chunk::<CRC>() else {
        return Err(DecodeError::Length { stated: head.len });
    };
    let (stored, computed) = (u32::from_le_bytes(*stored), crc32(body));
    if stored != computed {
        return Err(DecodeError::Crc { stored, computed });
    }
    Ok((head, record))
}

/// `L` fits the header's 16-bit length field: a compile-time error for an order so large that
/// the record would not.
const fn fits<M: Record>() {
    const {
        assert!(
            M::LEN <= u16::MAX as usize,
            "the record is longer than 65535 bytes"
        )
    };
}

fn u16_le(v: usize) -> [u8; 2] {
    u16::try_from(v).unwrap_or(u16::MAX).to_le_bytes()
}

/// A record being written: the header, then the payload with [`Out::put`], then
/// [`Out::finish`] appends the CRC.
struct Out<'a> {
    buf: &'a mut [u8],
    pos: usize,
}

impl<'a> Out<'a> {
    /// The header of an `M` at the start of `buf`.
    fn begin<M: Record>(buf: &'a mut [u8]) -> Result<Self, EncodeError> {
        fits::<M>();
        let given = buf.len();
        let Some(buf) = buf.get_mut(..M::LEN) else {
            return Err(EncodeError::Buffer {
                needed: M::LEN,
                given,
            });
        };
        let mut out = Self { buf, pos: 0 };
        out.put(&MAGIC);
        out.put(&[VERSION, M::KIND]);
        out.put(&u16_le(M::ORDER));
        out.put(&u16_le(M::CAPACITY));
        out.put(&u16_le(M::LEN));
        Ok(out)
    }

    fn put(&mut self, bytes: &[u8]) {
        let end = self.pos.saturating_add(bytes.len());
        if let Some(dst) = self.buf.get_mut(self.pos..end) {
            for (d, s) in dst.iter_mut().zip(bytes) {
                *d = *s;
            }
        }
        self.pos = end;
    }

    fn zeros(&mut self, n: usize) {
        for _ in 0..n {
            self.put(&[0]);
        }
    }

    fn f64(&mut self, v: f64) {
        self.put(&v.to_le_bytes());
    }

    /// Appends the CRC of everything before it; returns the record's length.
    fn finish(mut self) -> usize {
        let crc = crc32(self.buf.get(..self.pos).unwrap_or(&[]));
        self.put(&crc.to_le_bytes());
        self.pos
    }
}

/// A record being read, from just after its header.
struct In<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> In<'a> {
    /// The payload of the `M` at the start of `bytes`: [`open`], then [`Head::expect`].
    fn open<M: Record>(bytes: &'a [u8]) -> Result<Self, DecodeError> {
        fits::<M>();
        let (head, record) = open(bytes)?;
        head.expect::<M>()?;
        Ok(Self {
            bytes: record,
            pos: HEADER,
        })
    }

    /// The next `N` bytes (zeros past the end, which the length checks rule out).
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let chunk = self
            .bytes
            .get(self.pos..)
            .and_then(|b| b.first_chunk::<N>());
        self.pos = self.pos.saturating_add(N);
        chunk.copied().unwrap_or([0; N])
    }

    fn f64(&mut self) -> f64 {
        f64::from_le_bytes(self.take())
    }

    fn count(&mut self) -> usize {
        usize::from(u16::from_le_bytes(self.take()))
    }
}

macro_rules! ar_record {
    ($t:ty, $kind:expr, $array_kind:expr, $size:expr) => {
        impl<const P: usize> Sealed for ArModel<$t, P> {
            const KIND: u8 = $kind;
            const ORDER: usize = P;
            const CAPACITY: usize = 0;
        }

        impl<const P: usize> Record for ArModel<$t, P> {
            const LEN: usize = MIN_LEN + $size * (P + 3);

            fn encode(&self, buf: &mut [u8]) -> Result<usize, EncodeError> {
                self.reflection().map_err(EncodeError::Ar)?;
                let mut out = Out::begin::<Self>(buf)?;
                put_ar(&mut out, self);
                Ok(out.finish())
            }

            fn decode(bytes: &[u8]) -> Result<Self, DecodeError> {
                take_ar(&mut In::open::<Self>(bytes)?)
            }
        }

        impl<const P: usize, const N: usize> Sealed for [ArModel<$t, P>; N] {
            const KIND: u8 = $array_kind;
            const ORDER: usize = P;
            const CAPACITY: usize = N;
        }

        impl<const P: usize, const N: usize> Record for [ArModel<$t, P>; N] {
            const LEN: usize = MIN_LEN + N * $size * (P + 3);

            fn encode(&self, buf: &mut [u8]) -> Result<usize, EncodeError> {
                const { assert!(N > 0, "an array of at least one model") };
                for m in self {
                    m.reflection().map_err(EncodeError::Ar)?;
                }
                let mut out = Out::begin::<Self>(buf)?;
                self.iter().for_each(|m| put_ar(&mut out, m));
                Ok(out.finish())
            }

            fn decode(bytes: &[u8]) -> Result<Self, DecodeError> {
                const { assert!(N > 0, "an array of at least one model") };
                let mut r = In::open::<Self>(bytes)?;
                let first = take_ar(&mut r)?;
                let mut error = None;
                let models = core::array::from_fn(|i| match i {
                    0 => first,
                    _ => take_ar(&mut r).unwrap_or_else(|e| {
                        error.get_or_insert(e);
                        first
                    }),
                });
                error.map_or(Ok(models), Err)
            }
        }

        impl Wire for $t {
            fn put(self, out: &mut Out<'_>) {
                out.put(&self.to_le_bytes());
            }

            fn take(r: &mut In<'_>) -> Self {
                <$t>::from_le_bytes(r.take())
            }
        }
    };
}

/// A value as the layouts store it: IEEE 754, little-endian.
trait Wire: Scalar {
    fn put(self, out: &mut Out<'_>);
    fn take(r: &mut In<'_>) -> Self;
}

/// An AR payload: `a_1..a_P`, variance, mean, `dt`.
fn put_ar<T: Wire, const P: usize>(out: &mut Out<'_>, m: &ArModel<T, P>) {
    let values = [m.noise_variance(), m.mean(), m.dt()];
    m.a().iter().chain(&values).for_each(|v| v.put(out));
}

/// The AR payload at the reader, validated: [`ArModel::new`], then stationarity.
fn take_ar<T: Wire, const P: usize>(r: &mut In<'_>) -> Result<ArModel<T, P>, DecodeError> {
    let a = core::array::from_fn(|_| T::take(r));
    let [variance, mean, dt] = core::array::from_fn(|_| T::take(r));
    let model = ArModel::new(a, variance, mean, dt).map_err(DecodeError::Ar)?;
    model.reflection().map_err(DecodeError::Ar)?;
    Ok(model)
}

ar_record!(f32, 1, 4, 4);
ar_record!(f64, 2, 5, 8);

impl<const P: usize, const G: usize> Sealed for NoiseModel<P, G> {
    const KIND: u8 = 3;
    const ORDER: usize = P;
    const CAPACITY: usize = G;
}

impl<const P: usize, const G: usize> Record for NoiseModel<P, G> {
    const LEN: usize = 88 + 40 * G + 8 * P;

    fn encode(&self, buf: &mut [u8]) -> Result<usize, EncodeError> {
        self.validate().map_err(EncodeError::Noise)?;
        let mut out = Out::begin::<Self>(buf)?;
        let (gm, osc) = (self.gauss_markov(), self.oscillators());
        out.put(&u16_le(gm.len()));
        out.put(&u16_le(osc.len()));
        out.put(&u32::from(self.ar().is_some()).to_le_bytes());
        let c = self.coefficients();
        for v in [self.dt(), c.quantization, c.white, c.random_walk, c.ramp] {
            out.f64(v);
        }
        // Unused slots as the default term: all bytes zero.
        for i in 0..G {
            let t = gm.get(i).copied().unwrap_or_default();
            for v in [t.sigma, t.correlation_time] {
                out.f64(v);
            }
        }
        for i in 0..G {
            let o = osc.get(i).copied().unwrap_or_default();
            for v in [o.sigma, o.frequency, o.decay_time] {
                out.f64(v);
            }
        }
        match self.ar() {
            Some(ar) => {
                let values = [ar.noise_variance(), ar.mean(), ar.dt()];
                ar.a().iter().chain(&values).for_each(|v| out.f64(*v));
            }
            None => out.zeros(8 * (P + 3)),
        }
        Ok(out.finish())
    }

    fn decode(bytes: &[u8]) -> Result<Self, DecodeError> {
        let mut r = In::open::<Self>(bytes)?;
        let (n_gm, n_osc) = (r.count(), r.count());
        for requested in [n_gm, n_osc] {
            if requested > G {
                return Err(DecodeError::Noise(NoiseError::Budget {
                    requested,
                    capacity: G,
                }));
            }
        }
        let flag = u32::from_le_bytes(r.take());
        if flag > 1 {
            return Err(DecodeError::Field { offset: AR_FLAG });
        }
        let [dt, quantization, white, random_walk, ramp] = core::array::from_fn(|_| r.f64());
        let mut gm = [GmTerm::default(); G];
        for (i, slot) in (0..G).zip(gm.iter_mut()) {
            let offset = r.pos;
            let [sigma, correlation_time] = core::array::from_fn(|_| r.f64());
            if i >= n_gm && !zero(&[sigma, correlation_time]) {
                return Err(DecodeError::Field { offset });
            }
            *slot = GmTerm {
                sigma,
                correlation_time,
            };
        }
        let mut osc = [Oscillator::default(); G];
        for (i, slot) in (0..G).zip(osc.iter_mut()) {
            let offset = r.pos;
            let [sigma, frequency, decay_time] = core::array::from_fn(|_| r.f64());
            if i >= n_osc && !zero(&[sigma, frequency, decay_time]) {
                return Err(DecodeError::Field { offset });
            }
            *slot = Oscillator {
                sigma,
                frequency,
                decay_time,
            };
        }
        let offset = r.pos;
        let a: [f64; P] = core::array::from_fn(|_| r.f64());
        let rest: [f64; 3] = core::array::from_fn(|_| r.f64());
        let ar = if flag == 1 {
            let [variance, mean, ar_dt] = rest;
            let ar = ArModel::new(a, variance, mean, ar_dt);
            Some(ar.map_err(|e| DecodeError::Noise(NoiseError::Ar(e)))?)
        } else if zero(&a) && zero(&rest) {
            None
        } else {
            return Err(DecodeError::Field { offset });
        };
        let coefficients = Coefficients {
            quantization,
            white,
            random_walk,
            ramp,
        };
        let (gm, osc) = (gm.get(..n_gm), osc.get(..n_osc));
        let model = NoiseModel::new(dt, coefficients, gm.unwrap_or(&[]), osc.unwrap_or(&[]), ar);
        model.map_err(DecodeError::Noise)
    }
}

/// Whether every value is `+0.0` (all bytes zero).
fn zero(values: &[f64]) -> bool {
    values.iter().all(|v| v.to_bits() == 0)
}
