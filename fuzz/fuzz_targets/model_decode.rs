//! The persisted-model decoders on arbitrary bytes: never a panic; whatever decodes is a valid
//! model (stationary AR part) whose encoding is the very bytes decoded; and the flash store,
//! loading from a flash image of the same bytes, returns such a model or a typed error.
#![no_main]

use std::fmt::Debug;

use imu_ar::ArModel;
use imu_ar::noise::NoiseModel;
use imu_ar::persist::{FlashStore, Record, StoreError};
use imu_ar_host::flash::RamFlash;
use libfuzzer_sys::fuzz_target;

/// `data` as an `M`: if it decodes, it encodes back to the same bytes.
fn decode<M: Record + Debug>(data: &[u8]) {
    if let Ok(m) = M::decode(data) {
        let mut buf = vec![0u8; M::LEN];
        assert_eq!(m.encode(&mut buf), Ok(M::LEN), "{m:?}");
        assert_eq!(buf, data[..M::LEN], "{m:?}");
    }
}

/// Loads an `M` from `flash`: a model that encodes, or nothing stored, or a decode error.
fn load<M: Record + Debug>(flash: &mut RamFlash<1, 4, 256>) {
    let mut buf = vec![0u8; M::LEN];
    let mut store = FlashStore::new(flash, 0..512).unwrap();
    match store.load::<M>(&mut buf) {
        Ok(m) => assert_eq!(m.encode(&mut buf), Ok(M::LEN), "{m:?}"),
        Err(StoreError::Empty | StoreError::Decode(_)) => {}
        Err(e) => panic!("{e:?}"),
    }
}

fuzz_target!(|data: &[u8]| {
    decode::<ArModel<f32, 1>>(data);
    decode::<ArModel<f32, 4>>(data);
    decode::<ArModel<f32, 8>>(data);
    decode::<ArModel<f64, 4>>(data);
    decode::<[ArModel<f32, 4>; 6]>(data);
    decode::<[ArModel<f64, 2>; 3]>(data);
    decode::<NoiseModel<1, 1>>(data);
    decode::<NoiseModel<4, 2>>(data);
    decode::<NoiseModel<8, 3>>(data);
    // The same bytes as the contents of a store of two 256-byte slots.
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    let n = data.len().min(512);
    flash.bytes_mut()[..n].copy_from_slice(&data[..n]);
    load::<ArModel<f32, 4>>(&mut flash);
    load::<NoiseModel<4, 2>>(&mut flash);
    load::<[ArModel<f32, 4>; 6]>(&mut flash);
});
