//! The sensor readers under bus faults that need more than the simulator's own fault rules:
//! chip resets in the middle of a FIFO reset, samples arriving between the reader's
//! transfers, corrupted bytes on the wire, and calls in unusual orders. Each test checks one
//! guarantee of README "Sensors" against the register-level simulator (`sim`).
//!
//! Some tests wrap the simulated bus in a hooked bus (`sim::hooks`) that advances the chip's
//! clock right before a chosen transfer (on real hardware samples keep arriving while the
//! reader works: a 1 kHz MPU-6050 on 400 kHz I2C writes a sample every ~13 transfers) or
//! corrupts the bytes of a chosen read (a bit error on the wire).

use crate::sim;

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::{i2c, spi};
use imu_ar::sensor::{
    Dlpf, Error, Icm42688, Icm42688Async, Icm42688Config, ImuReader, Mpu6050, Mpu6050Async,
    Mpu6050Config, Odr, RawSample, Replay, Scale,
};
use sim::asynch::{AsyncBus, AsyncNoDelay, Awaited, block_on};
use sim::hooks::{Action, HookedI2c, HookedSpi, Hooks};
use sim::icm42688::{self as icm, SimSpi};
use sim::mpu6050::{self as mpu, SimI2c};
use sim::{Kind, Model, NoDelay, Sim, decode};

/// 1 kHz: one tick per millisecond.
fn mpu_config() -> Mpu6050Config {
    Mpu6050Config {
        dlpf: Dlpf::Hz44,
        sample_rate_divider: 0,
        ..Mpu6050Config::default()
    }
}

fn mpu(seed: u64) -> (Rc<RefCell<Sim>>, Hooks, Mpu6050<HookedI2c>) {
    mpu_with(seed, mpu_config())
}

/// An MPU-6050 with `config` and its FIFO on.
fn mpu_with(seed: u64, config: Mpu6050Config) -> (Rc<RefCell<Sim>>, Hooks, Mpu6050<HookedI2c>) {
    let sim = Sim::new(Model::Mpu6050, seed);
    let hooks = Hooks::default();
    let bus = HookedI2c {
        sim: sim.clone(),
        inner: SimI2c(sim.clone()),
        hooks: hooks.clone(),
    };
    let mut imu = Mpu6050::new(bus, 0x68);
    imu.init(&mut NoDelay, config).unwrap();
    imu.enable_fifo().unwrap();
    (sim, hooks, imu)
}

/// A session of the blocking and of the async reader (its bus suspending at every transfer).
type Both<E> = Vec<(Rc<RefCell<Sim>>, Hooks, Box<dyn ImuReader<BusError = E>>)>;

/// [`mpu`] with the blocking reader, then the same session with the async one.
fn mpu_both(seed: u64) -> Both<i2c::ErrorKind> {
    let (sim, hooks, imu) = mpu(seed);
    let blocking: Box<dyn ImuReader<BusError = _>> = Box::new(imu);
    let sim2 = Sim::new(Model::Mpu6050, seed);
    let hooks2 = Hooks::default();
    let bus = HookedI2c {
        sim: sim2.clone(),
        inner: SimI2c(sim2.clone()),
        hooks: hooks2.clone(),
    };
    let mut imu = Awaited(Mpu6050Async::new(AsyncBus(bus), 0x68));
    block_on(imu.0.init(&mut AsyncNoDelay, mpu_config())).unwrap();
    block_on(imu.0.enable_fifo()).unwrap();
    vec![(sim, hooks, blocking), (sim2, hooks2, Box::new(imu))]
}

/// [`icm`] with the blocking reader, then the same session with the async one.
fn icm_both(seed: u64) -> Both<spi::ErrorKind> {
    let (sim, hooks, imu) = icm(seed);
    let blocking: Box<dyn ImuReader<BusError = _>> = Box::new(imu);
    let sim2 = Sim::new(Model::Icm42688, seed);
    let hooks2 = Hooks::default();
    let bus = HookedSpi {
        sim: sim2.clone(),
        inner: SimSpi(sim2.clone()),
        hooks: hooks2.clone(),
    };
    let mut imu = Awaited(Icm42688Async::new(AsyncBus(bus)));
    block_on(imu.0.init(&mut AsyncNoDelay, icm_config())).unwrap();
    block_on(imu.0.enable_fifo()).unwrap();
    sim2.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
    let mut out = [RawSample::default(); 160];
    assert_eq!(imu.read_fifo(&mut out), Ok(0));
    vec![(sim, hooks, blocking), (sim2, hooks2, Box::new(imu))]
}

/// 1 kHz.
fn icm_config() -> Icm42688Config {
    Icm42688Config {
        odr: Odr::Hz1000,
        ..Icm42688Config::default()
    }
}

/// An ICM-42688-P at 1 kHz with its FIFO on and the gyro start-up behind it.
fn icm(seed: u64) -> (Rc<RefCell<Sim>>, Hooks, Icm42688<HookedSpi>) {
    let sim = Sim::new(Model::Icm42688, seed);
    let hooks = Hooks::default();
    let bus = HookedSpi {
        sim: sim.clone(),
        inner: SimSpi(sim.clone()),
        hooks: hooks.clone(),
    };
    let mut imu = Icm42688::new(bus);
    imu.init(&mut NoDelay, icm_config()).unwrap();
    imu.enable_fifo().unwrap();
    sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
    let mut out = [RawSample::default(); 160];
    assert_eq!(imu.read_fifo(&mut out), Ok(0));
    (sim, hooks, imu)
}

/// Every sample the chip wrote into its FIFO since `since_ticks` is delivered or counted.
/// (No overflow by the chip and no outage in these tests.)
fn assert_accounted<R: ImuReader>(sim: &Rc<RefCell<Sim>>, imu: &R, delivered: u64, what: &str) {
    let sim = sim.borrow();
    let s = imu.fifo_stats();
    let written = sim.produced;
    let counted = delivered + s.discarded + s.invalid + s.malformed + s.lost + sim.fifo_packets();
    assert_eq!(
        counted, written,
        "{what}: the chip wrote {written} samples into its FIFO, the reader accounts for \
         {counted}: {s:#?}"
    );
}

// ---------------------------------------------------------------------------------------------

/// MPU-6050: a chip reset (brown-out) while a FIFO reset is pending after a bus error. Finishing
/// the pending reset used to write USER_CTRL.FIFO_EN and FIFO_EN again on the freshly reset,
/// sleeping chip, which erased the evidence (USER_CTRL without FIFO_EN) the reset detection
/// relies on: every later `read_fifo` returned `Ok(0)`. The FIFO reset now reads the count with
/// the channels off and, on an empty FIFO, checks PWR_MGMT_1 before going on.
/// Expected: `Error::SensorReset` within a few calls (or samples flowing again).
#[test]
fn mpu_chip_reset_with_a_fifo_reset_pending_is_reported() {
    let (sim, _hooks, mut imu) = mpu(1);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    // A FIFO read fails part-way, and so does the FIFO reset behind it: the reset is pending.
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    sim.borrow_mut().fail(Kind::Write(mpu::FIFO_EN), 0, 0);
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    // The supply glitch that caused the bus errors resets the chip.
    sim.borrow_mut().glitch();
    let mut results = Vec::new();
    let mut delivered = 0;
    for _ in 0..20 {
        sim.borrow_mut().tick(10);
        let r = imu.read_fifo(&mut out);
        if let Ok(k) = r {
            delivered += k;
        }
        results.push(r);
    }
    assert!(
        delivered > 0 || results.contains(&Err(Error::SensorReset)),
        "200 sample periods after a chip reset: no sample and no SensorReset, the loop is \
         stalled: {results:?}"
    );
}

