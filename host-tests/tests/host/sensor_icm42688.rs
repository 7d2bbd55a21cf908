//! The ICM-42688-P reader: register by register against mocked buses (embedded-hal-mock 0.11,
//! `eh1`; every mock ends with `.done()`, which fails the test if an expected transfer did not
//! happen), then against the register-level simulator (`sim`): each defect of issue 24 that
//! the simulator reproduces, and a long run with random bus faults.

use crate::common;
use crate::sim;
use crate::sim::asynch::{AsyncBus, AsyncNoDelay, Awaited, block_on};
use crate::sim::run::fault_run;

use std::cell::RefCell;
use std::rc::Rc;

use common::expect_samples;
use embedded_hal::spi::{ErrorType, Operation, SpiDevice};
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as Spi};
use imu_ar::sensor::{
    AccelUnit, Error, GyroUnit, Icm42688, Icm42688Async, Icm42688Config, IcmAccelRange,
    IcmGyroRange, ImuReader, Odr, RawSample, Thermometer,
};
use sim::icm42688::{self as icm, SimSpi};
use sim::{Kind, Model, NoDelay, Sim, decode};

// ---- Against mocked buses ----

fn spi_read(reg: u8, response: Vec<u8>) -> Vec<Spi<u8>> {
    vec![
        Spi::transaction_start(),
        Spi::write(reg | 0x80),
        Spi::read_vec(response),
        Spi::transaction_end(),
    ]
}

fn spi_write(reg: u8, value: u8) -> Vec<Spi<u8>> {
    vec![
        Spi::transaction_start(),
        Spi::write_vec(vec![reg, value]),
        Spi::transaction_end(),
    ]
}

fn icm_config() -> Icm42688Config {
    Icm42688Config {
        gyro_range: IcmGyroRange::Dps250,
        accel_range: IcmAccelRange::G4,
        odr: Odr::Hz100,
    }
}

/// The init sequence of `icm_config()` (DS-000347 bank 0 registers).
fn icm_init() -> Vec<Spi<u8>> {
    [
        spi_read(0x75, vec![0x47]),  // WHO_AM_I
        spi_write(0x11, 0x01),       // DEVICE_CONFIG: soft reset
        spi_write(0x4F, 3 << 5 | 8), // GYRO_CONFIG0: +-250 deg/s, 100 Hz
        spi_write(0x50, 2 << 5 | 8), // ACCEL_CONFIG0: +-4 g, 100 Hz
        spi_write(0x4E, 0x0F),       // PWR_MGMT0: gyro and accel low noise
        // The three read back (SPI writes have no acknowledge).
        spi_read(0x4F, vec![3 << 5 | 8]),
        spi_read(0x50, vec![2 << 5 | 8]),
        spi_read(0x4E, vec![0x0F]),
    ]
    .concat()
}

fn icm_fifo_enable() -> Vec<Spi<u8>> {
    [spi_write(0x16, 0x40), icm_fifo_reset(0)].concat() // FIFO_CONFIG: stream-to-FIFO
}

/// The FIFO flush, channels off around it, with `held` bytes in the FIFO once they are off;
/// an empty FIFO is checked against a chip reset (PWR_MGMT0).
fn icm_fifo_reset(held: u16) -> Vec<Spi<u8>> {
    let mut v = [
        spi_write(0x5F, 0x00),                       // FIFO_CONFIG1: no channels
        spi_read(0x5F, vec![0x00]),                  // read back: off
        spi_read(0x2E, held.to_be_bytes().to_vec()), // FIFO_COUNT
        spi_read(0x2E, held.to_be_bytes().to_vec()), // confirmed
        spi_read(0x2D, vec![0x00]),                  // INT_STATUS: no flag raised since
    ]
    .concat();
    if held == 0 {
        v.extend(spi_read(0x4E, vec![0x0F])); // PWR_MGMT0: low noise
    }
    v.extend(spi_write(0x4B, 0x02)); // SIGNAL_PATH_RESET: FIFO_FLUSH
    v.extend(spi_read(0x2E, vec![0, 0])); // FIFO_COUNT: flushed
    v.extend(spi_write(0x5F, 0x07)); // FIFO_CONFIG1: temp, gyro, accel (packet 3)
    v
}

