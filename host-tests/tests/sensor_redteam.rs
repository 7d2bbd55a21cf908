//! Red-team tests of the reworked sensor readers (issue 24): each test is a confirmed defect,
//! reproduced against the register-level simulator (`sim`), and fails until it is fixed.
//!
//! Some tests wrap the simulated bus in a `Hooked` bus that advances the chip's clock right
//! before a chosen transfer (on real hardware samples keep arriving while the reader works: a
//! 1 kHz MPU-6050 on 400 kHz I2C writes a sample every ~13 transfers) or corrupts the bytes of
//! a chosen read (a bit error on the wire).

mod sim;

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::i2c::{self, I2c};
use embedded_hal::spi::{self, Operation, SpiDevice};
use imu_ar::sensor::{
    Dlpf, Error, Icm42688, Icm42688Config, ImuReader, Mpu6050, Mpu6050Config, Odr, RawSample,
    Replay, Scale,
};
use sim::{Kind, Model, NoDelay, Sim, SimI2c, SimSpi, decode, icm, mpu};

/// What a hook does at its transfer.
#[derive(Clone)]
enum Action {
    /// The chip writes `n` samples right before the transfer.
    TickBefore(u64),
    /// The read returns these bytes at these offsets (after the chip's own answer).
    Overwrite(Vec<(usize, u8)>),
}

struct Hook {
    kind: Kind,
    skip: u32,
    action: Action,
}

#[derive(Default, Clone)]
struct Hooks(Rc<RefCell<Vec<Hook>>>);

impl Hooks {
    fn add(&self, kind: Kind, skip: u32, action: Action) {
        self.0.borrow_mut().push(Hook { kind, skip, action });
    }

    /// The action due at this transfer of `kind`, if any.
    fn due(&self, kind: Kind) -> Option<Action> {
        let mut hooks = self.0.borrow_mut();
        let i = hooks.iter().position(|h| h.kind == kind)?;
        if hooks[i].skip == 0 {
            Some(hooks.remove(i).action)
        } else {
            hooks[i].skip -= 1;
            None
        }
    }

    fn around(
        &self,
        sim: &Rc<RefCell<Sim>>,
        kind: Kind,
        buf: Option<&mut [u8]>,
        transfer: impl FnOnce(Option<&mut [u8]>) -> bool,
    ) -> bool {
        let action = self.due(kind);
        if let Some(Action::TickBefore(n)) = &action {
            sim.borrow_mut().tick(*n);
        }
        match buf {
            Some(buf) => {
                let ok = transfer(Some(&mut *buf));
                if let Some(Action::Overwrite(bytes)) = action {
                    for (i, b) in bytes {
                        buf[i] = b;
                    }
                }
                ok
            }
            None => transfer(None),
        }
    }
}

/// The simulated MPU-6050's I2C bus with hooks.
struct HookedI2c {
    sim: Rc<RefCell<Sim>>,
    inner: SimI2c,
    hooks: Hooks,
}

impl i2c::ErrorType for HookedI2c {
    type Error = i2c::ErrorKind;
}

