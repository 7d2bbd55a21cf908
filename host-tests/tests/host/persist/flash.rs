//! `FlashStore` on a NOR flash in RAM (`imu_ar_host::flash`): a power cut at every byte
//! operation of a save leaves the old model or the new one, never garbage and never nothing;
//! interleaved cut and completed saves; slots filling and alternating; every error typed.

use std::fmt::Debug;

use embedded_storage::nor_flash::ReadNorFlash;
use imu_ar::ArModel;
use imu_ar::noise::NoiseModel;
use imu_ar::persist::{DecodeError, FlashStore, Record, StoreError};
use imu_ar_host::flash::{RamFlash, RamFlashError};
use proptest::prelude::*;

use super::sample_noise;

fn model(i: u32) -> ArModel<f32, 4> {
    let a = [0.5, -0.1, 0.05, 0.001 * (i % 17) as f32];
    ArModel::new(a, 1e-4 * (i + 1) as f32, i as f32, 0.01).unwrap()
}

fn region<const R: usize, const W: usize, const E: usize>(
    flash: &RamFlash<R, W, E>,
) -> std::ops::Range<u32> {
    0..flash.capacity() as u32
}

fn save<const R: usize, const W: usize, const E: usize, M: Record>(
    flash: &mut RamFlash<R, W, E>,
    m: &M,
) -> Result<u32, StoreError<RamFlashError>> {
    let mut buf = vec![0u8; M::LEN];
    let region = region(flash);
    FlashStore::new(flash, region).unwrap().save(m, &mut buf)
}

fn load<const R: usize, const W: usize, const E: usize, M: Record>(
    flash: &mut RamFlash<R, W, E>,
) -> Result<M, StoreError<RamFlashError>> {
    let mut buf = vec![0u8; M::LEN];
    let region = region(flash);
    FlashStore::new(flash, region).unwrap().load(&mut buf)
}

/// Cuts the power after every possible number of byte operations of saving `new` on
/// `before` (which holds `old`, or nothing), reboots and loads: the old model until some
/// cut, the new one from there on. After each cut a complete save succeeds. Returns the
/// save's byte operations and the first cut that leaves the new model.
fn every_cut<const R: usize, const W: usize, const E: usize, O, M>(
    before: &RamFlash<R, W, E>,
    old: Option<&O>,
    new: &M,
) -> (usize, usize)
where
    O: Record + PartialEq + Debug,
    M: Record + PartialEq + Debug,
{
    let mut full = before.clone();
    let start = full.ops;
    save(&mut full, new).unwrap();
    let total = full.ops - start;
    let mut first_new = None;
    for k in 0..=total {
        let mut flash = before.clone();
        flash.cut_after(k);
        let saved = save(&mut flash, new);
        if k < total {
            assert_eq!(
                saved,
                Err(StoreError::Flash(RamFlashError::PowerCut)),
                "cut at {k}"
            );
        } else {
            assert!(saved.is_ok(), "{saved:?}");
        }
        flash.power_on();
        let got = (
            load::<R, W, E, M>(&mut flash),
            load::<R, W, E, O>(&mut flash),
        );
        match got {
            (Ok(m), _) if m == *new => {
                first_new.get_or_insert(k);
            }
            (_, Ok(o)) if Some(&o) == old && first_new.is_none() => {}
            (Err(StoreError::Empty), _) if old.is_none() && first_new.is_none() => {}
            got => panic!("cut after {k} of {total} byte operations: {got:?}"),
        }
        save(&mut flash, new).unwrap();
        assert_eq!(
            load::<R, W, E, M>(&mut flash).as_ref(),
            Ok(new),
            "after cut at {k}"
        );
    }
    (
        total,
        first_new.expect("the complete save leaves the new model"),
    )
}

/// An entry: the record, the sequence number and its complement.
fn entry<M: Record>(seq: u32, m: &M) -> Vec<u8> {
    let mut e = super::encode(m);
    e.extend(seq.to_le_bytes());
    e.extend((!seq).to_le_bytes());
    e
}