/// What closes a FIFO read that found nothing wrong: INT_STATUS without the overflow flag, the
/// FIFO still in stream mode with its channels on, and a count of `left` bytes, whole packets.
fn icm_read_closed(left: u16) -> Vec<Spi<u8>> {
    [
        spi_read(0x2D, vec![0x00]),                  // INT_STATUS after the read
        spi_read(0x16, vec![0x40]),                  // FIFO_CONFIG: stream mode
        spi_read(0x5F, vec![0x07]),                  // FIFO_CONFIG1: packet 3
        spi_read(0x2E, left.to_be_bytes().to_vec()), // FIFO_COUNT
    ]
    .concat()
}

/// A reader on a mock expecting `expect`, initialised with `icm_config()` and its FIFO on:
/// `expect` begins with `icm_init()` and `icm_fifo_enable()`.
fn icm_with_fifo(expect: &[Spi<u8>]) -> Icm42688<SpiMock<u8>> {
    let mut imu = Icm42688::new(SpiMock::new(expect));
    imu.init(&mut NoopDelay, icm_config()).unwrap();
    imu.enable_fifo().unwrap();
    imu
}

/// Packet 3: header, accel, gyro (big-endian), temperature (1 byte), timestamp (2 bytes).
fn icm_packet(header: u8, a: [i16; 3], g: [i16; 3], temp: i8) -> Vec<u8> {
    let mut p = vec![header];
    p.extend(a.iter().chain(&g).flat_map(|v| v.to_be_bytes()));
    p.push(temp as u8);
    p.extend([0x12, 0x34]);
    p
}

#[test]
fn icm42688_init_read_and_scale() {
    let mut expect = icm_init();
    let mut burst = Vec::new();
    for v in [1325i16, 8192, 0, -8192, 131, -262, 0] {
        burst.extend(v.to_be_bytes());
    }
    expect.extend(spi_read(0x1D, burst));
    let mut imu = Icm42688::new(SpiMock::new(&expect));
    imu.init(&mut NoopDelay, icm_config()).unwrap();
    let s = imu.read().unwrap();
    assert_eq!(
        (s.temperature, s.accel, s.gyro),
        (Some(1325), [8192, 0, -8192], [131, -262, 0])
    );
    // +-4 g: 8192 counts per g; +-250 deg/s: 131 counts per deg/s (DS-000347 3.1, 3.2).
    assert_eq!(imu.scale().accel(s.accel, AccelUnit::G), [1.0, 0.0, -1.0]);
    assert_eq!(
        imu.scale().gyro(s.gyro, GyroUnit::DegPerSec),
        [1.0, -2.0, 0.0]
    );
    assert!((Icm42688::<SpiMock<u8>>::temperature_celsius(1325) - 35.0016).abs() < 1e-3);
    assert_eq!(
        imu.die_temperature(&s),
        Some(Icm42688::<SpiMock<u8>>::temperature_celsius(1325))
    );
    imu.destroy().done();
}

/// The die temperature through the reader, against DS-000347 rev 1.8: TEMP_DATA reads
/// `TEMP_DATA / 132.48 + 25` deg C (section 14, registers 0x1D-0x1E), the 8-bit FIFO
/// temperature `FIFO_TEMP_DATA / 2.07 + 25` (section 6.1), delivered by the reader as 64 times
/// the 8-bit value (132.48 / 64 = 2.07).
#[test]
fn icm42688_die_temperature_is_the_datasheet_formula() {
    let imu = Icm42688::new(SpiMock::new(&[]));
    let register: [(i16, f32); 6] = [
        (0, 25.0),
        (1325, 35.001_51),
        (-3312, 0.0),
        (-8611, -39.998_49),
        (7949, 85.001_51),
        (i16::MIN, 25.0 - 32_768.0 / 132.48),
    ];
    let fifo: [(i8, f32); 5] = [
        (0, 25.0),
        (10, 25.0 + 10.0 / 2.07),
        (-52, 25.0 - 52.0 / 2.07),
        (124, 25.0 + 124.0 / 2.07),
        (i8::MIN + 1, 25.0 - 127.0 / 2.07),
    ];
    let rows = register
        .into_iter()
        .chain(fifo.map(|(t, c)| (i16::from(t) * 64, c)));
    for (raw, celsius) in rows {
        let s = RawSample {
            temperature: Some(raw),
            ..Default::default()
        };
        let got = imu
            .die_temperature(&s)
            .expect("the ICM-42688-P reader knows its formula");
        assert!((got - celsius).abs() <= 1e-4, "{raw}: {got} vs {celsius}");
        assert_eq!(
            got,
            Icm42688::<SpiMock<u8>>::temperature_celsius(raw),
            "{raw}"
        );
    }
    assert_eq!(imu.thermometer(), Some(Thermometer::ICM42688));
    assert_eq!(imu.die_temperature(&RawSample::default()), None);
    imu.destroy().done();
}