impl I2c for HookedI2c {
    fn transaction(
        &mut self,
        address: u8,
        ops: &mut [i2c::Operation<'_>],
    ) -> Result<(), Self::Error> {
        let kind = match &*ops {
            [i2c::Operation::Write(w)] => Kind::Write(w[0]),
            [i2c::Operation::Write(w), i2c::Operation::Read(_)] => Kind::Read(w[0]),
            _ => panic!("unexpected I2C transaction"),
        };
        let mut result = Ok(());
        let inner = &mut self.inner;
        match ops {
            [i2c::Operation::Write(w), i2c::Operation::Read(r)] => {
                let w: &[u8] = w;
                self.hooks.around(&self.sim, kind, Some(&mut **r), |r| {
                    result = inner.write_read(address, w, r.unwrap());
                    result.is_ok()
                });
            }
            _ => {
                self.hooks.around(&self.sim, kind, None, |_| {
                    result = inner.transaction(address, ops);
                    result.is_ok()
                });
            }
        }
        result
    }
}

/// The simulated ICM-42688-P's SPI device with hooks.
struct HookedSpi {
    sim: Rc<RefCell<Sim>>,
    inner: SimSpi,
    hooks: Hooks,
}

impl spi::ErrorType for HookedSpi {
    type Error = spi::ErrorKind;
}

impl SpiDevice for HookedSpi {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        let mut result = Ok(());
        let inner = &mut self.inner;
        match ops {
            [Operation::Write(w)] => {
                let kind = Kind::Write(w[0]);
                let w: &[u8] = w;
                self.hooks.around(&self.sim, kind, None, |_| {
                    result = inner.write(w);
                    result.is_ok()
                });
            }
            [Operation::Write(w), Operation::Read(r)] => {
                let kind = Kind::Read(w[0] & 0x7F);
                let w: &[u8] = w;
                self.hooks.around(&self.sim, kind, Some(&mut **r), |r| {
                    result =
                        inner.transaction(&mut [Operation::Write(w), Operation::Read(r.unwrap())]);
                    result.is_ok()
                });
            }
            _ => panic!("unexpected SPI transaction"),
        }
        result
    }
}

