//! Arrays of AR models (the axes of an IMU in one record): the layout, bit-exact round trips,
//! damage and mismatches rejected, and one array saved and loaded through the flash store.

use imu_ar::ArModel;
use imu_ar::model::ModelError;
use imu_ar::persist::{DecodeError, EncodeError, FlashStore, Record};
use imu_ar_host::flash::RamFlash;

use super::{encode, reseal};

fn axes() -> [ArModel<f32, 4>; 6] {
    core::array::from_fn(|i| {
        let a = [0.6, -0.2, 0.05, 0.01 * i as f32];
        ArModel::new(a, 1e-4 * (i + 1) as f32, i as f32 - 3.0, 0.01).unwrap()
    })
}

#[test]
fn six_axes_in_one_record() {
    let models = axes();
    let bytes = encode(&models);
    assert_eq!(bytes.len(), 184);
    assert_eq!(
        &bytes[..12],
        &[0x49, 0x4d, 0x41, 0x52, 1, 4, 4, 0, 6, 0, 184, 0]
    );
    // The payloads of the single models, one after the other.
    for (i, m) in models.iter().enumerate() {
        let single = encode(m);
        assert_eq!(
            &bytes[12 + 28 * i..40 + 28 * i],
            &single[12..40],
            "axis {i}"
        );
    }
    let back = <[ArModel<f32, 4>; 6]>::decode(&bytes).unwrap();
    for (b, m) in back.iter().zip(&models) {
        assert_eq!(b.a().map(f32::to_bits), m.a().map(f32::to_bits));
        let fields = |m: &ArModel<f32, 4>| [m.noise_variance(), m.mean(), m.dt()].map(f32::to_bits);
        assert_eq!(fields(b), fields(m));
    }
    let f64s = models.map(|m| {
        let a = m.a().map(f64::from);
        ArModel::new(a, m.noise_variance().into(), m.mean().into(), 0.01).unwrap()
    });
    let bytes64 = encode(&f64s);
    assert_eq!((bytes64.len(), bytes64[5]), (16 + 6 * 56, 5));
    assert_eq!(<[ArModel<f64, 4>; 6]>::decode(&bytes64), Ok(f64s));
}

#[test]
fn damaged_or_mismatched_arrays_are_rejected() {
    let bytes = encode(&axes());
    let decodes = |b: &[u8]| <[ArModel<f32, 4>; 6]>::decode(b).is_ok();
    for bit in 0..bytes.len() * 8 {
        let mut damaged = bytes.clone();
        damaged[bit / 8] ^= 1 << (bit % 8);
        assert!(!decodes(&damaged), "bit {bit} flipped and accepted");
    }
    for n in 0..bytes.len() {
        assert!(!decodes(&bytes[..n]), "the first {n} bytes accepted");
    }
    let capacity = |expected| {
        Err(DecodeError::Capacity {
            stored: 6,
            expected,
        })
    };
    assert_eq!(<[ArModel<f32, 4>; 3]>::decode(&bytes), capacity(3));
    assert_eq!(
        <[ArModel<f32, 4>; 1]>::decode(&bytes).err(),
        capacity(1).err()
    );
    let order = Err(DecodeError::Order {
        stored: 4,
        expected: 2,
    });
    assert_eq!(<[ArModel<f32, 2>; 6]>::decode(&bytes), order);
    let kind = Some(DecodeError::Kind {
        stored: 4,
        expected: 1,
    });
    assert_eq!(ArModel::<f32, 4>::decode(&bytes).err(), kind);
    // The fourth axis unstable, CRC intact: the model's error.
    let mut unstable = bytes.clone();
    unstable[12 + 28 * 3 + 12..12 + 28 * 3 + 16].copy_from_slice(&1.0f32.to_le_bytes());
    reseal(&mut unstable);
    let got = <[ArModel<f32, 4>; 6]>::decode(&unstable);
    assert_eq!(got, Err(DecodeError::Ar(ModelError::Unstable { order: 4 })));
    // And refused when encoding.
    let mut models = axes();
    models[3] = ArModel::new([0.0, 0.0, 0.0, 1.0], 1.0, 0.0, 0.01).unwrap();
    let got = models.encode(&mut [0u8; 184]);
    assert_eq!(got, Err(EncodeError::Ar(ModelError::Unstable { order: 4 })));
}

#[test]
fn six_axes_through_the_flash_store() {
    let mut flash = RamFlash::<1, 4, 256>::new(4);
    let mut store = FlashStore::new(&mut flash, 0..1024).unwrap();
    let mut buf = [0u8; 184];
    assert_eq!(store.save(&axes(), &mut buf), Ok(0));
    assert_eq!(store.load::<[ArModel<f32, 4>; 6]>(&mut buf), Ok(axes()));
}