/// The byte operations into the entry of number `seq` after which it is intact: up to its
/// last byte that is not `0xFF` (writing `0xFF` changes nothing).
fn intact_at<M: Record>(seq: u32, m: &M) -> usize {
    entry(seq, m).iter().rposition(|b| *b != 0xFF).unwrap() + 1
}

/// A cut in every byte of the first save, of an append and of a save that erases the other
/// slot, for one geometry; `per_slot` entries of `ArModel<f32, 4>` fit a slot.
fn cuts_in_every_kind_of_save<const R: usize, const W: usize, const E: usize>(
    units: usize,
    per_slot: u32,
) {
    let mut flash = RamFlash::<R, W, E>::new(units);
    let entry = (8 + 44usize).next_multiple_of(W);
    let (total, first) = every_cut(&flash, None::<&ArModel<f32, 4>>, &model(0));
    let slot = units / 2 * E;
    assert_eq!(
        total,
        slot + entry,
        "the first save erases slot 0 and writes"
    );
    assert_eq!(
        first,
        slot + intact_at(0, &model(0)),
        "new from the entry's last byte on"
    );
    save(&mut flash, &model(0)).unwrap();
    let (total, first) = every_cut(&flash, Some(&model(0)), &model(1));
    assert_eq!(
        (total, first),
        (entry, intact_at(1, &model(1))),
        "an append erases nothing"
    );
    for i in 1..per_slot {
        save(&mut flash, &model(i)).unwrap();
    }
    let old = model(per_slot - 1);
    let (total, first) = every_cut(&flash, Some(&old), &model(per_slot));
    let want = (slot + entry, slot + intact_at(per_slot, &model(per_slot)));
    assert_eq!((total, first), want, "a full slot: the other one is erased");
    // The noise model too, whose entry fills most of a slot.
    let (_, first) = every_cut(&flash, Some(&old), &sample_noise());
    assert!(first > slot, "{first}");
}

#[test]
fn a_power_cut_at_any_byte_leaves_the_old_model_or_the_new_one() {
    cuts_in_every_kind_of_save::<1, 4, 256>(2, 4);
    cuts_in_every_kind_of_save::<1, 1, 256>(4, 9);
    cuts_in_every_kind_of_save::<4, 8, 512>(2, 9);
    cuts_in_every_kind_of_save::<16, 32, 1024>(2, 16);
    cuts_in_every_kind_of_save::<2, 16, 256>(3, 4);
}