#[test]
fn icm42688_sensitivities_are_the_datasheet_values() {
    let gyro = [
        (IcmGyroRange::Dps2000, 16.4),
        (IcmGyroRange::Dps1000, 32.8),
        (IcmGyroRange::Dps500, 65.5),
        (IcmGyroRange::Dps250, 131.0),
        (IcmGyroRange::Dps125, 262.0),
        (IcmGyroRange::Dps62_5, 524.3),
        (IcmGyroRange::Dps31_25, 1048.6),
        (IcmGyroRange::Dps15_625, 2097.2),
    ];
    common::assert_sensitivities(&gyro, IcmGyroRange::counts_per_dps);
    let accel = [
        (IcmAccelRange::G16, 2048.0),
        (IcmAccelRange::G8, 4096.0),
        (IcmAccelRange::G4, 8192.0),
        (IcmAccelRange::G2, 16384.0),
    ];
    common::assert_sensitivities(&accel, IcmAccelRange::counts_per_g);
}

#[test]
fn icm42688_wrong_device_is_a_typed_error() {
    let expect = spi_read(0x75, vec![0x68]);
    let mut imu = Icm42688::new(SpiMock::new(&expect));
    assert_eq!(
        imu.init(&mut NoopDelay, icm_config()),
        Err(Error::WrongDevice { found: 0x68 })
    );
    imu.destroy().done();
}

/// A header that is not one (a wrong layout, or the "FIFO empty" marker inside the counted
/// bytes) most likely means misaligned packets: the call's packets are dropped (the malformed
/// ones counted as such, the rest as discarded) and the FIFO is flushed, which realigns it.
/// The chip writes whole packets, so a count with part of one (a byte slipped on the wire)
/// is misaligned too.
#[test]
fn icm42688_fifo_packets_malformed_empty_and_partial() {
    let mut expect = icm_init();
    expect.extend(icm_fifo_enable());
    expect.extend(spi_read(0x2D, vec![0x08])); // INT_STATUS: data ready
    expect.extend(spi_read(0x2E, vec![0, 2 * 16])); // 2 packets
    expect.extend(spi_read(0x2E, vec![0, 2 * 16])); // the count confirmed
    let data = [
        icm_packet(0x68, [1, 2, 3], [4, 5, 6], 10),
        icm_packet(0x6A, [-1, -2, -3], [-4, -5, -6], -5),
    ]
    .concat();
    expect.extend(spi_read(0x30, data));
    expect.extend(icm_read_closed(0));
    // The next call's second packet is gyro only: malformed for this layout.
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 3 * 16]));
    expect.extend(spi_read(0x2E, vec![0, 3 * 16])); // the count confirmed
    let data = [
        icm_packet(0x68, [7; 3], [7; 3], 0),
        icm_packet(0x28, [0; 3], [7, 8, 9], 0),
        icm_packet(0x68, [8; 3], [8; 3], 0),
    ]
    .concat();
    expect.extend(spi_read(0x30, data));
    expect.extend(icm_fifo_reset(0));
    // An empty-FIFO header inside the counted bytes is a damaged header too.
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 32]));
    expect.extend(spi_read(0x2E, vec![0, 32])); // the count confirmed
    expect.extend(spi_read(
        0x30,
        [
            icm_packet(0x80, [0; 3], [0; 3], 0),
            icm_packet(0x68, [9; 3], [9; 3], 0),
        ]
        .concat(),
    ));
    expect.extend(icm_fifo_reset(0));
    // A packet and 7 bytes: misaligned, nothing read; the flush drops the packet.
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 16 + 7]));
    expect.extend(spi_read(0x2E, vec![0, 16 + 7])); // the count confirmed
    expect.extend(icm_fifo_reset(16 + 7));
    let mut imu = Icm42688::new(SpiMock::new(&expect));
    let mut out = [RawSample::default(); 8];
    assert_eq!(imu.read_fifo(&mut out), Err(Error::FifoDisabled));
    imu.init(&mut NoopDelay, icm_config()).unwrap();
    imu.enable_fifo().unwrap();
    assert_eq!(imu.read_fifo(&mut out), Ok(2));
    assert_eq!(
        (out[0].accel, out[0].gyro, out[0].temperature),
        ([1, 2, 3], [4, 5, 6], Some(640))
    );
    assert_eq!(
        (out[1].accel, out[1].gyro, out[1].temperature),
        ([-1, -2, -3], [-4, -5, -6], Some(-320))
    );
    // FIFO temperature 10 is 10 / 2.07 + 25 deg C, the register form 640 gives the same.
    assert!(
        (Icm42688::<SpiMock<u8>>::temperature_celsius(640) - (10.0 / 2.07 + 25.0)).abs() < 1e-4
    );
    let celsius = imu.die_temperature(&out[0]).unwrap();
    assert!((celsius - (10.0 / 2.07 + 25.0)).abs() < 1e-4, "{celsius}");
    // 2 good packets dropped with the malformed one: 2 discarded.
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoResync { discarded: 2 })
    );
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoResync { discarded: 1 })
    );
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoResync { discarded: 1 })
    );
    let stats = imu.fifo_stats();
    assert_eq!(
        (
            stats.samples,
            stats.malformed,
            stats.discarded,
            stats.resyncs
        ),
        (2, 2, 4, 3)
    );
    imu.destroy().done();
}