/// 1 kHz: one tick per millisecond.
fn mpu_config() -> Mpu6050Config {
    Mpu6050Config {
        dlpf: Dlpf::Hz44,
        sample_rate_divider: 0,
        ..Mpu6050Config::default()
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
    let config = Icm42688Config {
        odr: Odr::Hz1000,
        ..Icm42688Config::default()
    };
    imu.init(&mut NoDelay, config).unwrap();
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

/// DEFECT 1 (stall, MPU-6050). A chip reset (brown-out) while a FIFO reset is pending after a
/// bus error: the next `read_fifo` finishes the pending reset, which writes USER_CTRL.FIFO_EN
/// and FIFO_EN again on the freshly reset, sleeping chip. That erases the very evidence
/// (USER_CTRL without FIFO_EN) that the reset detection relies on: from then on every
/// `read_fifo` returns `Ok(0)` (empty FIFO, USER_CTRL says "configured"), the chip sleeps with
/// its configuration gone, and no error ever tells the caller to `recover`.
/// Expected: `Error::SensorReset` within a few calls (or samples flowing again).
#[test]
fn mpu_chip_reset_during_pending_fifo_reset_stalls_forever() {
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

/// DEFECT 2 (count lies, MPU-6050; ICM-42688-P's `enable_fifo` is the same). `enable_fifo`
/// that fails at its last write after the write took effect leaves the chip's FIFO running
/// while the reader says `FifoNotRunning`. The documented remedy is to call `enable_fifo`
/// again; it resets the FIFO and the samples the chip wrote in the meantime vanish: not
/// delivered, not `discarded`, not `lost` (enable_fifo takes no outage).
/// Expected: those samples are counted (`discarded`) or delivered.
#[test]
fn enable_fifo_retry_drops_samples_uncounted() {
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

/// DEFECT 3 (count lies, both chips: shared `fifo::finish_reset`). The discarded count of a
/// FIFO reset is taken from FIFO_COUNT read *before* the channels are taken off the FIFO; a
/// sample the chip writes between that count and `FIFO_EN = 0` is dropped by the reset but not
/// counted. README: "the count is exact: the channels are taken off the FIFO before it is
/// emptied". Expected: FifoResync { discarded: 11 } and every sample accounted for.
#[test]
fn reset_drops_sample_written_after_the_count_uncounted() {
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

/// DEFECT 4 (count lies, both chips: `fifo::resync`). After a failed data read, resync computes
/// the bytes the failed transfer consumed as `count_before - count_now` (saturating), assuming
/// the FIFO only shrinks. With the channels still on, a sample arriving meanwhile makes
/// count_now > count_before: the consumed bytes become 0 and the partly read packet is lost
/// from the count (here 5 + 127 = 132 bytes = 11 samples dropped, counted 127 bytes = 10).
/// Expected: FifoResync { discarded: 11 }, discarded_bytes 132.
#[test]
fn resync_with_fifo_growing_meanwhile_undercounts() {
    let (sim, hooks, mut imu) = mpu(4);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    // FIFO_COUNTH is read by read_fifo (skip it), then by resync: a sample arrives before it.
    hooks.add(Kind::Read(mpu::FIFO_COUNTH), 1, Action::TickBefore(1));
    let r = imu.read_fifo(&mut out);
    assert_eq!(
        imu.fifo_stats().discarded_bytes,
        132,
        "bytes dropped: 5 read + 127 left"
    );
    assert_eq!(r, Err(Error::FifoResync { discarded: 11 }));
    assert_accounted(&sim, &imu, 0, "resync with the FIFO growing");
}

/// DEFECT 5 (count lies, both chips). With the bus stuck high (every read 0xFF) each
/// `read_fifo` "discards" a full FIFO: 85 samples per call on the MPU-6050, though the chip
/// wrote one sample between calls. Ten calls count 850 discarded samples out of 12 written.
/// The `discarded` doc: "Complete samples dropped by FIFO resets: those in the FIFO when it was
/// reset". Expected: never more discarded than the chip wrote.
#[test]
fn stuck_high_bus_counts_phantom_discarded_samples() {
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

/// DEFECT 6 (samples vanish uncounted, ICM-42688-P). A header with HEADER_MSG (bit 7, "FIFO
/// empty") in the middle of a batch ends the batch, but the packets after it in the same
/// chunk were already clocked out of the FIFO: they are neither delivered nor counted (not
/// even the marker packet itself is counted as malformed). One corrupted header byte (0xFF on
/// the wire) silently loses up to 8 samples. FIFO_COUNT said 3 packets, so an "empty" marker
/// here is malformed. Expected: the 2 packets counted (malformed/discarded) or delivered.
#[test]
fn icm_empty_marker_mid_batch_loses_following_packets() {
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
    let k = imu.read_fifo(&mut out).unwrap();
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

/// DEFECT 7 (overflow count lost). An overflow whose FIFO reset meets a bus error is pending;
/// `recover` (called for FifoNotRunning, or "any suspected glitch" as its doc invites) clears
/// the pending reset (`FifoState::restarting`) and the overflow is never counted. README: "An
/// overflow is never lost ... every overflow is counted (`overflows`)".
/// Expected: overflows == 1.
#[test]
fn recover_forgets_pending_overflow() {
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

/// DEFECT 8 (doc vs behaviour). `FifoStats::resets` is documented as "Chip resets detected
/// (`Error::SensorReset`) and recovered from", but every successful `recover` increments it,
/// including one after `FifoNotRunning` (a failed `enable_fifo`, no chip reset at all) and a
/// `recover` before the reader was ever initialised. Expected: resets == 0.
#[test]
fn resets_counts_recoveries_not_chip_resets() {
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

/// DEFECT 9 (count lies, `Replay`). `FifoStats::clipped` ("Delivered samples with some axis
/// at a rail") is never counted by `Replay::read_fifo`. Expected: clipped == 1.
#[test]
fn replay_does_not_count_clipped_samples() {
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

/// DEFECT 10 (silent garbage, MPU-6050). A FIFO_COUNT read corrupted on the wire (here 0x0078
/// = 10 packets while the FIFO holds 2) is trusted: the reader reads past the FIFO's end and
/// delivers 8 samples made of the FIFO's repeated last byte, uncounted and undetected.
/// (ArduPilot puts the temperature into the MPU FIFO and checks it to detect such reads;
/// re-reading FIFO_COUNT and taking the smaller is another cheap guard.)
/// Expected: only the 2 samples the chip produced are delivered.
#[test]
fn mpu_corrupted_fifo_count_delivers_garbage() {
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

/// DEFECT 11 (count lies / doc conflict, ICM-42688-P). `FifoStats::invalid` is documented as
/// "FIFO packets skipped because the chip marked their data invalid", and README's accounting
/// ("every sample the chip writes into its FIFO is delivered or counted ... invalid") relies
/// on it; but `Icm42688::read()` (a data-register read, no FIFO packet) adds to it too. A
/// firmware polling `read()` while the FIFO runs gets more samples accounted than written.
/// Expected: `invalid` unchanged by `read()` (count it elsewhere).
#[test]
fn icm_register_read_inflates_fifo_invalid_count() {
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

/// DEFECT 12 (failure of the failure handling over-counts, both chips: `fifo::resync` then
/// `finish_reset`). A FIFO read fails part-way (5 of 96 bytes clocked out), the FIFO_COUNT
/// retries all fail, so resync books the whole failed transfer (96 bytes) as consumed and
/// 120 - 96 = 24 as held; then the reset fails too. The next call reads FIFO_COUNT = 115 (the
/// bytes really left) and takes max(24, 115) as held, on top of the 96 "consumed": 211 bytes,
/// 17 samples "discarded" out of the 10 the chip ever wrote.
/// Expected: FifoResync { discarded: 10 }, discarded_bytes 120.
#[test]
fn failed_count_retries_then_failed_reset_overcounts() {
    let (sim, _hooks, mut imu) = mpu(12);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    // read_fifo's own FIFO_COUNT read passes; resync's 4 retries fail.
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_COUNTH), 1, 0);
    for _ in 0..3 {
        sim.borrow_mut().fail(Kind::Read(mpu::FIFO_COUNTH), 0, 0);
    }
    sim.borrow_mut().fail(Kind::Write(mpu::FIFO_EN), 0, 0);
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    let r = imu.read_fifo(&mut out);
    assert_accounted(&sim, &imu, 0, "failed count retries, then a failed reset");
    assert_eq!(r, Err(Error::FifoResync { discarded: 10 }));
}

/// DEFECT 13 (silent garbage, ICM-42688-P header flags). `parse` accepts any header with
/// HEADER_ACCEL and HEADER_GYRO set, including HEADER_20 (bit 4: a 20-byte packet 4, which
/// this reader never configures). Such a header means the stream is not the 16-byte packet 3
/// the reader assumes (corruption, or a 20-byte packet whose layout differs): the packet is
/// delivered as a sample. Expected: counted as malformed, not delivered.
#[test]
fn icm_header_20_bit_packet_delivered_as_sample() {
    let (sim, hooks, mut imu) = icm(13);
    let mut out = [RawSample::default(); 160];
    sim.borrow_mut().tick(1);
    hooks.add(
        Kind::Read(icm::FIFO_DATA),
        0,
        Action::Overwrite(vec![(0, 0x78)]),
    );
    let malformed = imu.fifo_stats().malformed;
    let k = imu.read_fifo(&mut out).unwrap();
    assert_eq!(
        (k, imu.fifo_stats().malformed - malformed),
        (0, 1),
        "a packet with HEADER_20 set was delivered as a 16-byte sample"
    );
}

/// DEFECT 14 (stall, MPU-6050, edge order). `enable_fifo` before `init` (nothing in its doc
/// requires init first) leaves the chip asleep (PWR_MGMT_1.SLEEP, its power-on state) but
/// writes USER_CTRL.FIFO_EN, so `read_fifo` returns `Ok(0)` forever: no sample, no error, no
/// `SensorReset` (same root cause as defect 1: USER_CTRL is the only glitch evidence checked).
/// Expected: an error (FifoDisabled / SensorReset / NotRunning) or samples.
#[test]
fn mpu_enable_fifo_before_init_reads_nothing_forever() {
    let sim = Sim::new(Model::Mpu6050, 14);
    let mut imu = Mpu6050::new(SimI2c(sim.clone()), 0x68);
    let _ = imu.enable_fifo();
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