/// MPU-6050 (the ICM-42688-P's `enable_fifo` is the same routine): `enable_fifo` that fails at
/// its last write after the write took effect leaves the chip's FIFO running while the reader
/// says `FifoNotRunning`. The documented remedy is to call `enable_fifo` again; it resets the
/// FIFO, and the samples the chip wrote in the meantime must not vanish.
/// Expected: those samples are counted (`discarded`) or delivered.
#[test]
fn enable_fifo_retry_counts_the_samples_it_drops() {
    let sim = Sim::new(Model::Mpu6050, 2);
    let mut imu = Mpu6050::new(SimI2c(sim.clone()), 0x68);
    imu.init(&mut NoDelay, mpu_config()).unwrap();
    // enable_fifo: FIFO_EN = 0, ..., FIFO_EN = channels; the second fails after taking effect.
    sim.borrow_mut().fail_applied(Kind::Write(mpu::FIFO_EN), 1);
    assert!(matches!(imu.enable_fifo(), Err(Error::Bus(_))));
    sim.borrow_mut().tick(10);
    let mut out = [RawSample::default(); 128];
    assert_eq!(imu.read_fifo(&mut out), Err(Error::FifoNotRunning));
    imu.enable_fifo().unwrap();
    let k = imu.read_fifo(&mut out).unwrap();
    assert_accounted(&sim, &imu, k as u64, "enable_fifo retried");
}

/// Both chips (shared FIFO reset): a sample the chip writes after the reader's FIFO_COUNT read
/// and before the reset takes the channels off is dropped by the reset, and must be counted
/// (README: "the count is exact: the channels are taken off the FIFO before it is emptied").
/// Expected: FifoResync { discarded: 11 } and every sample accounted for.
#[test]
fn reset_counts_a_sample_written_after_the_count() {
    let (sim, hooks, mut imu) = mpu(3);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    // One sample arrives after resync's FIFO_COUNT, before the reset's FIFO_EN = 0.
    hooks.add(Kind::Write(mpu::FIFO_EN), 0, Action::TickBefore(1));
    let r = imu.read_fifo(&mut out);
    assert_accounted(&sim, &imu, 0, "reset after a failed read");
    assert_eq!(r, Err(Error::FifoResync { discarded: 11 }));
}

/// Both chips (shared resync): after a failed data read, the bytes the failed transfer clocked
/// out were reckoned as `count_before - count_now` (saturating), as if the FIFO only shrank.
/// With the channels still on, a sample arriving meanwhile makes count_now > count_before: the
/// partly read packet was lost from the count (here 5 + 127 = 132 bytes = 11 samples dropped,
/// counted 127 bytes = 10).
/// Expected: FifoResync { discarded: 11 }, discarded_bytes 132.
#[test]
fn resync_counts_exactly_while_the_fifo_grows() {
    let (sim, hooks, mut imu) = mpu(4);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    // FIFO_COUNTH is read twice by read_fifo (skip both), then by resync: a sample arrives
    // before it.
    hooks.add(Kind::Read(mpu::FIFO_COUNTH), 2, Action::TickBefore(1));
    let r = imu.read_fifo(&mut out);
    assert_eq!(
        imu.fifo_stats().discarded_bytes,
        132,
        "bytes dropped: 5 read + 127 left"
    );
    assert_eq!(r, Err(Error::FifoResync { discarded: 11 }));
    assert_accounted(&sim, &imu, 0, "resync with the FIFO growing");
}

/// As above, with the sample arriving between read_fifo's two FIFO_COUNT reads: the data are
/// read by the smaller count, the bytes of the failed read reckoned from the later one.
#[test]
fn resync_counts_exactly_when_the_fifo_grows_between_the_count_reads() {
    let (sim, hooks, mut imu) = mpu(4);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    hooks.add(Kind::Read(mpu::FIFO_COUNTH), 1, Action::TickBefore(1));
    let r = imu.read_fifo(&mut out);
    assert_eq!(imu.fifo_stats().discarded_bytes, 132);
    assert_eq!(r, Err(Error::FifoResync { discarded: 11 }));
    assert_accounted(
        &sim,
        &imu,
        0,
        "resync with the FIFO growing before the data read",
    );
}

/// `recover` and `enable_fifo` before `init`: nothing is configured to recover, and no
/// outage is counted.
#[test]
fn recover_and_enable_fifo_before_init_are_errors() {
    let sim = Sim::new(Model::Mpu6050, 15);
    let mut imu = Mpu6050::new(SimI2c(sim.clone()), 0x68);
    assert_eq!(
        imu.recover(&mut NoDelay, 1_000_000),
        Err(Error::NotInitialised)
    );
    assert_eq!(imu.fifo_stats(), Default::default());
    let sim = Sim::new(Model::Icm42688, 15);
    let mut imu = Icm42688::new(SimSpi(sim.clone()));
    assert_eq!(imu.enable_fifo(), Err(Error::NotInitialised));
    assert_eq!(
        imu.recover(&mut NoDelay, 1_000_000),
        Err(Error::NotInitialised)
    );
    assert_eq!(imu.fifo_stats(), Default::default());
}

/// Both chips: with the bus stuck high (every read 0xFF) each `read_fifo` used to "discard" a
/// full FIFO: 85 samples per call on the MPU-6050, though the chip wrote one sample between
/// calls. A count above the FIFO's size is no count.
/// Expected: never more discarded than the chip wrote.
#[test]
fn stuck_high_bus_discards_no_more_than_the_chip_wrote() {
    let (sim, _hooks, mut imu) = mpu(5);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(2);
    sim.borrow_mut().stuck_high = true;
    for _ in 0..10 {
        let _ = imu.read_fifo(&mut out);
        sim.borrow_mut().tick(1);
    }
    sim.borrow_mut().stuck_high = false;
    let s = imu.fifo_stats();
    let written = sim.borrow().produced;
    assert!(
        s.discarded <= written,
        "discarded {} samples, the chip wrote {written}: {s:#?}",
        s.discarded
    );
}