#[test]
fn slots_fill_then_alternate() {
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    for i in 0..20 {
        assert_eq!(save(&mut flash, &model(i)), Ok(i));
        assert_eq!(load(&mut flash), Ok(model(i)));
    }
    // Four 52-byte entries per 256-byte slot: one erase per four saves.
    assert_eq!(flash.erases, 5);
    // Both slots hold intact entries; slot 0 the newest four, slot 1 the four before.
    assert_eq!(&flash.bytes()[44..48], &16u32.to_le_bytes());
    assert_eq!(&flash.bytes()[256 + 44..256 + 48], &12u32.to_le_bytes());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Saves, some cut at a random byte: after each, a reboot loads the model of the last
    /// complete save, or the one just cut if the cut came after its record.
    #[test]
    fn cut_and_complete_saves_interleaved(steps in prop::collection::vec((any::<bool>(), 0usize..800), 1..30)) {
        let mut flash = RamFlash::<1, 8, 256>::new(3);
        let mut current: Option<ArModel<f32, 4>> = None;
        for (i, &(cut, k)) in steps.iter().enumerate() {
            let new = model(i as u32);
            if cut {
                flash.cut_after(k);
            }
            let saved = save(&mut flash, &new);
            flash.power_on();
            let got = load::<1, 8, 256, ArModel<f32, 4>>(&mut flash);
            match got {
                Ok(m) if m == new => current = Some(m),
                Ok(m) => prop_assert!(saved.is_err() && current == Some(m), "step {i}: {m:?}"),
                Err(StoreError::Empty) => prop_assert!(saved.is_err() && current.is_none()),
                Err(e) => prop_assert!(false, "step {}: {:?}", i, e),
            }
        }
    }

    /// Whatever the flash holds, loading returns a valid model or a typed error.
    #[test]
    fn any_flash_contents_load_to_a_model_or_an_error(
        bytes in prop::collection::vec(any::<u8>(), 512),
        plant in prop::option::of((0usize..2, any::<bool>())),
    ) {
        let mut flash = RamFlash::<1, 4, 256>::new(2);
        flash.bytes_mut().copy_from_slice(&bytes);
        if let Some((slot, seal)) = plant {
            // A record header and a sequence number at the start of a slot, and the CRC of
            // the random payload if `seal`, so that the scan and the decoder go deeper.
            let at = 256 * slot;
            let mem = flash.bytes_mut();
            mem[at..at + 12].copy_from_slice(&[0x49, 0x4d, 0x41, 0x52, 1, 1, 4, 0, 0, 0, 44, 0]);
            mem[at + 44..at + 52].copy_from_slice(&[7, 0, 0, 0, !7, !0, !0, !0]);
            if seal {
                super::reseal(&mut mem[at..at + 44]);
            }
        }
        match load::<1, 4, 256, ArModel<f32, 4>>(&mut flash) {
            Ok(m) => prop_assert!(m.is_stable()),
            Err(StoreError::Empty | StoreError::Decode(_)) => {}
            Err(e) => prop_assert!(false, "{:?}", e),
        }
    }
}

#[test]
fn damage_at_rest_falls_back_to_the_previous_save() {
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    save(&mut flash, &model(0)).unwrap();
    save(&mut flash, &model(1)).unwrap();
    flash.bytes_mut()[52 + 20] ^= 0x04; // in the second record
    assert_eq!(load(&mut flash), Ok(model(0)));
    // The next save does not write after a damaged entry: it starts the other slot.
    save(&mut flash, &model(2)).unwrap();
    assert_eq!((flash.erases, load(&mut flash)), (2, Ok(model(2))));
    // A damaged sequence number counts as damage too.
    flash.bytes_mut()[256 + 44 + 5] ^= 0x80;
    assert_eq!(load(&mut flash), Ok(model(0)));
}

#[test]
fn sequence_numbers_compare_modulo_2_32() {
    for (s0, s1, newest) in [
        (u32::MAX - 1, 1, 1),
        (1, u32::MAX - 1, 0),
        (5, 6, 1),
        (6, 5, 0),
    ] {
        let mut flash = RamFlash::<1, 4, 256>::new(2);
        flash.bytes_mut()[..52].copy_from_slice(&entry(s0, &model(10)));
        flash.bytes_mut()[256..308].copy_from_slice(&entry(s1, &model(11)));
        assert_eq!(load(&mut flash), Ok(model(10 + newest)), "{s0:x} {s1:x}");
    }
    // After 2^32 - 2 comes 0 (all ones would read as erased with its complement).
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    flash.bytes_mut()[..52].copy_from_slice(&entry(u32::MAX - 1, &model(3)));
    assert_eq!(save(&mut flash, &model(4)), Ok(0));
    assert_eq!(load(&mut flash), Ok(model(4)));
}

