//! Red team: targeted defects of the sensor readers, each one scenario on the simulator.

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::spi::{Operation, SpiDevice};
use imu_ar::sensor::{
    Dlpf, Error, FifoStats, Icm42688, Icm42688Config, IcmGyroRange, ImuReader, Mpu6050,
    Mpu6050Config, Odr, RawSample,
};

use crate::sim::hooks::{Action, HookedI2c, HookedSpi, Hooks};
use crate::sim::icm42688::{self as icm, SimSpi};
use crate::sim::mpu6050::{self as mpu, SimI2c};
use crate::sim::{Kind, Model, NoDelay, Sim, decode};

fn mpu_config() -> Mpu6050Config {
    Mpu6050Config {
        dlpf: Dlpf::Hz44,
        sample_rate_divider: 0,
        ..Mpu6050Config::default()
    }
}

fn icm_config() -> Icm42688Config {
    Icm42688Config {
        odr: Odr::Hz1000,
        ..Icm42688Config::default()
    }
}

fn mpu(seed: u64) -> (Rc<RefCell<Sim>>, Hooks, Mpu6050<HookedI2c>) {
    let sim = Sim::new(Model::Mpu6050, seed);
    let hooks = Hooks::default();
    let bus = HookedI2c {
        sim: sim.clone(),
        inner: SimI2c(sim.clone()),
        hooks: hooks.clone(),
    };
    let mut imu = Mpu6050::new(bus, 0x68);
    imu.init(&mut NoDelay, mpu_config()).unwrap();
    imu.enable_fifo().unwrap();
    (sim, hooks, imu)
}

fn icm_with(seed: u64, config: Icm42688Config) -> (Rc<RefCell<Sim>>, Hooks, Icm42688<HookedSpi>) {
    let sim = Sim::new(Model::Icm42688, seed);
    let hooks = Hooks::default();
    let bus = HookedSpi {
        sim: sim.clone(),
        inner: SimSpi(sim.clone()),
        hooks: hooks.clone(),
    };
    let mut imu = Icm42688::new(bus);
    imu.init(&mut NoDelay, config).unwrap();
    imu.enable_fifo().unwrap();
    sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
    let mut out = [RawSample::default(); 160];
    assert_eq!(imu.read_fifo(&mut out), Ok(0));
    (sim, hooks, imu)
}

fn icm(seed: u64) -> (Rc<RefCell<Sim>>, Hooks, Icm42688<HookedSpi>) {
    icm_with(seed, icm_config())
}

/// delivered + discarded + invalid + malformed + lost + left in the FIFO, against what the
/// chip wrote.
fn accounted<R: ImuReader>(sim: &Rc<RefCell<Sim>>, imu: &R, delivered: u64) -> (u64, u64) {
    let s = imu.fifo_stats();
    let sim = sim.borrow();
    (
        delivered + s.discarded + s.invalid + s.malformed + s.lost + sim.fifo_packets(),
        sim.produced,
    )
}

// ---------------------------------------------------------------------------------------------

/// Both chips: the FIFO reset's own FIFO_COUNT read (channels off, read once, unconfirmed) is
/// corrupted on the wire. The reader takes the largest count seen as what the reset drops, so
/// one corrupted count makes it "discard" samples the chip never wrote. README: "Nothing is
/// counted that the chip did not write" and the count confirmation "so that a count corrupted
/// on the wire is not dropped as samples".
/// Expected: discarded <= what the chip wrote (10).
#[test]
fn mpu_corrupted_count_inside_the_fifo_reset_counts_phantom_samples() {
    let (sim, hooks, mut imu) = mpu(1);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    // The data read fails (nothing clocked out): resync reads FIFO_COUNT (3rd of the call),
    // then the reset reads it with the channels off (4th): that one reads 0x0278.
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 0);
    hooks.add(
        Kind::Read(mpu::FIFO_COUNTH),
        3,
        Action::Overwrite(vec![(0, 0x02)]),
    );
    let r = imu.read_fifo(&mut out);
    let s = imu.fifo_stats();
    let (counted, written) = accounted(&sim, &imu, 0);
    assert!(
        s.discarded <= written && counted == written,
        "{r:?}: the chip wrote {written}, the reader discarded {}: {s:?}",
        s.discarded
    );
}