/// ICM-42688-P: a header with HEADER_MSG (bit 7, "FIFO empty") in the middle of a batch ended
/// the batch, and the packets after it in the same transfer, already clocked out of the FIFO,
/// were neither delivered nor counted (nor the marker packet itself). FIFO_COUNT said 3
/// packets, so an "empty" marker here is a damaged header (0xFF on the wire).
/// Expected: the 2 packets counted (malformed/discarded) or delivered.
#[test]
fn icm_empty_marker_inside_the_count_is_malformed() {
    let (sim, hooks, mut imu) = icm(6);
    let mut out = [RawSample::default(); 160];
    let before = imu.fifo_stats();
    sim.borrow_mut().tick(3);
    // The second packet's header reads 0xFF.
    hooks.add(
        Kind::Read(icm::FIFO_DATA),
        0,
        Action::Overwrite(vec![(16, 0xFF)]),
    );
    let k = match imu.read_fifo(&mut out) {
        Ok(k) => k,
        Err(Error::FifoResync { .. }) => 0,
        Err(e) => panic!("{e:?}"),
    };
    let s = imu.fifo_stats();
    let accounted = k as u64
        + (s.malformed - before.malformed)
        + (s.discarded - before.discarded)
        + (s.invalid - before.invalid)
        + sim.borrow().fifo_packets();
    assert_eq!(
        accounted, 3,
        "3 packets read out of the FIFO; delivered {k}: {s:#?}"
    );
}

/// An overflow whose FIFO reset meets a bus error is pending; `recover` (called for
/// FifoNotRunning, or "any suspected glitch" as its doc invites) replaces the pending reset,
/// and the overflow must still be counted. README: "An overflow is never lost ... every
/// overflow is counted (`overflows`)".
/// Expected: overflows == 1.
#[test]
fn recover_counts_a_pending_overflow() {
    let (sim, _hooks, mut imu) = mpu(7);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(100); // the FIFO overflows
    sim.borrow_mut().fail(Kind::Write(mpu::FIFO_EN), 0, 0);
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    imu.recover(&mut NoDelay, 100_000).unwrap();
    sim.borrow_mut().tick(5);
    let _ = imu.read_fifo(&mut out);
    assert_eq!(imu.fifo_stats().overflows, 1, "{:#?}", imu.fifo_stats());
}

/// `FifoStats::resets` is documented as chip resets detected (`Error::SensorReset`) and
/// recovered from; a `recover` after `FifoNotRunning` (a failed `enable_fifo`, no chip reset at
/// all) is no chip reset.
/// Expected: resets == 0.
#[test]
fn resets_counts_only_detected_chip_resets() {
    let sim = Sim::new(Model::Mpu6050, 8);
    let mut imu = Mpu6050::new(SimI2c(sim.clone()), 0x68);
    imu.init(&mut NoDelay, mpu_config()).unwrap();
    sim.borrow_mut().fail(Kind::Write(0x38), 0, 0); // INT_ENABLE
    assert!(imu.enable_fifo().is_err());
    let mut out = [RawSample::default(); 16];
    assert_eq!(imu.read_fifo(&mut out), Err(Error::FifoNotRunning));
    imu.recover(&mut NoDelay, 0).unwrap();
    assert_eq!(imu.fifo_stats().resets, 0, "no chip reset was detected");
}

/// `Replay`: `FifoStats::clipped` ("Delivered samples with some axis at a rail") is counted by
/// `Replay::read_fifo` too.
/// Expected: clipped == 1.
#[test]
fn replay_counts_clipped_samples() {
    let samples = [
        RawSample {
            gyro: [i16::MAX, 0, 0],
            ..RawSample::default()
        },
        RawSample::default(),
    ];
    let scale = Scale {
        gyro_counts_per_dps: 131.0,
        accel_counts_per_g: 16384.0,
    };
    let mut replay = Replay::new(&samples, scale);
    let mut out = [RawSample::default(); 4];
    assert_eq!(replay.read_fifo(&mut out), Ok(2));
    assert_eq!(replay.fifo_stats().clipped, 1);
}

/// MPU-6050: a FIFO_COUNT read corrupted on the wire (here 0x0078 = 10 packets while the FIFO
/// holds 2) was trusted: the reader read past the FIFO's end and delivered 8 samples made of
/// the FIFO's repeated last byte. (ArduPilot puts the temperature into the MPU FIFO and checks
/// it to detect such reads; the reader reads FIFO_COUNT twice and takes the smaller.)
/// Expected: only the 2 samples the chip produced are delivered.
#[test]
fn mpu_corrupted_fifo_count_delivers_no_garbage() {
    let (sim, hooks, mut imu) = mpu(10);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(2);
    hooks.add(
        Kind::Read(mpu::FIFO_COUNTH),
        0,
        Action::Overwrite(vec![(0, 0x00), (1, 0x78)]),
    );
    let k = imu.read_fifo(&mut out).unwrap();
    let garbage: Vec<&RawSample> = out[..k].iter().filter(|s| decode(s).is_none()).collect();
    assert!(
        garbage.is_empty(),
        "{} garbage samples delivered: {:?}",
        garbage.len(),
        garbage.first()
    );
}

/// ICM-42688-P: a FIFO_COUNT read corrupted high on the wire (0x00A0 = 10 packets while the
/// FIFO holds 2) was trusted: the reader read past the FIFO's end, took the bytes there for 8
/// malformed packets, and dropped the call: the 2 real samples discarded and 8 samples that
/// were never written counted as malformed. (The count is confirmed as the MPU-6050's is.)
/// Expected: the 2 samples delivered, and every sample accounted for exactly.
#[test]
fn icm_corrupted_fifo_count_counts_no_phantom_samples() {
    let (sim, hooks, mut imu) = icm(12);
    let mut out = [RawSample::default(); 160];
    let delivered = imu.fifo_stats().samples;
    sim.borrow_mut().tick(2);
    hooks.add(
        Kind::Read(icm::FIFO_COUNTH),
        0,
        Action::Overwrite(vec![(0, 0x00), (1, 0xA0)]),
    );
    assert_eq!(imu.read_fifo(&mut out), Ok(2));
    assert_eq!(imu.fifo_stats().malformed, 0);
    assert_accounted(&sim, &imu, delivered + 2, "a count corrupted high");
}

/// ICM-42688-P: the FIFO_CONFIG1 write of `enable_fifo` corrupted on the wire (0x00: no
/// channel into the FIFO; SPI reports success). The FIFO stayed empty, and as FIFO_CONFIG still
/// read stream mode, `read_fifo` returned Ok(0) call after call on a healthy bus.
/// Expected: the FIFO found off ([`Error::SensorReset`]), and samples flowing after `recover`.
#[test]
fn icm_corrupted_channel_write_is_found_and_recovered() {
    let (sim, hooks, mut imu) = icm(13);
    let mut out = [RawSample::default(); 160];
    hooks.add(
        Kind::Write(icm::FIFO_CONFIG1),
        1,
        Action::Corrupt(vec![(1, 0x00)]),
    );
    // The reset's two writes of FIFO_CONFIG1: channels off, then (corrupted) on.
    assert!(imu.enable_fifo().is_ok());
    sim.borrow_mut().tick(20);
    assert_eq!(imu.read_fifo(&mut out), Err(Error::SensorReset));
    imu.recover(&mut NoDelay, 2_000).unwrap();
    // The gyro starts again: its first samples carry the invalid marker.
    sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP) + 20);
    assert_eq!(imu.read_fifo(&mut out), Ok(20));
}