#[test]
fn icm42688_fifo_overflow_is_counted_and_recovered() {
    let mut expect = icm_init();
    expect.extend(icm_fifo_enable());
    expect.extend(spi_read(0x2D, vec![0x02])); // FIFO_FULL_INT
    expect.extend(spi_read(0x2E, vec![0x08, 0x00])); // 2048 bytes
    expect.extend(spi_read(0x2E, vec![0x08, 0x00])); // the count confirmed
    expect.extend(icm_fifo_reset(2048));
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 16]));
    expect.extend(spi_read(0x2E, vec![0, 16])); // the count confirmed
    expect.extend(spi_read(0x30, icm_packet(0x68, [1; 3], [2; 3], 0)));
    expect.extend(icm_read_closed(0));
    let mut imu = icm_with_fifo(&expect);
    common::overflow_then_one_sample(&mut imu, 128);
    imu.destroy().done();
}

#[test]
fn icm42688_resetting_itself_is_detected_recovered_and_counted() {
    // One good sample, then the chip resets: FIFO_CONFIG reads back bypass mode. Recovered
    // after 120 ms at 100 Hz: 12 samples lost.
    let mut expect = icm_init();
    expect.extend(icm_fifo_enable());
    expect.extend(spi_read(0x2D, vec![0x08]));
    expect.extend(spi_read(0x2E, vec![0, 16]));
    expect.extend(spi_read(0x2E, vec![0, 16])); // the count confirmed
    expect.extend(spi_read(0x30, icm_packet(0x68, [1; 3], [2; 3], 0)));
    expect.extend(icm_read_closed(0));
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 0]));
    expect.extend(spi_read(0x16, vec![0x00])); // FIFO_CONFIG after a reset: bypass
    expect.extend(icm_init());
    expect.extend(icm_fifo_enable());
    expect.extend(spi_read(0x2D, vec![0x08]));
    expect.extend(spi_read(0x2E, vec![0, 0]));
    expect.extend(spi_read(0x16, vec![0x40])); // stream mode
    expect.extend(spi_read(0x5F, vec![0x07])); // packet 3's channels: simply empty
    let mut imu = icm_with_fifo(&expect);
    let mut out = [RawSample::default(); 4];
    assert_eq!(imu.read_fifo(&mut out), Ok(1));
    assert_eq!(imu.read_fifo(&mut out), Err(Error::SensorReset));
    imu.recover(&mut NoopDelay, 120_000).unwrap();
    assert_eq!(imu.read_fifo(&mut out), Ok(0));
    let stats = imu.fifo_stats();
    assert_eq!((stats.samples, stats.resets, stats.lost), (1, 1, 12));
    imu.destroy().done();
}

