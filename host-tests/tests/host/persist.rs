//! The persisted layouts of `imu_ar::persist`: bit-exact round trips of fixed and random valid
//! models, the layout pinned byte by byte, every single-bit flip and every truncation of a
//! record rejected, 10,000 random byte strings rejected, intact records of invalid models
//! rejected with the model's own error; the flash store (`persist/flash.rs`) against a NOR
//! flash in RAM with power cuts at every byte of a save; and records written by another
//! encoder from the documented layout (`persist/seeds.rs`).

#[path = "persist/arrays.rs"]
mod arrays;
#[path = "persist/flash.rs"]
mod flash;
#[path = "persist/seeds.rs"]
mod seeds;

use imu_ar::ArModel;
use imu_ar::model::ModelError;
use imu_ar::noise::{Coefficients, GmTerm, NoiseError, NoiseModel, Oscillator};
use imu_ar::persist::{DecodeError, EncodeError, Record};
use imu_ar_host::crc::{crc32, reseal};
use proptest::prelude::*;

fn encode<M: Record>(m: &M) -> Vec<u8> {
    let mut buf = vec![0u8; M::LEN];
    assert_eq!(m.encode(&mut buf), Ok(M::LEN));
    buf
}

/// `a_1..a_P` of the stationary model with reflection coefficients `k` (the step-up
/// recursion, `a_j^(m) = a_j^(m-1) - k_m a_(m-j)^(m-1)`, `a_m^(m) = k_m`).
fn step_up<const P: usize>(k: &[f64]) -> [f64; P] {
    let mut a = [0.0; P];
    for (m, &km) in k.iter().enumerate().take(P) {
        let prev = a;
        for j in 0..m {
            a[j] = prev[j] - km * prev[m - 1 - j];
        }
        a[m] = km;
    }
    a
}

fn ar_bits<const P: usize>(m: &ArModel<f64, P>) -> Vec<u64> {
    let mut v: Vec<u64> = m.a().iter().map(|x| x.to_bits()).collect();
    v.extend([m.noise_variance(), m.mean(), m.dt()].map(f64::to_bits));
    v
}

/// Every field of a noise model as bits, the counts included.
fn noise_bits<const P: usize, const G: usize>(m: &NoiseModel<P, G>) -> Vec<u64> {
    let c = m.coefficients();
    let mut v = vec![m.gauss_markov().len() as u64, m.oscillators().len() as u64];
    v.extend([m.dt(), c.quantization, c.white, c.random_walk, c.ramp].map(f64::to_bits));
    for t in m.gauss_markov() {
        v.extend([t.sigma, t.correlation_time].map(f64::to_bits));
    }
    for o in m.oscillators() {
        v.extend([o.sigma, o.frequency, o.decay_time].map(f64::to_bits));
    }
    v.extend(m.ar().map(ar_bits).unwrap_or_default());
    v
}

fn sample_noise() -> NoiseModel<4, 2> {
    let c = Coefficients {
        quantization: 1e-5,
        white: 3e-3,
        random_walk: 2e-5,
        ramp: 0.0,
    };
    let gm = [GmTerm {
        sigma: 4e-3,
        correlation_time: 25.0,
    }];
    let osc = [Oscillator {
        sigma: 1e-3,
        frequency: 7.5,
        decay_time: 10.0 / 7.5,
    }];
    let ar = ArModel::new([0.5, -0.2, 0.1, 0.05], 2e-6, 0.0, 0.01).unwrap();
    NoiseModel::new(0.01, c, &gm, &osc, Some(ar)).unwrap()
}