/// ICM-42688-P: `FifoStats::invalid` counts FIFO packets the chip marked invalid, and README's
/// accounting ("every sample the chip writes into its FIFO is delivered or counted ...
/// invalid") relies on it; `Icm42688::read()` (a data-register read, no FIFO packet) added to
/// it too, so a firmware polling `read()` while the FIFO ran got more samples accounted than
/// written.
/// Expected: `invalid` unchanged by `read()`.
#[test]
fn icm_register_read_leaves_the_fifo_invalid_count() {
    let (sim, hooks, mut imu) = icm(11);
    let mut out = [RawSample::default(); 160];
    let before = imu.fifo_stats().invalid;
    // The data registers hold the invalid marker in GYRO_DATA_X (bytes 8-9 of the burst).
    hooks.add(
        Kind::Read(0x1D),
        0,
        Action::Overwrite(vec![(8, 0x80), (9, 0x00)]),
    );
    assert_eq!(imu.read(), Err(Error::NoData));
    sim.borrow_mut().tick(4);
    let k = imu.read_fifo(&mut out).unwrap();
    assert_eq!(k, 4);
    assert_eq!(
        imu.fifo_stats().invalid,
        before,
        "no FIFO packet was invalid, yet FifoStats::invalid grew"
    );
}

/// Both chips (shared resync and reset): a FIFO read fails part-way (5 of 96 bytes clocked
/// out), the FIFO_COUNT retries all fail, then the reset fails too. The whole failed transfer
/// (96 bytes) used to be booked as consumed and 24 as held; the next call read FIFO_COUNT =
/// 115 (the bytes really left) and took it as held on top of the 96: 211 bytes, 17 samples
/// "discarded" out of the 10 the chip ever wrote.
/// Expected: FifoResync { discarded: 10 }, discarded_bytes 120.
#[test]
fn failed_count_retries_then_failed_reset_count_exactly() {
    let (sim, _hooks, mut imu) = mpu(12);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    // read_fifo's own two FIFO_COUNT reads pass; resync's 4 retries fail.
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_COUNTH), 2, 0);
    for _ in 0..3 {
        sim.borrow_mut().fail(Kind::Read(mpu::FIFO_COUNTH), 0, 0);
    }
    sim.borrow_mut().fail(Kind::Write(mpu::FIFO_EN), 0, 0);
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    let r = imu.read_fifo(&mut out);
    assert_accounted(&sim, &imu, 0, "failed count retries, then a failed reset");
    assert_eq!(r, Err(Error::FifoResync { discarded: 10 }));
}

/// ICM-42688-P: a header with HEADER_ACCEL and HEADER_GYRO set and HEADER_20 (bit 4: a 20-byte
/// packet 4, which this reader never configures) means the stream is not the 16-byte packet 3
/// the reader assumes (corruption, or a packet whose layout differs). It was delivered as a
/// sample.
/// Expected: counted as malformed, not delivered.
#[test]
fn icm_header_20_packet_is_malformed() {
    let (sim, hooks, mut imu) = icm(13);
    let mut out = [RawSample::default(); 160];
    sim.borrow_mut().tick(1);
    hooks.add(
        Kind::Read(icm::FIFO_DATA),
        0,
        Action::Overwrite(vec![(0, 0x78)]),
    );
    let malformed = imu.fifo_stats().malformed;
    let r = imu.read_fifo(&mut out);
    assert_eq!(
        (r, imu.fifo_stats().malformed - malformed),
        (Err(Error::FifoResync { discarded: 0 }), 1),
        "a packet with HEADER_20 set was delivered as a 16-byte sample"
    );
}

/// MPU-6050: `enable_fifo` before `init` left the chip asleep (PWR_MGMT_1.SLEEP, its power-on
/// state) but wrote USER_CTRL.FIFO_EN, so `read_fifo` returned `Ok(0)` forever: no sample, no
/// error. It is now `Error::NotInitialised`.
/// Expected: an error (FifoDisabled / SensorReset / NotRunning) or samples.
#[test]
fn mpu_enable_fifo_before_init_is_an_error() {
    let sim = Sim::new(Model::Mpu6050, 14);
    let mut imu = Mpu6050::new(SimI2c(sim.clone()), 0x68);
    assert_eq!(imu.enable_fifo(), Err(Error::NotInitialised));
    let mut out = [RawSample::default(); 16];
    let mut results = Vec::new();
    for _ in 0..10 {
        sim.borrow_mut().tick(10);
        results.push(imu.read_fifo(&mut out));
    }
    assert!(
        results.iter().any(|r| *r != Ok(0)),
        "100 sample periods, Ok(0) every time: {results:?}"
    );
}

/// MPU-6050: the FIFO holds 85 packets (1020 of its 1024 bytes), INT_STATUS shows no overflow
/// and both FIFO_COUNT reads say 1020; one sample arrives before the first FIFO_R_W transfer.
/// The full FIFO overwrites its 8 oldest bytes, so every packet read is shifted by 8 bytes:
/// the reader delivered 85 misaligned samples, counted nowhere.
/// Expected: no malformed sample delivered; the FIFO reset as an overflow, and what it drops
/// counted.
#[test]
fn mpu_overflow_during_a_near_full_read_delivers_no_misaligned_sample() {
    for (sim, hooks, mut imu) in mpu_both(11) {
        let mut out = [RawSample::default(); 128];
        sim.borrow_mut().tick(85);
        hooks.add(Kind::Read(mpu::FIFO_R_W), 0, Action::TickBefore(1));
        let r = imu.read_fifo(&mut out);
        if let Ok(k) = r {
            let garbage = out[..k].iter().filter(|s| decode(s).is_none()).count();
            assert_eq!(garbage, 0, "{garbage} of {k} samples delivered misaligned");
        }
        assert!(
            matches!(r, Err(Error::FifoOverflow { .. })),
            "{r:?}: the overflow during the read is reported"
        );
        // The next calls deliver aligned samples again.
        sim.borrow_mut().tick(20);
        let k = imu.read_fifo(&mut out).unwrap();
        assert_eq!(k, 20);
        assert!(out[..k].iter().all(|s| decode(s).is_some()));
    }
}