/// An SPI device that fails transaction number `fail_at` (counting from 0) and passes the
/// others to a mock.
struct FailingSpi {
    inner: SpiMock<u8>,
    count: usize,
    fail_at: usize,
}

impl ErrorType for FailingSpi {
    type Error = embedded_hal::spi::ErrorKind;
}

impl SpiDevice for FailingSpi {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        let n = self.count;
        self.count += 1;
        if n == self.fail_at {
            return Err(embedded_hal::spi::ErrorKind::Other);
        }
        self.inner
            .transaction(ops)
            .map_err(|_| embedded_hal::spi::ErrorKind::Other)
    }
}

#[test]
fn icm42688_bus_error_at_every_init_step_then_a_clean_init() {
    let steps = 8;
    for fail_at in 0..steps {
        // The mock expects the transactions before the failing one, then a full init.
        let transactions: Vec<Vec<Spi<u8>>> = vec![
            spi_read(0x75, vec![0x47]),
            spi_write(0x11, 0x01),
            spi_write(0x4F, 3 << 5 | 8),
            spi_write(0x50, 2 << 5 | 8),
            spi_write(0x4E, 0x0F),
            spi_read(0x4F, vec![3 << 5 | 8]),
            spi_read(0x50, vec![2 << 5 | 8]),
            spi_read(0x4E, vec![0x0F]),
        ];
        let mut expect: Vec<Spi<u8>> = transactions[..fail_at].concat();
        expect.extend(icm_init());
        let bus = FailingSpi {
            inner: SpiMock::new(&expect),
            count: 0,
            fail_at,
        };
        let mut imu = Icm42688::new(bus);
        let err = imu.init(&mut NoopDelay, icm_config());
        assert_eq!(
            err,
            Err(Error::Bus(embedded_hal::spi::ErrorKind::Other)),
            "step {fail_at}"
        );
        assert_eq!(
            imu.init(&mut NoopDelay, icm_config()),
            Ok(0x47),
            "step {fail_at}"
        );
        imu.destroy().inner.done();
    }
}

/// Issue 24 item 4: the ICM-42688-P's invalid-data marker (-32768; -128 for the FIFO
/// temperature) was delivered as a real sample: -1998 deg/s at +-2000 deg/s, -36.8 deg C.
#[test]
fn icm42688_invalid_marker_is_skipped_and_counted() {
    let mut expect = icm_init();
    expect.extend(icm_fifo_enable());
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 4 * 16]));
    expect.extend(spi_read(0x2E, vec![0, 4 * 16])); // the count confirmed
    let data = [
        icm_packet(0x68, [1, 2, 3], [i16::MIN; 3], 10),
        icm_packet(0x68, [i16::MIN, 0, 0], [4, 5, 6], 10),
        icm_packet(0x68, [1, 2, 3], [4, 5, 6], i8::MIN),
        icm_packet(0x68, [7, 8, 9], [10, 11, 12], 10),
    ]
    .concat();
    expect.extend(spi_read(0x30, data));
    expect.extend(icm_read_closed(0));
    let mut burst = Vec::new();
    for v in [1325i16, 0, 0, 0, i16::MIN, i16::MIN, i16::MIN] {
        burst.extend(v.to_be_bytes());
    }
    expect.extend(spi_read(0x1D, burst));
    let mut imu = icm_with_fifo(&expect);
    let mut out = [RawSample::default(); 8];
    assert_eq!(imu.read_fifo(&mut out), Ok(1));
    assert_eq!((out[0].accel, out[0].gyro), ([7, 8, 9], [10, 11, 12]));
    assert_eq!(
        imu.read(),
        Err(Error::NoData),
        "data registers still invalid"
    );
    let stats = imu.fifo_stats();
    assert_eq!(
        (stats.samples, stats.invalid),
        (1, 3),
        "FIFO packets only: the data-register read is no FIFO packet"
    );
    imu.destroy().done();
}

// ---- Against the simulator ----

/// 1 kHz: one tick per millisecond.
fn config() -> Icm42688Config {
    Icm42688Config {
        odr: Odr::Hz1000,
        ..Icm42688Config::default()
    }
}