/// ICM-42688-P, same defect: the count the reset reads after taking the channels off.
#[test]
fn icm_corrupted_count_inside_the_fifo_reset_counts_phantom_samples() {
    let (sim, hooks, mut imu) = icm(2);
    let mut out = [RawSample::default(); 160];
    let base = imu.fifo_stats();
    let p0 = sim.borrow().produced;
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(icm::FIFO_DATA), 0, 0);
    hooks.add(
        Kind::Read(icm::FIFO_COUNTH),
        3,
        Action::Overwrite(vec![(0, 0x04)]),
    );
    let r = imu.read_fifo(&mut out);
    let s = imu.fifo_stats();
    let written = sim.borrow().produced - p0;
    let discarded = s.discarded - base.discarded;
    assert!(
        discarded <= written,
        "{r:?}: the chip wrote {written}, the reader discarded {discarded}: {s:?}"
    );
}

/// Both chips: with a count of exactly the FIFO's size read once on the wire (the second,
/// "confirming" FIFO_COUNT read of the call), the reader takes the smaller count to read by,
/// but decides "overflow" on the larger, unconfirmed one: the 10 good samples are discarded
/// and an overflow the chip never had is counted.
/// Expected: Ok(10), overflows 0.
#[test]
fn mpu_second_count_corrupted_to_full_is_a_phantom_overflow() {
    let (sim, hooks, mut imu) = mpu(3);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    hooks.add(
        Kind::Read(mpu::FIFO_COUNTH),
        1,
        Action::Overwrite(vec![(0, 0x04), (1, 0x00)]),
    );
    let r = imu.read_fifo(&mut out);
    assert_eq!(
        (r, imu.fifo_stats().overflows),
        (Ok(10), 0),
        "{:?}",
        imu.fifo_stats()
    );
}

#[test]
fn icm_second_count_corrupted_to_full_is_a_phantom_overflow() {
    let (sim, hooks, mut imu) = icm(4);
    let mut out = [RawSample::default(); 160];
    sim.borrow_mut().tick(10);
    hooks.add(
        Kind::Read(icm::FIFO_COUNTH),
        1,
        Action::Overwrite(vec![(0, 0x08), (1, 0x00)]),
    );
    let r = imu.read_fifo(&mut out);
    assert_eq!(
        (r, imu.fifo_stats().overflows),
        (Ok(10), 0),
        "{:?}",
        imu.fifo_stats()
    );
}

/// Both chips: a full FIFO keeps overwriting (samples keep arriving). The call reads (and
/// clears) INT_STATUS, finds the FIFO full and resets it; a sample arriving between that
/// INT_STATUS read and the reset's channels-off write overwrites again and sets the flag
/// anew. The flag survives the reset, so the NEXT call takes it for a new overflow: it drops
/// the 5 good, aligned samples written since, and counts a second overflow.
/// Expected: after the one overflow, the next call delivers the 5 samples; overflows 1.
#[test]
fn mpu_stale_overflow_flag_after_the_reset_drops_good_samples_and_double_counts() {
    let (sim, hooks, mut imu) = mpu(5);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(100);
    // The first FIFO_COUNT read of the call: one more sample overwrites the full FIFO.
    hooks.add(Kind::Read(mpu::FIFO_COUNTH), 0, Action::TickBefore(1));
    let r1 = imu.read_fifo(&mut out);
    assert!(matches!(r1, Err(Error::FifoOverflow { .. })), "{r1:?}");
    sim.borrow_mut().tick(5);
    let r2 = imu.read_fifo(&mut out);
    let s = imu.fifo_stats();
    assert_eq!((r2, s.overflows), (Ok(5), 1), "{s:?}");
}

#[test]
fn icm_stale_overflow_flag_after_the_reset_drops_good_samples_and_double_counts() {
    let (sim, hooks, mut imu) = icm(6);
    let mut out = [RawSample::default(); 160];
    sim.borrow_mut().tick(140);
    hooks.add(Kind::Read(icm::FIFO_COUNTH), 0, Action::TickBefore(1));
    let r1 = imu.read_fifo(&mut out);
    assert!(matches!(r1, Err(Error::FifoOverflow { .. })), "{r1:?}");
    sim.borrow_mut().tick(5);
    let r2 = imu.read_fifo(&mut out);
    let s = imu.fifo_stats();
    assert_eq!((r2, s.overflows), (Ok(5), 1), "{s:?}");
}