/// Both chips: 10 packets in the FIFO, a sample arrives just before the FIFO_R_W transfer,
/// which then fails after clocking out all of its bytes. The reset
/// drops 11 samples, but the reader reported `FifoResync { discarded: 10 }`: one sample
/// neither delivered nor counted.
/// Expected: the sample counted as unsure (`FifoStats::unsure`: the counts cannot tell it from
/// a transfer that clocked out one packet more), so that discarded <= dropped <= discarded +
/// unsure; the unsure samples no more than the transfer's length leaves room for.
#[test]
fn resync_after_a_sample_arrived_before_the_failed_read_counts_it_as_unsure() {
    // The first transfer asks for 96 bytes (8 packets, one chunk) of 132, clocks out
    // `clock_out` and fails; the count after it is 132 - clock_out, taken as clock_out - 12
    // bytes out (nothing entered): the packets the 96 leave room for beyond those are unsure.
    for (clock_out, unsure) in [(usize::MAX, 1), (60, 4), (0, 8)] {
        for (sim, hooks, mut imu) in mpu_both(12) {
            let mut out = [RawSample::default(); 128];
            sim.borrow_mut().tick(10);
            hooks.add(Kind::Read(mpu::FIFO_R_W), 0, Action::TickBefore(1));
            sim.borrow_mut()
                .fail(Kind::Read(mpu::FIFO_R_W), 0, clock_out);
            let r = imu.read_fifo(&mut out);
            assert!(matches!(r, Err(Error::FifoResync { .. })), "{r:?}");
            let s = imu.fifo_stats();
            let sim = sim.borrow();
            let dropped = sim.produced - sim.fifo_packets();
            assert!(
                s.discarded <= dropped && dropped <= s.discarded + s.unsure,
                "clock-out {clock_out}: {dropped} dropped, {s:?}"
            );
            assert_eq!(s.unsure, unsure, "clock-out {clock_out}: {s:?}");
        }
    }
}

/// ICM-42688-P: one FIFO_DATA transfer takes one byte fewer out of the FIFO than it returns,
/// and reports success (SPI has no acknowledge). From then on every header the reader assumed
/// was the previous packet's last byte: the packets were counted as malformed but the FIFO
/// never flushed, so `read_fifo` returned Ok(0) call after call on a healthy bus, and about 1
/// in 16 shifted packets passed the header test and was delivered.
/// Expected: the malformed header flushes the FIFO (a resync); no misaligned sample is
/// delivered; samples flow again; every sample accounted for.
#[test]
fn icm_byte_slip_is_resynchronised() {
    for seed in 0..16 {
        for (sim, hooks, mut imu) in icm_both(100 + seed) {
            let mut out = [RawSample::default(); 160];
            let before = imu.fifo_stats();
            let produced = sim.borrow().produced;
            sim.borrow_mut().tick(12);
            hooks.add(Kind::Read(icm::FIFO_DATA), 0, Action::Slip);
            let mut delivered = 0u64;
            let mut resynced = false;
            for _ in 0..5 {
                match imu.read_fifo(&mut out) {
                    Ok(k) => {
                        let garbage = out[..k].iter().filter(|s| decode(s).is_none()).count();
                        assert_eq!(garbage, 0, "seed {seed}: misaligned samples delivered");
                        delivered += k as u64;
                    }
                    Err(Error::FifoResync { .. }) => resynced = true,
                    Err(e) => panic!("seed {seed}: {e:?}"),
                }
                sim.borrow_mut().tick(10);
            }
            assert!(resynced, "seed {seed}: the slip was never resynchronised");
            let k = imu.read_fifo(&mut out).unwrap();
            assert!(k >= 10, "seed {seed}: samples do not flow again ({k})");
            delivered += k as u64;
            let s = imu.fifo_stats();
            let sim = sim.borrow();
            let counted = delivered
                + (s.discarded - before.discarded)
                + (s.malformed - before.malformed)
                + (s.invalid - before.invalid)
                + sim.fifo_packets();
            // The slipped byte leaves a partial packet: the counts reckon whole packets.
            let written = sim.produced - produced;
            assert!(
                counted <= written && written <= counted + (s.unsure - before.unsure) + 1,
                "seed {seed}: wrote {written}, accounted {counted}: {s:?}"
            );
        }
    }
}

/// The Black Pill example's loop (`sensor::FifoLoop`, which the example runs) on the simulated
/// MPU-6050 at 100 Hz and a simulated 84 MHz DWT cycle counter, one pass every 50 ms. The
/// sensor is unplugged for 120 s (the chip unpowered: it writes nothing, every transfer
/// fails), then plugged back (the chip starts from power-on). The example's clock extends the
/// 32-bit counter (51 s per wrap) and was read only on some of the loop's arms: through the
/// outage it missed two wraps, `recover` was passed 17.8 s instead of 120.1 s, and `lost` came
/// out about 10,200 samples short.
/// Expected: `lost` is the outage's samples, and every sample the chip wrote is delivered or
/// counted.
#[test]
fn board_loop_counts_a_two_minute_unplug() {
    use imu_ar::sensor::FifoLoop;
    let sim = Sim::new(Model::Mpu6050, 21);
    let config = Mpu6050Config::default(); // 100 Hz
    let mut blocking = Mpu6050::new(SimI2c(sim.clone()), 0x68);
    blocking.init(&mut NoDelay, config).unwrap();
    blocking.enable_fifo().unwrap();
    two_minute_unplug(&sim, |board, counter, out| {
        let pass = board.pass(|| counter, &mut blocking, &mut NoDelay, out);
        (pass, blocking.fifo_stats())
    });
    // The async reader and FifoLoop::pass_async on the same session.
    let sim = Sim::new(Model::Mpu6050, 21);
    let mut reader = Mpu6050Async::new(AsyncBus(SimI2c(sim.clone())), 0x68);
    block_on(reader.init(&mut AsyncNoDelay, config)).unwrap();
    block_on(reader.enable_fifo()).unwrap();
    two_minute_unplug(&sim, |board: &mut FifoLoop, counter, out| {
        let pass = block_on(board.pass_async(|| counter, &mut reader, &mut AsyncNoDelay, out));
        (pass, reader.fifo_stats())
    });
}