/// A reader with its FIFO on and the gyro start-up (invalid samples) behind it.
fn reader(seed: u64) -> (Rc<RefCell<Sim>>, Icm42688<SimSpi>) {
    let sim = Sim::new(Model::Icm42688, seed);
    let mut imu = Icm42688::new(SimSpi(sim.clone()));
    imu.init(&mut NoDelay, config()).unwrap();
    imu.enable_fifo().unwrap();
    sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
    let mut out = [RawSample::default(); 160];
    assert_eq!(imu.read_fifo(&mut out), Ok(0));
    (sim, imu)
}

/// Item 1: a failed FIFO enable inside `recover` left the FIFO off for good.
#[test]
fn recover_that_fails_part_way_is_finished_by_the_next_one() {
    let (sim, mut imu) = reader(1);
    expect_samples(&sim, &mut imu, 5);
    common::recover_after_a_failed_recover(
        &sim,
        &mut imu,
        (Kind::Write(icm::FIFO_CONFIG), 0),
        |imu, us| imu.recover(&mut NoDelay, us),
        0x47,
    );
    let mut out = [RawSample::default(); 16];
    sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
    assert_eq!(imu.read_fifo(&mut out), Ok(0));
    expect_samples(&sim, &mut imu, 7);
    let stats = imu.fifo_stats();
    assert_eq!((stats.resets, stats.lost, stats.samples), (1, 20, 12));
    assert_eq!(stats.invalid, 60, "two gyro start-ups of 30 samples");
}

/// Item 2: FIFO_COUNT fails after INT_STATUS (cleared by the read) reported a full FIFO; the
/// overflow was lost: `overflows 0, discarded 0`, and no flush.
#[test]
fn overflow_survives_a_failed_count_read() {
    let (sim, mut imu) = reader(2);
    sim.borrow_mut().tick(140);
    sim.borrow_mut().fail(Kind::Read(icm::FIFO_COUNTH), 0, 0);
    let mut out = [RawSample::default(); 160];
    common::overflow_after_a_bus_error(&mut imu, &mut out, 128);
    let stats = imu.fifo_stats();
    assert_eq!((stats.overflows, stats.discarded), (1, 128));
    expect_samples(&sim, &mut imu, 9);
}

/// Item 2: the flush fails; the overflow is still counted when the next call flushes.
#[test]
fn overflow_survives_a_failed_flush() {
    let (sim, mut imu) = reader(3);
    sim.borrow_mut().tick(128);
    sim.borrow_mut()
        .fail(Kind::Write(icm::SIGNAL_PATH_RESET), 0, 0);
    let mut out = [RawSample::default(); 160];
    common::overflow_after_a_bus_error(&mut imu, &mut out, 128);
    expect_samples(&sim, &mut imu, 4);
}

/// Item 3 (both chips): a FIFO read that fails part-way is followed by a flush.
#[test]
fn fifo_read_failing_part_way_flushes_the_fifo() {
    let (sim, mut imu) = reader(4);
    sim.borrow_mut().tick(20);
    let mut out = [RawSample::default(); 160];
    let data = (Kind::Read(icm::FIFO_DATA), 21);
    common::resync_after_a_failed_data_read(&sim, &mut imu, &mut out, data, 20);
    assert_eq!(imu.fifo_stats().discarded_bytes, 320);
    expect_samples(&sim, &mut imu, 33);
}

/// Item 4: the gyro's start-up samples carry -32768; they were delivered as -1998 deg/s.
#[test]
fn invalid_marker_after_start_up_is_skipped_and_counted() {
    let sim = Sim::new(Model::Icm42688, 5);
    let mut imu = Icm42688::new(SimSpi(sim.clone()));
    imu.init(&mut NoDelay, config()).unwrap();
    imu.enable_fifo().unwrap();
    sim.borrow_mut().tick(40);
    let mut out = [RawSample::default(); 160];
    assert_eq!(imu.read_fifo(&mut out), Ok(10));
    assert_eq!(
        out[..10].iter().map(decode).collect::<Vec<_>>(),
        (30..40).map(Some).collect::<Vec<_>>()
    );
    let stats = imu.fifo_stats();
    assert_eq!((stats.invalid, stats.samples), (30, 10));
}