/// ICM-42688-P: the FIFO flush write (SIGNAL_PATH_RESET.FIFO_FLUSH) of a FIFO reset is
/// corrupted on the wire (SPI reports success): the FIFO is not emptied, but the reader books
/// its 10 samples as discarded, then delivers the same 10 samples on the next call: every one
/// counted twice. README: "Nothing is counted that the chip did not write".
/// Expected: delivered + discarded == written.
#[test]
fn icm_corrupted_flush_write_counts_samples_twice() {
    let (sim, hooks, mut imu) = icm(7);
    let mut out = [RawSample::default(); 160];
    let base = imu.fifo_stats();
    let p0 = sim.borrow().produced;
    sim.borrow_mut().tick(10);
    // A damaged header (malformed packet): the call is dropped and the FIFO reset.
    hooks.add(
        Kind::Read(icm::FIFO_DATA),
        0,
        Action::Overwrite(vec![(0, 0x00)]),
    );
    hooks.add(
        Kind::Write(icm::SIGNAL_PATH_RESET),
        0,
        Action::Corrupt(vec![(1, 0x00)]),
    );
    let r1 = imu.read_fifo(&mut out);
    let r2 = imu.read_fifo(&mut out);
    let delivered = match r2 {
        Ok(k) => {
            assert!(out[..k].iter().all(|s| decode(s).is_some()));
            k as u64
        }
        _ => 0,
    };
    let s = imu.fifo_stats();
    let written = sim.borrow().produced - p0;
    let counted = delivered
        + (s.discarded - base.discarded)
        + (s.malformed - base.malformed)
        + sim.borrow().fifo_packets();
    assert_eq!(
        counted, written,
        "{r1:?} then {r2:?}: the chip wrote {written}, accounted {counted}: {s:?}"
    );
}

/// ICM-42688-P: the FIFO reset's channels-off write (FIFO_CONFIG1 = 0) is corrupted on the
/// wire and leaves the channels on; the reset reads the count, a sample arrives, and the flush
/// drops it: neither delivered nor counted.
/// Expected: every sample the chip wrote accounted for.
#[test]
fn icm_corrupted_channels_off_write_loses_a_sample_uncounted() {
    let (sim, hooks, mut imu) = icm(8);
    let mut out = [RawSample::default(); 160];
    let base = imu.fifo_stats();
    let p0 = sim.borrow().produced;
    sim.borrow_mut().tick(10);
    // A damaged header (malformed packet): the call is dropped and the FIFO reset.
    hooks.add(
        Kind::Read(icm::FIFO_DATA),
        0,
        Action::Overwrite(vec![(0, 0x00)]),
    );
    hooks.add(
        Kind::Write(icm::FIFO_CONFIG1),
        0,
        Action::Corrupt(vec![(1, 0x07)]),
    );
    hooks.add(
        Kind::Write(icm::SIGNAL_PATH_RESET),
        0,
        Action::TickBefore(1),
    );
    let r1 = imu.read_fifo(&mut out);
    sim.borrow_mut().tick(3);
    let r2 = imu.read_fifo(&mut out);
    let delivered = match r2 {
        Ok(k) => k as u64,
        _ => 0,
    };
    let s = imu.fifo_stats();
    let written = sim.borrow().produced - p0;
    let counted = delivered
        + (s.discarded - base.discarded)
        + (s.malformed - base.malformed)
        + sim.borrow().fifo_packets();
    assert!(
        counted == written || written <= counted + (s.unsure - base.unsure),
        "{r1:?} then {r2:?}: the chip wrote {written}, accounted {counted}, unsure {}: {s:?}",
        s.unsure - base.unsure
    );
}