/// [`board_loop_counts_a_two_minute_unplug`] with the pass `step` (the loop, the cycle
/// counter, the buffer: what the pass did and the reader's counts after it).
fn two_minute_unplug(
    sim: &Rc<RefCell<Sim>>,
    mut step: impl FnMut(
        &mut imu_ar::sensor::FifoLoop,
        u32,
        &mut [RawSample],
    ) -> (
        imu_ar::sensor::Pass<i2c::ErrorKind>,
        imu_ar::sensor::FifoStats,
    ),
) {
    use imu_ar::sensor::{CycleClock, FifoLoop, Pass};
    const HZ: u64 = 84_000_000;
    // Cycles, wrapping at 32 bits; time in microseconds kept exactly beside it.
    let mut t_us: u64 = 5_000_000;
    let counter = |t_us: u64| ((t_us * (HZ / 1_000_000)) % (1 << 32)) as u32;
    let mut board = FifoLoop::new(CycleClock::new(84, counter(t_us)), counter(t_us), 100_000);
    let mut out = [RawSample::default(); 32];
    let (mut delivered, mut recovered) = (0u64, None);
    let (unplug, replug) = (60_000_000u64, 180_000_000u64);
    let mut stats = imu_ar::sensor::FifoStats::default();
    // The chip's sample clock: one sample per 10 ms while powered.
    let mut chip_us = t_us;
    while t_us < 300_000_000 {
        t_us += 50_000;
        let powered = !(unplug..replug).contains(&t_us);
        if t_us >= replug && sim.borrow().unplugged {
            sim.borrow_mut().unplugged = false;
            sim.borrow_mut().glitch();
        }
        if !powered {
            sim.borrow_mut().unplugged = true;
        }
        if powered {
            let due = (t_us - chip_us) / 10_000;
            sim.borrow_mut().tick(due);
            chip_us += due * 10_000;
        } else {
            chip_us = t_us;
        }
        let (pass, now) = step(&mut board, counter(t_us), &mut out);
        stats = now;
        match pass {
            Pass::Samples(n) => {
                assert!(out[..n].iter().all(|s| decode(s).is_some()));
                delivered += n as u64;
            }
            Pass::Recovered { outage_us } => recovered = Some(outage_us),
            Pass::Failed(_) | Pass::Dropped(_) | Pass::RecoveryFailed(_) => {}
        }
    }
    let outage = recovered.expect("recovered after the unplug");
    // From the last read before the unplug (at most one pass before it) to the replug's
    // recovery (at most one pass after it), plus the recovery's 100 ms.
    assert!(
        (120_000_000..=120_200_000).contains(&outage),
        "recover was passed {outage} us"
    );
    let s = stats;
    assert_eq!(s.lost, (outage + 5_000) / 10_000, "{s:?}");
    // The chip wrote only while powered: all of it delivered or still in the FIFO.
    let sim = sim.borrow();
    assert_eq!(
        delivered + s.discarded + sim.fifo_packets(),
        sim.produced,
        "{s:?}"
    );
}

/// MPU-6050 at 1 kHz on 100 kHz I2C: a 96-byte FIFO_R_W transfer takes about 9 ms, so about 9
/// samples arrive per 8 packets read and the FIFO grows by a packet per transfer. With 77
/// packets at the count (100 bytes of room) the FIFO overflowed before the 10th transfer: the
/// reader delivered Ok(77) with misaligned samples and no overflow counted, since it checked
/// INT_STATUS after a read only when the count left less than 8 packets of room.
/// Expected: no misaligned sample delivered; the overflow counted.
#[test]
fn mpu_samples_arriving_during_a_read_with_eight_packets_of_room_misalign_nothing() {
    let (_, imu, r) = read_through_an_overflow(32);
    assert!(matches!(r, Err(Error::FifoOverflow { .. })), "{r:?}");
    assert_eq!(imu.fifo_stats().overflows, 1);
}

/// What [`read_through_an_overflow`] leaves: the chip, the reader and what its read returned.
type Overflowed = (
    Rc<RefCell<Sim>>,
    Mpu6050<HookedI2c>,
    Result<usize, Error<embedded_hal::i2c::ErrorKind>>,
);

/// An MPU-6050 at 1 kHz read from 77 packets while 9 samples arrive before each of its
/// transfers after the first (the FIFO overflows before the 10th).
fn read_through_an_overflow(seed: u64) -> Overflowed {
    let (sim, hooks, mut imu) = mpu(seed);
    let r = read_while_samples_arrive(&sim, &hooks, &mut imu, 77, 9);
    (sim, imu, r)
}

/// `held` samples in the FIFO, then `arriving` more before each FIFO_R_W transfer after the
/// first, for the transfers of one read: what the read returns, checked to deliver no
/// misaligned sample.
fn read_while_samples_arrive(
    sim: &Rc<RefCell<Sim>>,
    hooks: &Hooks,
    imu: &mut Mpu6050<HookedI2c>,
    held: u64,
    arriving: u64,
) -> Result<usize, Error<embedded_hal::i2c::ErrorKind>> {
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(held);
    hooks.add(Kind::Read(mpu::FIFO_R_W), 1, Action::TickBefore(arriving));
    for _ in 0..held.div_ceil(8) {
        hooks.add(Kind::Read(mpu::FIFO_R_W), 0, Action::TickBefore(arriving));
    }
    let r = imu.read_fifo(&mut out);
    let garbage = match r {
        Ok(k) => out[..k].iter().filter(|s| decode(s).is_none()).count(),
        Err(_) => 0,
    };
    assert_eq!(garbage, 0, "{r:?}: {garbage} misaligned samples delivered");
    r
}

/// As above at 8 kHz (`Dlpf::Hz260`, divider 0) on 400 kHz I2C: about 18 samples arrive
/// during each 96-byte transfer; 65 packets at the count (20 packets of room): Ok(65) with 41
/// misaligned.
#[test]
fn mpu_8khz_read_with_twenty_packets_of_room_misaligns_nothing() {
    let config = Mpu6050Config {
        dlpf: Dlpf::Hz260,
        sample_rate_divider: 0,
        ..mpu_config()
    };
    let (sim, hooks, mut imu) = mpu_with(90, config);
    let r = read_while_samples_arrive(&sim, &hooks, &mut imu, 65, 18);
    assert!(matches!(r, Err(Error::FifoOverflow { .. })), "{r:?}");
}

/// The read above, then the next call's INT_STATUS read fails after clearing the flag: with
/// the overflow missed, the FIFO stayed 8 bytes off and every later sample was garbage (570 of
/// them), with no error and no overflow counted.
/// Expected: no garbage; samples flow.
#[test]
fn mpu_an_overflow_during_a_read_leaves_no_misaligned_fifo_behind() {
    let (sim, mut imu, _) = read_through_an_overflow(32);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut()
        .fail_applied(Kind::Read(mpu::INT_STATUS), 0);
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    let (mut good, mut garbage) = (0, 0);
    for _ in 0..50 {
        if let Ok(k) = imu.read_fifo(&mut out) {
            for s in &out[..k] {
                if decode(s).is_some() {
                    good += 1;
                } else {
                    garbage += 1;
                }
            }
        }
        sim.borrow_mut().tick(10);
    }
    assert_eq!(garbage, 0, "{good} good, {garbage} garbage");
    assert!(good >= 400, "{good} good");
}

/// MPU-6050: a reset is pending (a failed data read whose FIFO reset failed); the next call's
/// first FIFO_COUNT reads 0x0273 instead of 0x0073 (one bit of FIFO_COUNTH). A pending reset
/// took the largest count seen as what it drops, unconfirmed: 52 samples "discarded" of the
/// 10 the chip wrote.
/// Expected: discarded no more than the chip wrote.
#[test]
fn mpu_corrupted_count_during_a_pending_reset_discards_only_what_was_written() {
    let (sim, hooks, mut imu) = mpu(34);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    sim.borrow_mut().fail(Kind::Write(mpu::FIFO_EN), 0, 0);
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    hooks.add(
        Kind::Read(mpu::FIFO_COUNTH),
        0,
        Action::Overwrite(vec![(0, 0x02)]),
    );
    let r = imu.read_fifo(&mut out);
    let s = imu.fifo_stats();
    assert!(
        s.discarded <= sim.borrow().produced,
        "{r:?}: the chip wrote 10: {s:?}"
    );
    assert_accounted(&sim, &imu, 0, "a corrupted count while a reset is pending");
}