/// Item 8: with the bus stuck high, FIFO_COUNT reads 65535: no count at all (not a full
/// FIFO of 128 packets, which would count 123 samples the chip never wrote). Nothing is read
/// or counted; the overflow flag read as set is kept, and once the bus is back the FIFO is
/// flushed and its 5 real samples counted.
#[test]
fn count_above_the_fifo_size_is_no_count() {
    let (sim, mut imu) = reader(7);
    sim.borrow_mut().tick(5);
    let mut out = [RawSample::default(); 160];
    common::stuck_high_count_is_no_count(&sim, &mut imu, &mut out, 1, 5);
    expect_samples(&sim, &mut imu, 6);
}

/// Issue 24 acceptance, as for the MPU-6050.
#[test]
fn random_bus_faults_lose_nothing_uncounted() {
    let (sim, mut imu) = reader(2024);
    let recover = |imu: &mut Icm42688<SimSpi>, us| imu.recover(&mut NoDelay, us).map(|_| ());
    let figures = common::random_bus_faults(&sim, &mut imu, recover, 12, "ICM-42688-P");
    assert!(figures.stats.invalid > 0);
}

/// The async reader ([`Icm42688Async`]) on the same session as the blocking one, faults
/// included, its bus suspending at every transfer: the same transfers, faults, samples and
/// counts, figure for figure.
#[test]
fn async_reader_agrees_with_the_blocking_one_under_random_faults() {
    let (sim, mut imu) = reader(2024);
    let recover = |imu: &mut Icm42688<SimSpi>, us| imu.recover(&mut NoDelay, us).map(|_| ());
    let blocking = fault_run(&sim, &mut imu, recover, 12, 0.01, 100_000);

    let sim = Sim::new(Model::Icm42688, 2024);
    let mut imu = Awaited(Icm42688Async::new(AsyncBus(SimSpi(sim.clone()))));
    block_on(imu.0.init(&mut AsyncNoDelay, config())).unwrap();
    block_on(imu.0.enable_fifo()).unwrap();
    sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
    let mut out = [RawSample::default(); 160];
    assert_eq!(imu.read_fifo(&mut out), Ok(0));
    let recover = |imu: &mut Awaited<Icm42688Async<AsyncBus<SimSpi>>>, us| {
        block_on(imu.0.recover(&mut AsyncNoDelay, us)).map(|_| ())
    };
    let awaited = fault_run(&sim, &mut imu, recover, 12, 0.01, 100_000);
    assert!(
        awaited.delivered >= 100_000 && awaited.faults > 1000,
        "{awaited:#?}"
    );
    assert_eq!(format!("{blocking:?}"), format!("{awaited:?}"));
}

/// The random-fault run with samples arriving during the reader's transfers (5 % of transfers) and byte slips on the
/// FIFO data reads (1 %, SPI reports none), besides the failed transfers: every sample delivered
/// well-formed or counted, exactly; the blocking and the async reader alike.
#[test]
fn random_faults_arrivals_during_transfers_and_slips_lose_nothing_uncounted() {
    let (sim, mut imu) = reader(2025);
    sim.borrow_mut().arrivals = 0.05;
    sim.borrow_mut().slips = 0.01;
    let recover = |imu: &mut Icm42688<SimSpi>, us| imu.recover(&mut NoDelay, us).map(|_| ());
    let blocking = fault_run(&sim, &mut imu, recover, 14, 0.01, 100_000);
    println!("{blocking:#?}, slips {}", sim.borrow().slipped);
    assert!(sim.borrow().slipped > 100);

    let sim = Sim::new(Model::Icm42688, 2025);
    let mut imu = Awaited(Icm42688Async::new(AsyncBus(SimSpi(sim.clone()))));
    block_on(imu.0.init(&mut AsyncNoDelay, config())).unwrap();
    block_on(imu.0.enable_fifo()).unwrap();
    sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
    let mut out = [RawSample::default(); 160];
    assert_eq!(imu.read_fifo(&mut out), Ok(0));
    sim.borrow_mut().arrivals = 0.05;
    sim.borrow_mut().slips = 0.01;
    let recover = |imu: &mut Awaited<Icm42688Async<AsyncBus<SimSpi>>>, us| {
        block_on(imu.0.recover(&mut AsyncNoDelay, us)).map(|_| ())
    };
    let awaited = fault_run(&sim, &mut imu, recover, 14, 0.01, 100_000);
    assert_eq!(format!("{blocking:?}"), format!("{awaited:?}"));
}