/// Reads one register of the simulated ICM-42688-P straight off its SPI bus.
fn icm_register(sim: &Rc<RefCell<Sim>>, reg: u8) -> u8 {
    let mut b = [0u8];
    SimSpi(sim.clone())
        .transaction(&mut [Operation::Write(&[reg | 0x80]), Operation::Read(&mut b)])
        .unwrap();
    b[0]
}

/// ICM-42688-P: a GYRO_CONFIG0 write of `init` corrupted on the wire (or a chip reset between
/// the configuration writes, before PWR_MGMT0) leaves the gyro at another full-scale range
/// and rate than the configuration, and nothing reads it back: `init` and `enable_fifo`
/// succeed and every sample is delivered, scaled by `scale()` for 250 dps while the chip
/// measures at another range (the 8x error here).
/// Expected: the mismatch found (an error, or a recovery) before samples are delivered.
#[test]
fn icm_gyro_range_lost_in_init_is_never_noticed() {
    let config = Icm42688Config {
        gyro_range: IcmGyroRange::Dps250,
        odr: Odr::Hz1000,
        ..Icm42688Config::default()
    };
    // A chip reset (supply glitch) between GYRO_CONFIG0 and ACCEL_CONFIG0.
    let sim = Sim::new(Model::Icm42688, 9);
    let hooks = Hooks::default();
    let bus = HookedSpi {
        sim: sim.clone(),
        inner: SimSpi(sim.clone()),
        hooks: hooks.clone(),
    };
    let mut imu = Icm42688::new(bus);
    hooks.add(Kind::Write(0x50), 0, Action::GlitchBefore); // ACCEL_CONFIG0
    let init = imu.init(&mut NoDelay, config);
    let enable = imu.enable_fifo();
    sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP) + 10);
    let mut out = [RawSample::default(); 160];
    let read = imu.read_fifo(&mut out);
    let written = (3 << 5) | 6; // Dps250, 1 kHz
    let gyro_config0 = icm_register(&sim, 0x4F);
    assert!(
        gyro_config0 == written || init.is_err() || enable.is_err() || read.is_err(),
        "init {init:?}, enable_fifo {enable:?}, read_fifo {read:?}: samples delivered with \
         GYRO_CONFIG0 = {gyro_config0:#04x}, configured {written:#04x} (scale {:?})",
        imu.scale()
    );
}

/// `init` again on a running reader with an overflow detected and its FIFO reset pending
/// (the reset's write failed): `init` dropped the pending reset, and the overflow was counted
/// nowhere (README: "An overflow is never lost"; `recover` counts it, `init` did not), though
/// the stats carried on across `init`.
/// Expected (as fixed): `init` begins a new session, its counts from zero: the chip reset it
/// makes drops the old session's FIFO, and its counts are the old session's, read before.
/// After it, the new session's samples only.
#[test]
fn mpu_init_again_loses_a_pending_overflow() {
    let (sim, _hooks, mut imu) = mpu(10);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(100);
    sim.borrow_mut().fail(Kind::Write(mpu::FIFO_EN), 0, 0);
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    imu.init(&mut NoDelay, mpu_config()).unwrap();
    assert_eq!(imu.fifo_stats(), FifoStats::default());
    imu.enable_fifo().unwrap();
    sim.borrow_mut().tick(5);
    assert_eq!(imu.read_fifo(&mut out), Ok(5));
    let s = imu.fifo_stats();
    assert_eq!((s.samples, s.overflows, s.discarded), (5, 0, 0), "{s:?}");
}

/// `recover` on a reader whose FIFO was never enabled counts an outage's worth of samples
/// as `lost`, though with the FIFO off the chip wrote none ("Nothing is counted that the chip
/// did not write").
/// Expected: lost 0.
#[test]
fn recover_without_fifo_counts_lost_samples_never_written() {
    let sim = Sim::new(Model::Mpu6050, 11);
    let mut imu = Mpu6050::new(SimI2c(sim.clone()), 0x68);
    imu.init(&mut NoDelay, mpu_config()).unwrap();
    sim.borrow_mut().tick(1000);
    imu.recover(&mut NoDelay, 1_000_000).unwrap();
    assert_eq!(
        (imu.fifo_stats().lost, sim.borrow().produced),
        (0, 0),
        "{:?}",
        imu.fifo_stats()
    );
}