#[test]
fn layout_is_pinned_byte_by_byte() {
    let m = ArModel::new([0.5f32], 0.25, -1.0, 0.01).unwrap();
    let want: [u8; 32] = [
        0x49, 0x4d, 0x41, 0x52, 1, 1, 1, 0, 0, 0, 32, 0, // magic, version, kind, P, G, L
        0x00, 0x00, 0x00, 0x3f, 0x00, 0x00, 0x80, 0x3e, // a_1 = 0.5, variance 0.25
        0x00, 0x00, 0x80, 0xbf, 0x0a, 0xd7, 0x23, 0x3c, // mean -1, dt 0.01
        0xcb, 0x49, 0x3f, 0x54, // CRC-32 0x543f49cb (Python's zlib.crc32)
    ];
    assert_eq!(encode(&m), want);
    assert_eq!(crc32(&want[..28]), 0x543f_49cb);
    assert_eq!(
        [
            ArModel::<f32, 4>::LEN,
            ArModel::<f64, 4>::LEN,
            NoiseModel::<4, 2>::LEN
        ],
        [44, 72, 200]
    );
    // The noise layout's offsets: counts, flag, dt, coefficients, slots, AR part.
    let bytes = encode(&sample_noise());
    assert_eq!(
        &bytes[..12],
        &[0x49, 0x4d, 0x41, 0x52, 1, 3, 4, 0, 2, 0, 200, 0]
    );
    assert_eq!(&bytes[12..20], &[1, 0, 1, 0, 1, 0, 0, 0]);
    let f = |at: usize| f64::from_le_bytes(bytes[at..at + 8].try_into().unwrap());
    assert_eq!(
        [f(20), f(28), f(36), f(44), f(52)],
        [0.01, 1e-5, 3e-3, 2e-5, 0.0]
    );
    assert_eq!([f(60), f(68), f(76), f(84)], [4e-3, 25.0, 0.0, 0.0]);
    assert_eq!([f(92), f(100), f(108)], [1e-3, 7.5, 10.0 / 7.5]);
    assert!(
        bytes[116..140].iter().all(|b| *b == 0),
        "unused oscillator slot"
    );
    assert_eq!([f(140), f(164), f(172), f(180)], [0.5, 0.05, 2e-6, 0.0]);
    assert_eq!(f(188), 0.01);
    assert_eq!(crc32(&bytes[..196]).to_le_bytes(), bytes[196..]);
}

#[test]
fn fixed_models_round_trip_bit_for_bit() {
    let f32s = ArModel::new([2.7607f32, -3.8106, 2.6535, -0.9238], 1.0, -3.5, 0.005).unwrap();
    let back = ArModel::<f32, 4>::decode(&encode(&f32s)).unwrap();
    assert_eq!(back.a().map(f32::to_bits), f32s.a().map(f32::to_bits));
    let f64s = ArModel::new([0.999f64, -1e-300, 5e-324, -0.0], -0.0, 1e300, 1e-9).unwrap();
    let back = ArModel::<f64, 4>::decode(&encode(&f64s)).unwrap();
    assert_eq!(ar_bits(&back), ar_bits(&f64s));
    let noise = sample_noise();
    let back = NoiseModel::<4, 2>::decode(&encode(&noise)).unwrap();
    assert_eq!(noise_bits(&back), noise_bits(&noise));
    assert_eq!(back, noise);
    // Without AR part, terms or oscillators.
    let empty = NoiseModel::<4, 2>::new(1.0, Coefficients::default(), &[], &[], None).unwrap();
    let back = NoiseModel::<4, 2>::decode(&encode(&empty)).unwrap();
    assert_eq!((back.ar(), back.gauss_markov().len()), (None, 0));
    assert_eq!(back, empty);
}