#[test]
fn errors_are_typed() {
    let mut flash = RamFlash::<1, 4, 256>::new(4);
    let bad =
        |r: std::ops::Range<u32>, flash: &mut RamFlash<1, 4, 256>| FlashStore::new(flash, r).err();
    // One unit, misaligned, beyond the flash, backwards, misaligned again.
    #[allow(clippy::reversed_empty_ranges)]
    let ranges = [0..256, 128..640, 0..1280, 512..256, 1..513];
    for r in ranges {
        assert_eq!(
            bad(r.clone(), &mut flash),
            Some(StoreError::Region),
            "{r:?}"
        );
    }
    // Three units: two slots of one, the third unused.
    assert_eq!(
        FlashStore::new(&mut flash, 256..1024).unwrap().slot_len(),
        256
    );

    assert_eq!(
        load::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Err(StoreError::Empty)
    );
    let mut store = FlashStore::new(&mut flash, 0..1024).unwrap();
    let mut short = [0u8; 43];
    let need = StoreError::Buffer {
        needed: 44,
        given: 43,
    };
    assert_eq!(store.save(&model(0), &mut short), Err(need));
    assert_eq!(store.load::<ArModel<f32, 4>>(&mut short), Err(need));
    // A record larger than a slot: refused before anything is erased.
    let big = NoiseModel::<16, 8>::new(1.0, Default::default(), &[], &[], None).unwrap();
    let mut buf = vec![0u8; NoiseModel::<16, 8>::LEN];
    assert_eq!(
        store.save(&big, &mut buf),
        Err(StoreError::TooSmall {
            needed: 544,
            slot: 512
        })
    );
    let unstable = ArModel::new([1.0f32, 0.0, 0.0, 0.0], 1.0, 0.0, 1.0).unwrap();
    assert!(matches!(
        store.save(&unstable, &mut buf),
        Err(StoreError::Encode(_))
    ));
    let _ = store.destroy();
    assert_eq!(flash.erases, 0);

    // The newest intact record of another type: its decode error, not an older record.
    save(&mut flash, &model(0)).unwrap();
    let order = Err(StoreError::Decode(DecodeError::Order {
        stored: 4,
        expected: 8,
    }));
    assert_eq!(load::<1, 4, 256, ArModel<f32, 8>>(&mut flash), order);
    let kind = Err(StoreError::Decode(DecodeError::Kind {
        stored: 1,
        expected: 2,
    }));
    assert_eq!(load::<1, 4, 256, ArModel<f64, 4>>(&mut flash), kind);
    save(&mut flash, &sample_noise()).unwrap();
    let kind = Err(StoreError::Decode(DecodeError::Kind {
        stored: 3,
        expected: 1,
    }));
    assert_eq!(load::<1, 4, 256, ArModel<f32, 4>>(&mut flash), kind);
    assert_eq!(load(&mut flash), Ok(sample_noise()));
    for e in [
        StoreError::Empty,
        StoreError::Flash(RamFlashError::PowerCut),
        StoreError::Verify,
    ] {
        assert!(!e.to_string().is_empty());
    }
}

#[test]
fn flash_errors_are_wrapped_and_keep_the_newest_model() {
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    save(&mut flash, &model(0)).unwrap();
    save(&mut flash, &model(1)).unwrap();
    // A read error at the second entry (an ECC error of a torn write, say) ends the scan
    // there: the entry before it is the newest readable one.
    flash.fail_reads_at(60..61);
    assert_eq!(load(&mut flash), Ok(model(0)));
    // Unreadable from the start, and nothing in the other slot: the flash's error.
    flash.fail_reads_at(0..1);
    assert_eq!(
        load::<1, 4, 256, ArModel<f32, 4>>(&mut flash),
        Err(StoreError::Flash(RamFlashError::ReadFault))
    );
    // The power stays off: the save fails with the flash's error, the model is still there.
    let mut flash = RamFlash::<1, 4, 256>::new(2);
    save(&mut flash, &model(0)).unwrap();
    flash.cut_after(0);
    assert_eq!(
        save(&mut flash, &model(1)),
        Err(StoreError::Flash(RamFlashError::PowerCut))
    );
    assert_eq!(
        save(&mut flash, &model(1)),
        Err(StoreError::Flash(RamFlashError::PowerCut))
    );
    flash.power_on();
    assert_eq!(load(&mut flash), Ok(model(0)));
}