/// FifoLoop: samples the chip writes while a pass's read runs, and that its FIFO reset drops,
/// are counted in `discarded`; the pass's clock was read before the read only, so when the
/// next pass found a chip reset, the outage passed to `recover` covered them again (`lost`):
/// 55 counted for 50 sample periods.
/// Expected: every sample period counted once.
#[test]
fn board_loop_counts_samples_written_during_a_resync_pass_once() {
    use imu_ar::sensor::{CycleClock, FifoLoop, Pass};
    let (sim, hooks, mut imu) = mpu(50); // 1 kHz: one tick per ms
    let counter = |t_ms: u64| ((t_ms * 84_000) % (1 << 32)) as u32;
    let mut board = FifoLoop::new(CycleClock::new(84, counter(0)), counter(0), 0);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    let p0 = board.pass(|| counter(10), &mut imu, &mut NoDelay, &mut out);
    assert_eq!(p0, Pass::Samples(10));
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    hooks.add(Kind::Write(mpu::FIFO_EN), 0, Action::TickBefore(5));
    // The pass takes 5 ms: the counter reads 20 ms before the read and 25 ms after it.
    let mut t = [20u64, 25].into_iter();
    let p1 = board.pass(
        || counter(t.next().unwrap_or(25)),
        &mut imu,
        &mut NoDelay,
        &mut out,
    );
    assert_eq!(p1, Pass::Dropped(Error::FifoResync { discarded: 15 }));
    // Then the chip resets and writes nothing for 25 ms.
    sim.borrow_mut().glitch();
    sim.borrow_mut().tick(25);
    let p2 = board.pass(|| counter(50), &mut imu, &mut NoDelay, &mut out);
    assert!(matches!(p2, Pass::Recovered { .. }), "{p2:?}");
    let s = imu.fifo_stats();
    let sim = sim.borrow();
    let accounted = s.samples + s.discarded + s.lost + sim.fifo_packets();
    assert_eq!(accounted, sim.ticks, "{p2:?}: {s:?}");
}

/// FifoLoop, ICM-42688-P: a malformed header was counted in `malformed` at once, but the call
/// ended in Err(Bus) (its FIFO reset failed), which accounts for nothing; the chip reset, and
/// the outage passed to `recover` ran from the pass before: the packet was counted in
/// `malformed` and in `lost` (21 for 20).
/// Expected: every sample period counted once.
#[test]
fn board_loop_counts_a_malformed_packet_of_a_failed_call_once() {
    use imu_ar::sensor::{CycleClock, FifoLoop, Pass};
    let (sim, hooks, mut imu) = icm(80);
    let counter = |t_ms: u64| ((t_ms * 84_000) % (1 << 32)) as u32;
    let t0 = sim.borrow().ticks;
    let mut board = FifoLoop::new(CycleClock::new(84, counter(0)), counter(0), 0);
    let mut out = [RawSample::default(); 160];
    sim.borrow_mut().tick(10);
    let p0 = board.pass(|| counter(10), &mut imu, &mut NoDelay, &mut out);
    assert_eq!(p0, Pass::Samples(10));
    sim.borrow_mut().tick(4);
    hooks.add(
        Kind::Read(icm::FIFO_DATA),
        0,
        Action::Overwrite(vec![(48, 0x00)]),
    );
    sim.borrow_mut().fail(Kind::Write(icm::FIFO_CONFIG1), 0, 0);
    let p1 = board.pass(|| counter(14), &mut imu, &mut NoDelay, &mut out);
    assert!(matches!(p1, Pass::Failed(Error::Bus(_))), "{p1:?}");
    sim.borrow_mut().glitch();
    sim.borrow_mut().tick(6);
    let p2 = board.pass(|| counter(20), &mut imu, &mut NoDelay, &mut out);
    assert!(matches!(p2, Pass::Recovered { .. }), "{p2:?}");
    let s = imu.fifo_stats();
    let sim = sim.borrow();
    let accounted = s.samples + s.discarded + s.malformed + s.lost + sim.fifo_packets();
    assert_eq!(accounted, sim.ticks - t0, "{p2:?}: {s:?}");
}

/// ICM-42688-P: a byte slip before a packet whose timestamp's low byte looks like a header
/// (0x60 to 0x6F: accelerometer and gyro, no 20-byte flag) was never found: the next call's
/// one shifted packet passed the header test and was delivered, garbage. The chip writes whole
/// packets, so after a slip its FIFO holds part of one: the count says, at the end of the
/// slipped read and at the start of every call.
/// Expected: for every timestamp byte, no misaligned sample is delivered, the slip is
/// resynchronised and samples flow again; both readers.
#[test]
fn icm_slip_before_a_header_like_byte_delivers_nothing_misaligned() {
    for before in 0..64u64 {
        for (sim, hooks, mut imu) in icm_both(500 + before) {
            let mut out = [RawSample::default(); 160];
            // Drain, then the slipped read of one to three packets; then one more packet.
            sim.borrow_mut().tick(before);
            let _ = imu.read_fifo(&mut out);
            let produced = sim.borrow().produced;
            // The slipped packet's timestamp low byte: 0x60 + (before % 16) for before < 64,
            // by aligning the producer's count.
            let next = (produced & !0xFF) + 0x160 + (before % 16);
            let wait = next - produced;
            sim.borrow_mut().tick(wait);
            let _ = imu.read_fifo(&mut out);
            sim.borrow_mut().tick(1 + before % 3);
            hooks.add(Kind::Read(icm::FIFO_DATA), 0, Action::Slip);
            let mut resynced = false;
            for k in 0..4 {
                match imu.read_fifo(&mut out) {
                    Ok(n) => {
                        let garbage = out[..n].iter().filter(|s| decode(s).is_none()).count();
                        assert_eq!(garbage, 0, "before {before}, call {k}: garbage delivered");
                    }
                    Err(Error::FifoResync { .. }) => resynced = true,
                    Err(e) => panic!("before {before}: {e:?}"),
                }
                sim.borrow_mut().tick(1);
            }
            assert!(resynced, "before {before}: the slip was not found");
            sim.borrow_mut().tick(5);
            let n = imu.read_fifo(&mut out).unwrap();
            assert!(n >= 5 && out[..n].iter().all(|s| decode(s).is_some()));
        }
    }
}