/// A record's name, its bytes, and whether bytes decode as its type.
type Sample = (&'static str, Vec<u8>, fn(&[u8]) -> bool);

/// Records of each kind, to damage.
fn records() -> Vec<Sample> {
    let ar32 = ArModel::new([0.9f32, -0.3, 0.1, 0.02], 1e-4, 0.1, 0.01).unwrap();
    let ar64 = ArModel::new([0.9f64, -0.3, 0.1, 0.02], 1e-4, 0.1, 0.01).unwrap();
    vec![
        ("ar f32", encode(&ar32), |b| {
            ArModel::<f32, 4>::decode(b).is_ok()
        }),
        ("ar f64", encode(&ar64), |b| {
            ArModel::<f64, 4>::decode(b).is_ok()
        }),
        ("noise", encode(&sample_noise()), |b| {
            NoiseModel::<4, 2>::decode(b).is_ok()
        }),
    ]
}

#[test]
fn every_single_bit_flip_is_rejected() {
    for (name, record, decodes) in records() {
        assert!(decodes(&record), "{name}: the intact record");
        for bit in 0..record.len() * 8 {
            let mut damaged = record.clone();
            damaged[bit / 8] ^= 1 << (bit % 8);
            assert!(!decodes(&damaged), "{name}: bit {bit} flipped and accepted");
        }
    }
}

#[test]
fn every_truncation_is_rejected() {
    for (name, record, decodes) in records() {
        for n in 0..record.len() {
            assert!(
                !decodes(&record[..n]),
                "{name}: the first {n} bytes accepted"
            );
        }
        // Bytes after the record are not read.
        let mut longer = record.clone();
        longer.extend([0xA5; 9]);
        assert!(decodes(&longer), "{name} with trailing bytes");
    }
    let r = encode(&ArModel::new([0.5f32], 1.0, 0.0, 1.0).unwrap());
    let got = ArModel::<f32, 1>::decode(&r[..31]);
    assert_eq!(
        got,
        Err(DecodeError::Truncated {
            needed: 32,
            given: 31
        })
    );
    let got = ArModel::<f32, 1>::decode(&r[..5]);
    assert_eq!(
        got,
        Err(DecodeError::Truncated {
            needed: 12,
            given: 5
        })
    );
}

#[test]
fn header_errors_are_typed() {
    let r = encode(&ArModel::new([0.5f32, 0.1], 1.0, 0.0, 1.0).unwrap());
    let mut bad = r.clone();
    bad[0] = b'J';
    assert_eq!(ArModel::<f32, 2>::decode(&bad), Err(DecodeError::Magic));
    bad = r.clone();
    bad[4] = 2;
    assert_eq!(
        ArModel::<f32, 2>::decode(&bad),
        Err(DecodeError::Version { stored: 2 })
    );
    bad = r.clone();
    bad[10] = 15;
    assert_eq!(
        ArModel::<f32, 2>::decode(&bad),
        Err(DecodeError::Length { stated: 15 })
    );
    bad = r.clone();
    bad[13] ^= 0x40;
    let got = ArModel::<f32, 2>::decode(&bad);
    assert!(matches!(got, Err(DecodeError::Crc { .. })), "{got:?}");
    // Intact records of another type.
    let kind = |stored, expected| Some(DecodeError::Kind { stored, expected });
    assert_eq!(ArModel::<f64, 2>::decode(&r).err(), kind(1, 2));
    assert_eq!(NoiseModel::<2, 1>::decode(&r).err(), kind(1, 3));
    let noise = encode(&sample_noise());
    assert_eq!(ArModel::<f32, 4>::decode(&noise).err(), kind(3, 1));
    for (q, got) in [
        (1, ArModel::<f32, 1>::decode(&r).err()),
        (3, ArModel::<f32, 3>::decode(&r).err()),
        (8, ArModel::<f32, 8>::decode(&r).err()),
    ] {
        assert_eq!(
            got,
            Some(DecodeError::Order {
                stored: 2,
                expected: q
            })
        );
    }
    let got = NoiseModel::<4, 3>::decode(&noise);
    assert_eq!(
        got,
        Err(DecodeError::Capacity {
            stored: 2,
            expected: 3
        })
    );
    assert_eq!(
        NoiseModel::<5, 2>::decode(&noise),
        Err(DecodeError::Order {
            stored: 4,
            expected: 5
        })
    );
    // A length field that disagrees with the kind and orders, CRC intact.
    let mut longer = r.clone();
    longer.splice(r.len() - 4..r.len() - 4, [0u8; 4]);
    longer[10] = longer.len() as u8;
    reseal(&mut longer);
    let stated = longer.len();
    assert_eq!(
        ArModel::<f32, 2>::decode(&longer),
        Err(DecodeError::Length { stated })
    );
    // Every error reads as a sentence.
    for e in [DecodeError::Magic, DecodeError::Field { offset: 16 }] {
        assert!(!e.to_string().is_empty());
    }
}

/// An AR f32 record of order 1 with these values, resealed.
fn ar1_record(values: [f32; 4]) -> Vec<u8> {
    let mut r = encode(&ArModel::new([0.5f32], 1.0, 0.0, 1.0).unwrap());
    for (i, v) in values.iter().enumerate() {
        r[12 + 4 * i..16 + 4 * i].copy_from_slice(&v.to_le_bytes());
    }
    reseal(&mut r);
    r
}

#[test]
fn intact_records_of_invalid_ar_models_are_the_models_errors() {
    let cases = [
        ([f32::NAN, 1.0, 0.0, 1.0], ModelError::NonFinite),
        ([0.5, f32::INFINITY, 0.0, 1.0], ModelError::NonFinite),
        ([0.5, 1.0, f32::NEG_INFINITY, 1.0], ModelError::NonFinite),
        ([0.5, -1e-30, 0.0, 1.0], ModelError::NegativeVariance),
        ([0.5, 1.0, 0.0, 0.0], ModelError::Interval),
        ([0.5, 1.0, 0.0, -0.01], ModelError::Interval),
        ([0.5, 1.0, 0.0, f32::NAN], ModelError::Interval),
        ([1.0, 1.0, 0.0, 1.0], ModelError::Unstable { order: 1 }),
        ([-1.5, 1.0, 0.0, 1.0], ModelError::Unstable { order: 1 }),
    ];
    for (values, want) in cases {
        let got = ArModel::<f32, 1>::decode(&ar1_record(values));
        assert_eq!(got, Err(DecodeError::Ar(want)), "{values:?}");
    }
    // Encoding refuses a model that is not stationary: every record written decodes.
    let unstable = ArModel::new([0.5f32, 0.6], 1.0, 0.0, 1.0).unwrap();
    let mut buf = [0x77u8; 64];
    let got = unstable.encode(&mut buf);
    // Step-down: k_2 = 0.6, then a_1 = (0.5 + 0.6 * 0.5) / (1 - 0.36) = 1.25.
    assert_eq!(got, Err(EncodeError::Ar(ModelError::Unstable { order: 1 })));
    assert!(buf.iter().all(|b| *b == 0x77), "buffer written");
    let short = ArModel::new([0.5f32], 1.0, 0.0, 1.0)
        .unwrap()
        .encode(&mut buf[..31]);
    assert_eq!(
        short,
        Err(EncodeError::Buffer {
            needed: 32,
            given: 31
        })
    );
}

#[test]
fn intact_records_of_invalid_noise_models_are_typed_errors() {
    let good = encode(&sample_noise());
    let f64_at = |r: &mut Vec<u8>, at: usize, v: f64| {
        r[at..at + 8].copy_from_slice(&v.to_le_bytes());
    };
    type Edit = Box<dyn Fn(&mut Vec<u8>)>;
    let cases: Vec<(&str, Edit, DecodeError)> = vec![
        (
            "dt 0",
            Box::new(move |r| f64_at(r, 20, 0.0)),
            DecodeError::Noise(NoiseError::Interval),
        ),
        (
            "negative white",
            Box::new(move |r| f64_at(r, 36, -1e-3)),
            DecodeError::Noise(NoiseError::Parameter),
        ),
        (
            "NaN ramp",
            Box::new(move |r| f64_at(r, 52, f64::NAN)),
            DecodeError::Noise(NoiseError::Parameter),
        ),
        (
            "correlation time 0",
            Box::new(move |r| f64_at(r, 68, 0.0)),
            DecodeError::Noise(NoiseError::Parameter),
        ),
        (
            "negative frequency",
            Box::new(move |r| f64_at(r, 100, -7.5)),
            DecodeError::Noise(NoiseError::Parameter),
        ),
        (
            "terms out of order",
            Box::new(move |r| {
                r[12] = 2;
                f64_at(r, 76, 1e-3);
                f64_at(r, 84, 5.0);
            }),
            DecodeError::Noise(NoiseError::Parameter),
        ),
        (
            "three terms in two slots",
            Box::new(|r| r[12] = 3),
            DecodeError::Noise(NoiseError::Budget {
                requested: 3,
                capacity: 2,
            }),
        ),
        (
            "flag 2",
            Box::new(|r| r[16] = 2),
            DecodeError::Field { offset: 16 },
        ),
        (
            "unused term slot",
            Box::new(move |r| f64_at(r, 84, 1.0)),
            DecodeError::Field { offset: 76 },
        ),
        (
            "unused oscillator slot",
            Box::new(|r| r[139] = 0x80),
            DecodeError::Field { offset: 116 },
        ),
        (
            "absent AR part not zero",
            Box::new(|r| r[16] = 0),
            DecodeError::Field { offset: 140 },
        ),
        (
            "AR part unstable",
            Box::new(move |r| f64_at(r, 164, 1.0)),
            DecodeError::Noise(NoiseError::Ar(ModelError::Unstable { order: 4 })),
        ),
        (
            "AR part negative variance",
            Box::new(move |r| f64_at(r, 172, -2e-6)),
            DecodeError::Noise(NoiseError::Ar(ModelError::NegativeVariance)),
        ),
    ];
    for (name, edit, want) in cases {
        let mut r = good.clone();
        edit(&mut r);
        reseal(&mut r);
        assert_eq!(NoiseModel::<4, 2>::decode(&r), Err(want), "{name}");
    }
}

fn finite_f32() -> impl Strategy<Value = f32> {
    any::<u32>()
        .prop_map(f32::from_bits)
        .prop_filter("finite", |v| v.is_finite())
}

fn finite_f64() -> impl Strategy<Value = f64> {
    any::<u64>()
        .prop_map(f64::from_bits)
        .prop_filter("finite", |v| v.is_finite())
}

/// Any non-negative finite value (`-0.0` included), every exponent equally likely.
fn nonnegative_f64() -> impl Strategy<Value = f64> {
    prop_oneof![
        9 => finite_f64().prop_map(f64::abs),
        1 => Just(-0.0),
    ]
}

fn positive_f64() -> impl Strategy<Value = f64> {
    finite_f64()
        .prop_map(f64::abs)
        .prop_filter("positive", |v| *v > 0.0)
}

type NoiseParts = (
    f64,
    [f64; 4],
    Vec<(f64, f64)>,
    Vec<[f64; 3]>,
    Option<(Vec<f64>, [f64; 3])>,
);

fn noise_parts(g: usize) -> impl Strategy<Value = NoiseParts> {
    let ar = (
        prop::collection::vec(-0.999f64..0.999, 3),
        (nonnegative_f64(), finite_f64(), positive_f64()),
    );
    (
        positive_f64(),
        prop::array::uniform4(nonnegative_f64()),
        prop::collection::vec((nonnegative_f64(), positive_f64()), 0..=g),
        prop::collection::vec(
            (nonnegative_f64(), positive_f64(), positive_f64()).prop_map(|(s, f, t)| [s, f, t]),
            0..=g,
        ),
        prop::option::of(ar.prop_map(|(k, (v, m, dt))| (k, [v, m, dt]))),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(10_000))]

    /// Random byte strings are rejected by every decoder, without a panic.
    #[test]
    fn random_bytes_are_rejected(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        prop_assert!(ArModel::<f32, 1>::decode(&bytes).is_err());
        prop_assert!(ArModel::<f32, 4>::decode(&bytes).is_err());
        prop_assert!(ArModel::<f64, 4>::decode(&bytes).is_err());
        prop_assert!(NoiseModel::<4, 2>::decode(&bytes).is_err());
        prop_assert!(NoiseModel::<1, 1>::decode(&bytes).is_err());
    }

    /// Random payloads behind a right header and a right CRC: a typed error, or a valid model
    /// whose encoding is the same bytes.
    #[test]
    fn intact_random_payloads_decode_to_valid_models_or_errors(
        payload in prop::collection::vec(any::<u8>(), 188),
        zero_mask in any::<u64>(),
    ) {
        let mut noise = encode(&sample_noise());
        // Zero some 8-byte fields, so that counts, flags and unused slots often fit.
        for (i, chunk) in payload.chunks(8).enumerate() {
            let at = 12 + 8 * i;
            let keep = zero_mask >> (i % 64) & 1 == 1;
            noise[at..at + chunk.len()].copy_from_slice(if keep { chunk } else { &[0; 8][..chunk.len()] });
        }
        noise[12..14].copy_from_slice(&[payload[0] % 4, 0]);
        noise[14..16].copy_from_slice(&[payload[1] % 4, 0]);
        noise[16..20].copy_from_slice(&[payload[2] % 3, 0, 0, 0]);
        reseal(&mut noise);
        if let Ok(m) = NoiseModel::<4, 2>::decode(&noise) {
            prop_assert_eq!(encode(&m), noise.clone());
        }
        let mut ar = noise[..44].to_vec();
        ar[..12].copy_from_slice(&[0x49, 0x4d, 0x41, 0x52, 1, 1, 4, 0, 0, 0, 44, 0]);
        reseal(&mut ar);
        if let Ok(m) = ArModel::<f32, 4>::decode(&ar) {
            prop_assert_eq!(encode(&m), ar);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2_000))]

    /// Any finite `f32` values: the model encodes exactly when it is stationary, and then
    /// decodes to the same bits.
    #[test]
    fn random_f32_models_round_trip_or_are_refused(
        a in prop::array::uniform4(finite_f32()),
        k in prop::collection::vec(-0.9999f64..0.9999, 4),
        use_k in any::<bool>(),
        variance in finite_f32().prop_map(f32::abs),
        mean in finite_f32(),
        dt in finite_f32().prop_map(f32::abs).prop_filter("positive", |v| *v > 0.0),
    ) {
        let a = if use_k { step_up::<4>(&k).map(|v| v as f32) } else { a };
        let m = ArModel::new(a, variance, mean, dt).unwrap();
        let mut buf = [0u8; 44];
        match m.encode(&mut buf) {
            Ok(n) => {
                prop_assert_eq!(n, 44);
                let back = ArModel::<f32, 4>::decode(&buf).unwrap();
                prop_assert_eq!(back.a().map(f32::to_bits), a.map(f32::to_bits));
                let fields = |m: &ArModel<f32, 4>| [m.noise_variance(), m.mean(), m.dt()].map(f32::to_bits);
                prop_assert_eq!(fields(&back), fields(&m));
            }
            Err(e) => {
                prop_assert!(!m.is_stable(), "stable model refused: {e:?}");
                let unstable = matches!(e, EncodeError::Ar(ModelError::Unstable { .. }));
                prop_assert!(unstable, "{:?}", e);
            }
        }
    }

    /// Random valid noise models (every field any allowed bit pattern) decode to the same
    /// bits, and encode again to the same bytes.
    #[test]
    fn random_noise_models_round_trip(parts in noise_parts(3)) {
        let (dt, [q, n, k, r], mut gm, osc, ar) = parts;
        gm.sort_by(|p, q| p.1.total_cmp(&q.1));
        let gm: Vec<GmTerm> = gm.into_iter().map(|(sigma, correlation_time)| GmTerm { sigma, correlation_time }).collect();
        let osc: Vec<Oscillator> = osc.into_iter().map(|[sigma, frequency, decay_time]| Oscillator { sigma, frequency, decay_time }).collect();
        let ar = ar.map(|(kappa, [v, m, dt])| ArModel::new(step_up::<3>(&kappa), v, m, dt).unwrap());
        let c = Coefficients { quantization: q, white: n, random_walk: k, ramp: r };
        let Ok(model) = NoiseModel::<3, 3>::new(dt, c, &gm, &osc, ar) else {
            // Only a step-up that rounds onto the unit circle is refused.
            prop_assert!(ar.is_some_and(|ar| !ar.is_stable()));
            return Ok(());
        };
        let bytes = encode(&model);
        let back = NoiseModel::<3, 3>::decode(&bytes).unwrap();
        prop_assert_eq!(noise_bits(&back), noise_bits(&model));
        prop_assert_eq!(encode(&back), bytes);
    }
}