/// MPU-6050: the chip resets itself (a supply glitch) between the reader's FIFO_COUNT reads
/// and its FIFO_R_W read. The reset FIFO is off and empty, and its reads repeat a byte: the
/// reader delivered those bytes as samples (all zeros).
/// Expected: nothing delivered, `Error::SensorReset`; `recover` brings samples back; both
/// readers.
#[test]
fn mpu_chip_reset_during_a_read_delivers_nothing() {
    for (sim, hooks, mut imu) in mpu_both(31) {
        let mut out = [RawSample::default(); 64];
        sim.borrow_mut().tick(10);
        hooks.add(Kind::Read(mpu::FIFO_R_W), 0, Action::GlitchBefore);
        let r = imu.read_fifo(&mut out);
        assert_eq!(r, Err(Error::SensorReset), "{r:?}");
        assert_eq!(imu.fifo_stats().samples, 0);
        assert_eq!(imu.fifo_stats().discarded, 0);
    }
    // Recovered (the blocking reader, as the board loop does).
    let (sim, hooks, mut imu) = mpu(31);
    let mut out = [RawSample::default(); 64];
    sim.borrow_mut().tick(10);
    hooks.add(Kind::Read(mpu::FIFO_R_W), 0, Action::GlitchBefore);
    assert_eq!(imu.read_fifo(&mut out), Err(Error::SensorReset));
    imu.recover(&mut NoDelay, 10_000).unwrap();
    sim.borrow_mut().tick(5);
    let n = imu.read_fifo(&mut out).unwrap();
    assert_eq!(n, 5);
    assert!(out[..n].iter().all(|s| decode(s).is_some()));
    assert_eq!(imu.fifo_stats().resets, 1);
}

/// Both chips: the FIFO overflows during the data read, and the INT_STATUS read that closes
/// the read fails after clearing the flag. The call's packets were dropped and the FIFO reset,
/// but counted as a resync: the overflow was lost.
/// Expected: a FIFO found full by the reset is an overflow, flag or not: `overflows` 1.
#[test]
fn failed_closing_int_status_read_still_counts_the_overflow() {
    for (sim, hooks, mut imu) in mpu_both(41) {
        let mut out = [RawSample::default(); 128];
        sim.borrow_mut().tick(80);
        hooks.add(Kind::Read(mpu::FIFO_R_W), 0, Action::TickBefore(10));
        // The opening INT_STATUS read, then the closing one, which fails once applied.
        sim.borrow_mut()
            .fail_applied(Kind::Read(mpu::INT_STATUS), 1);
        let r = imu.read_fifo(&mut out);
        assert!(matches!(r, Err(Error::FifoOverflow { .. })), "{r:?}");
        let s = imu.fifo_stats();
        assert_eq!((s.overflows, s.resyncs), (1, 0), "{s:?}");
    }
    for (sim, hooks, mut imu) in icm_both(41) {
        let mut out = [RawSample::default(); 160];
        sim.borrow_mut().tick(120);
        hooks.add(Kind::Read(icm::FIFO_DATA), 0, Action::TickBefore(10));
        sim.borrow_mut()
            .fail_applied(Kind::Read(icm::INT_STATUS), 1);
        let r = imu.read_fifo(&mut out);
        assert!(matches!(r, Err(Error::FifoOverflow { .. })), "{r:?}");
        let s = imu.fifo_stats();
        assert_eq!((s.overflows, s.resyncs), (1, 0), "{s:?}");
    }
}

/// An async read whose future is dropped part-way (a timeout or a `select` in an embassy
/// task), after each of its transfers in turn: the packets its completed transfers took out of
/// the FIFO were neither delivered nor counted, and the MPU-6050's FIFO (no headers) stayed
/// misaligned. The next call settles a read left part-way as a failed read (a FIFO reset,
/// its bytes counted).
/// Expected: after every cancel point, no misaligned sample is delivered and every sample is
/// delivered or counted (within `unsure`, the bytes of the transfer the cancel cut).
#[test]
fn async_read_cancelled_at_every_transfer_loses_nothing_uncounted() {
    use std::pin::pin;
    use std::task::{Context, Poll, Waker};
    fn check<R: ImuReader>(
        sim: &Rc<RefCell<Sim>>,
        imu: &mut R,
        mut cancelled: impl FnMut(&mut R, &mut [RawSample]) -> Option<usize>,
        what: &str,
    ) where
        R::BusError: std::fmt::Debug,
    {
        let mut out = [RawSample::default(); 160];
        let (produced, before) = (sim.borrow().produced, imu.fifo_stats());
        sim.borrow_mut().tick(20);
        let mut delivered = cancelled(imu, &mut out).unwrap_or(0) as u64;
        for _ in 0..3 {
            sim.borrow_mut().tick(5);
            match imu.read_fifo(&mut out) {
                Ok(n) => {
                    assert!(
                        out[..n].iter().all(|s| decode(s).is_some()),
                        "{what}: a misaligned sample delivered"
                    );
                    delivered += n as u64;
                }
                Err(Error::FifoResync { .. } | Error::FifoOverflow { .. }) => {}
                Err(e) => panic!("{what}: {e:?}"),
            }
        }
        let s = imu.fifo_stats();
        let counted = delivered
            + (s.discarded - before.discarded)
            + (s.invalid - before.invalid)
            + (s.malformed - before.malformed)
            + sim.borrow().fifo_packets();
        let written = sim.borrow().produced - produced;
        let unsure = s.unsure - before.unsure;
        assert!(
            counted <= written && written <= counted + unsure,
            "{what}: wrote {written}, accounted {counted} (unsure {unsure}): {s:?}"
        );
    }
    type MpuA = Awaited<Mpu6050Async<AsyncBus<SimI2c>>>;
    type IcmA = Awaited<Icm42688Async<AsyncBus<SimSpi>>>;
    for polls in 1..14 {
        let sim = Sim::new(Model::Mpu6050, 61);
        let mut imu: MpuA = Awaited(Mpu6050Async::new(AsyncBus(SimI2c(sim.clone())), 0x68));
        block_on(imu.0.init(&mut AsyncNoDelay, mpu_config())).unwrap();
        block_on(imu.0.enable_fifo()).unwrap();
        let cancel = |imu: &mut MpuA, out: &mut [RawSample]| {
            let mut cx = Context::from_waker(Waker::noop());
            let mut future = pin!(imu.0.read_fifo(out));
            (0..polls).find_map(|_| match future.as_mut().poll(&mut cx) {
                Poll::Ready(r) => Some(r.unwrap_or(0)),
                Poll::Pending => None,
            })
        };
        check(
            &sim,
            &mut imu,
            cancel,
            &format!("MPU-6050, dropped after {polls} polls"),
        );

        let sim = Sim::new(Model::Icm42688, 61);
        let mut imu: IcmA = Awaited(Icm42688Async::new(AsyncBus(SimSpi(sim.clone()))));
        block_on(imu.0.init(&mut AsyncNoDelay, icm_config())).unwrap();
        block_on(imu.0.enable_fifo()).unwrap();
        sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
        let mut out = [RawSample::default(); 160];
        assert_eq!(imu.read_fifo(&mut out), Ok(0));
        let cancel = |imu: &mut IcmA, out: &mut [RawSample]| {
            let mut cx = Context::from_waker(Waker::noop());
            let mut future = pin!(imu.0.read_fifo(out));
            (0..polls).find_map(|_| match future.as_mut().poll(&mut cx) {
                Poll::Ready(r) => Some(r.unwrap_or(0)),
                Poll::Pending => None,
            })
        };
        check(
            &sim,
            &mut imu,
            cancel,
            &format!("ICM-42688-P, dropped after {polls} polls"),
        );
    }
}
