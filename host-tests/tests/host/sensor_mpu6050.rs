//! The MPU-6050 reader: register by register against mocked buses (embedded-hal-mock 0.11,
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
use embedded_hal::i2c::ErrorKind;
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2c};
use imu_ar::sensor::{
    AccelRange, AccelUnit, Dlpf, Error, GyroRange, GyroUnit, ImuReader, Mpu6050, Mpu6050Async,
    Mpu6050Config, RawSample, Thermometer,
};
use sim::mpu6050::{self as mpu, SimI2c};
use sim::{Kind, Model, NoDelay, Sim};

// ---- Against mocked buses ----

const ADDR: u8 = 0x68;

fn mpu_config() -> Mpu6050Config {
    Mpu6050Config {
        gyro_range: GyroRange::Dps500,
        accel_range: AccelRange::G8,
        dlpf: Dlpf::Hz44,
        sample_rate_divider: 9,
    }
}

/// The init sequence of `mpu_config()`, register by register (RM-MPU-6000A-00 rev 4.2).
fn mpu_init() -> Vec<I2c> {
    vec![
        I2c::write_read(ADDR, vec![0x75], vec![0x68]), // WHO_AM_I
        I2c::write(ADDR, vec![0x6B, 0x80]),            // PWR_MGMT_1: DEVICE_RESET
        I2c::write(ADDR, vec![0x6B, 0x01]),            // PWR_MGMT_1: wake, PLL X gyro
        I2c::write(ADDR, vec![0x19, 9]),               // SMPLRT_DIV: 1 kHz / 10
        I2c::write(ADDR, vec![0x1A, 3]),               // CONFIG: DLPF 44 Hz
        I2c::write(ADDR, vec![0x1B, 1 << 3]),          // GYRO_CONFIG: +-500 deg/s
        I2c::write(ADDR, vec![0x1C, 2 << 3]),          // ACCEL_CONFIG: +-8 g
    ]
}

fn mpu_fifo_enable() -> Vec<I2c> {
    let mut v = vec![I2c::write(ADDR, vec![0x38, 0x10])]; // INT_ENABLE: FIFO_OFLOW_EN
    v.extend(mpu_fifo_reset(0));
    v
}

/// The FIFO reset, channels off first (ArduPilot's `_fifo_reset`), with `held` bytes in the
/// FIFO once they are off; an empty FIFO is checked against a chip reset (PWR_MGMT_1).
fn mpu_fifo_reset(held: u16) -> Vec<I2c> {
    let mut v = vec![
        I2c::write(ADDR, vec![0x23, 0x00]), // FIFO_EN: no channels
        I2c::write(ADDR, vec![0x6A, 0x00]), // USER_CTRL: FIFO off
        I2c::write_read(ADDR, vec![0x23], vec![0x00]), // FIFO_EN read back: no channels
        I2c::write_read(ADDR, vec![0x72], held.to_be_bytes().to_vec()), // FIFO_COUNT
        I2c::write_read(ADDR, vec![0x72], held.to_be_bytes().to_vec()), // confirmed
        I2c::write_read(ADDR, vec![0x3A], vec![0x00]), // INT_STATUS: no flag raised since
    ];
    if held == 0 {
        v.push(I2c::write_read(ADDR, vec![0x6B], vec![0x01])); // PWR_MGMT_1: awake, PLL
    }
    v.extend([
        I2c::write(ADDR, vec![0x6A, 0x04]), // USER_CTRL: FIFO_RESET
        I2c::write_read(ADDR, vec![0x72], vec![0, 0]), // FIFO_COUNT: emptied
        I2c::write(ADDR, vec![0x6A, 0x40]), // USER_CTRL: FIFO_EN
        I2c::write(ADDR, vec![0x23, 0x78]), // FIFO_EN: XG YG ZG ACCEL
    ]);
    v
}

/// A reader on a mock expecting `expect`, initialised with `mpu_config()` and its FIFO on:
/// `expect` begins with `mpu_init()` and `mpu_fifo_enable()`.
fn mpu_with_fifo(expect: &[I2c]) -> Mpu6050<I2cMock> {
    let mut imu = Mpu6050::new(I2cMock::new(expect), ADDR);
    imu.init(&mut NoopDelay, mpu_config()).unwrap();
    imu.enable_fifo().unwrap();
    imu
}

/// A FIFO packet: accel x, y, z then gyro x, y, z, big-endian.
fn mpu_packet(a: [i16; 3], g: [i16; 3]) -> Vec<u8> {
    a.iter().chain(&g).flat_map(|v| v.to_be_bytes()).collect()
}

#[test]
fn mpu6050_init_read_and_scale() {
    let mut expect = mpu_init();
    let mut burst = Vec::new();
    for v in [4096i16, -4096, 0, 3400, 655, -655, 0] {
        burst.extend(v.to_be_bytes());
    }
    expect.push(I2c::write_read(ADDR, vec![0x3B], burst));
    let mut imu = Mpu6050::new(I2cMock::new(&expect), ADDR);
    assert_eq!(imu.init(&mut NoopDelay, mpu_config()), Ok(0x68));
    assert_eq!(imu.config().sample_rate_hz(), 100.0);
    let s = imu.read().unwrap();
    assert_eq!(
        (s.accel, s.temperature, s.gyro),
        ([4096, -4096, 0], Some(3400), [655, -655, 0])
    );
    // +-8 g: 4096 counts per g; +-500 deg/s: 65.5 counts per deg/s (PS-MPU-6000A-00 6.1, 6.2).
    assert_eq!(imu.scale().accel(s.accel, AccelUnit::G), [1.0, -1.0, 0.0]);
    assert_eq!(
        imu.scale().gyro(s.gyro, GyroUnit::DegPerSec),
        [10.0, -10.0, 0.0]
    );
    let rad = imu.scale().gyro(s.gyro, GyroUnit::RadPerSec)[0];
    assert!((rad - 10.0f32.to_radians()).abs() < 1e-6);
    let ms2 = imu.scale().accel(s.accel, AccelUnit::MetersPerSec2)[0];
    assert!((ms2 - 9.80665).abs() < 1e-5);
    assert!((Mpu6050::<I2cMock>::temperature_celsius(3400) - 46.53).abs() < 1e-4);
    assert_eq!(imu.die_temperature(&s), Some(46.53));
    imu.destroy().done();
}

/// The die temperature through the reader, against the register map's formula (RM-MPU-6000A-00
/// rev 4.2, registers 65-66: `TEMP_OUT / 340 + 36.53`) and the product specification's offset
/// (PS-MPU-6000A-00 rev 3.4, section 6.4: 35 deg C reads -521 LSB, 340 LSB per deg C). The
/// FIFO's packets carry no temperature.
#[test]
fn mpu6050_die_temperature_is_the_datasheet_formula() {
    let imu = Mpu6050::new(I2cMock::new(&[]), ADDR);
    let table: [(i16, f32, f32); 7] = [
        (-521, 35.0, 0.005), // the specification's offset, to its 3 digits
        (0, 36.53, 1e-4),
        (340, 37.53, 1e-4),
        (3400, 46.53, 1e-4),
        (-12_420, 36.53 - 12_420.0 / 340.0, 1e-4), // 0.0006 deg C
        (i16::MIN, 36.53 - 32_768.0 / 340.0, 1e-4),
        (i16::MAX, 36.53 + 32_767.0 / 340.0, 1e-4),
    ];
    for (raw, celsius, tolerance) in table {
        let s = RawSample {
            temperature: Some(raw),
            ..Default::default()
        };
        let got = imu
            .die_temperature(&s)
            .expect("the MPU-6050 reader knows its formula");
        assert!(
            (got - celsius).abs() <= tolerance,
            "{raw}: {got} vs {celsius}"
        );
        assert_eq!(got, Mpu6050::<I2cMock>::temperature_celsius(raw), "{raw}");
    }
    assert_eq!(imu.thermometer(), Some(Thermometer::MPU6050));
    assert_eq!(imu.die_temperature(&RawSample::default()), None);
    imu.destroy().done();
}

#[test]
fn mpu6050_sensitivities_are_the_datasheet_values() {
    let gyro = [
        (GyroRange::Dps250, 131.0),
        (GyroRange::Dps500, 65.5),
        (GyroRange::Dps1000, 32.8),
        (GyroRange::Dps2000, 16.4),
    ];
    common::assert_sensitivities(&gyro, GyroRange::counts_per_dps);
    let accel = [
        (AccelRange::G2, 16384.0),
        (AccelRange::G4, 8192.0),
        (AccelRange::G8, 4096.0),
        (AccelRange::G16, 2048.0),
    ];
    common::assert_sensitivities(&accel, AccelRange::counts_per_g);
    let c = Mpu6050Config {
        dlpf: Dlpf::Hz260,
        sample_rate_divider: 7,
        ..mpu_config()
    };
    assert_eq!(c.sample_rate_hz(), 1000.0); // 8 kHz gyro rate without the DLPF
}

#[test]
fn mpu6050_wrong_device_is_a_typed_error() {
    let expect = [I2c::write_read(ADDR, vec![0x75], vec![0x12])];
    let mut imu = Mpu6050::new(I2cMock::new(&expect), ADDR);
    assert_eq!(
        imu.init(&mut NoopDelay, mpu_config()),
        Err(Error::WrongDevice { found: 0x12 })
    );
    imu.destroy().done();
}

#[test]
fn mpu6050_bus_error_at_every_init_step_then_a_clean_init() {
    let full = mpu_init();
    for step in 0..full.len() {
        let mut expect: Vec<I2c> = full[..step].to_vec();
        expect.push(full[step].clone().with_error(ErrorKind::Other));
        expect.extend(full.iter().cloned());
        let mut imu = Mpu6050::new(I2cMock::new(&expect), ADDR);
        let err = imu.init(&mut NoopDelay, mpu_config());
        assert_eq!(err, Err(Error::Bus(ErrorKind::Other)), "step {step}");
        // The same reader initialises cleanly when the bus recovers.
        assert_eq!(
            imu.init(&mut NoopDelay, mpu_config()),
            Ok(0x68),
            "step {step}"
        );
        imu.destroy().done();
    }
}

#[test]
fn mpu6050_fifo_whole_packets_chunks_and_partial_packets() {
    let mut expect = mpu_init();
    expect.extend(mpu_fifo_enable());
    // 10 packets and 5 stray bytes: 8 packets in the first transfer, 2 in the second; the
    // partial packet stays in the FIFO.
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x01])); // INT_STATUS: data ready only
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 125])); // FIFO_COUNT = 10*12 + 5
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 125])); // read again: the same
    let packets: Vec<Vec<u8>> = (0..10i16)
        .map(|i| mpu_packet([i, 0, 4096], [-i, 1, 2]))
        .collect();
    expect.push(I2c::write_read(ADDR, vec![0x74], packets[..8].concat()));
    expect.push(I2c::write_read(ADDR, vec![0x74], packets[8..].concat()));
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00])); // INT_STATUS after the read
    expect.push(I2c::write_read(ADDR, vec![0x6A], vec![0x40, 0x01])); // the FIFO still on
    // The next call asks for fewer samples than there are.
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 41])); // 3 packets + 5 bytes
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 41]));
    expect.push(I2c::write_read(ADDR, vec![0x74], packets[..2].concat()));
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00])); // INT_STATUS after the read
    expect.push(I2c::write_read(ADDR, vec![0x6A], vec![0x40, 0x01])); // the FIFO still on
    let mut imu = Mpu6050::new(I2cMock::new(&expect), ADDR);
    let mut out = [RawSample::default(); 16];
    assert_eq!(imu.read_fifo(&mut out), Err(Error::FifoDisabled));
    assert_eq!(imu.enable_fifo(), Err(Error::NotInitialised));
    imu.init(&mut NoopDelay, mpu_config()).unwrap();
    imu.enable_fifo().unwrap();
    assert_eq!(imu.read_fifo(&mut out), Ok(10));
    for (i, s) in out[..10].iter().enumerate() {
        assert_eq!(
            (s.accel, s.gyro, s.temperature),
            ([i as i16, 0, 4096], [-(i as i16), 1, 2], None)
        );
    }
    assert_eq!(imu.read_fifo(&mut out[..2]), Ok(2));
    assert_eq!(imu.fifo_stats().samples, 12);
    imu.destroy().done();
}

#[test]
fn mpu6050_fifo_overflow_is_counted_and_recovered() {
    let mut expect = mpu_init();
    expect.extend(mpu_fifo_enable());
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x10])); // FIFO_OFLOW_INT
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0x04, 0x00])); // 1024 bytes
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0x04, 0x00])); // confirmed
    expect.extend(mpu_fifo_reset(1024));
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 12]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 12]));
    expect.push(I2c::write_read(
        ADDR,
        vec![0x74],
        mpu_packet([1, 2, 3], [4, 5, 6]),
    ));
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00])); // INT_STATUS after the read
    expect.push(I2c::write_read(ADDR, vec![0x6A], vec![0x40, 0x01])); // the FIFO still on
    let mut imu = mpu_with_fifo(&expect);
    common::overflow_then_one_sample(&mut imu, 85);
    imu.destroy().done();
}

#[test]
fn mpu6050_bus_error_mid_fifo_is_propagated_and_counted() {
    let mut expect = mpu_init();
    expect.extend(mpu_fifo_enable());
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 120])); // 10 packets
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 120]));
    let packets: Vec<u8> = (0..8)
        .flat_map(|i| mpu_packet([i, i, i], [i, i, i]))
        .collect();
    expect.push(I2c::write_read(ADDR, vec![0x74], packets));
    expect.push(I2c::write_read(ADDR, vec![0x74], vec![0; 24]).with_error(ErrorKind::Other));
    // FIFO_COUNT tells how much the failed read took out (one packet of the two), then the
    // FIFO is reset to realign the packets: all 10 are discarded.
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 12]));
    expect.extend(mpu_fifo_reset(12));
    // Still usable afterwards.
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 0]));
    // Empty: USER_CTRL with the FIFO on, PWR_MGMT_1 awake on the PLL clock.
    expect.push(I2c::write_read(ADDR, vec![0x6A], vec![0x40, 0x01]));
    let mut imu = mpu_with_fifo(&expect);
    let mut out = [RawSample::default(); 16];
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoResync { discarded: 10 })
    );
    let stats = imu.fifo_stats();
    assert_eq!(
        (stats.discarded, stats.discarded_bytes, stats.resyncs),
        (10, 120, 1),
        "the 8 packets read before the error, and the 2 of the failed read, are lost"
    );
    assert_eq!(imu.read_fifo(&mut out), Ok(0));
    imu.destroy().done();
}

#[test]
fn mpu6050_resetting_itself_is_detected_recovered_and_counted() {
    // Two good samples; then a supply glitch resets the chip: its FIFO is off and empty. The
    // reader finds USER_CTRL cleared, the caller recovers it after an outage of 350 ms (35
    // samples at 100 Hz), and the stream goes on.
    let mut expect = mpu_init();
    expect.extend(mpu_fifo_enable());
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x01]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 24]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 24]));
    let packets = [mpu_packet([1; 3], [2; 3]), mpu_packet([3; 3], [4; 3])];
    expect.push(I2c::write_read(ADDR, vec![0x74], packets.concat()));
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00])); // INT_STATUS after the read
    expect.push(I2c::write_read(ADDR, vec![0x6A], vec![0x40, 0x01])); // the FIFO still on
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 0]));
    // USER_CTRL and PWR_MGMT_1 after a reset: FIFO off, asleep.
    expect.push(I2c::write_read(ADDR, vec![0x6A], vec![0x00, 0x40]));
    // The first recovery attempt meets a bus error at WHO_AM_I; the second succeeds.
    expect.push(I2c::write_read(ADDR, vec![0x75], vec![0x68]).with_error(ErrorKind::Other));
    expect.extend(mpu_init());
    expect.extend(mpu_fifo_enable());
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x01]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 12]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 12]));
    expect.push(I2c::write_read(
        ADDR,
        vec![0x74],
        mpu_packet([5; 3], [6; 3]),
    ));
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00])); // INT_STATUS after the read
    expect.push(I2c::write_read(ADDR, vec![0x6A], vec![0x40, 0x01])); // the FIFO still on
    let mut imu = mpu_with_fifo(&expect);
    let mut out = [RawSample::default(); 4];
    assert_eq!(imu.read_fifo(&mut out), Ok(2));
    assert_eq!(imu.read_fifo(&mut out), Err(Error::SensorReset));
    assert_eq!(
        imu.recover(&mut NoopDelay, 350_000),
        Err(Error::Bus(ErrorKind::Other))
    );
    assert_eq!(
        imu.fifo_stats().resets,
        0,
        "a failed recovery counts nothing"
    );
    assert_eq!(imu.recover(&mut NoopDelay, 350_000), Ok(0x68));
    assert_eq!(imu.read_fifo(&mut out), Ok(1));
    assert_eq!(out[0].gyro, [6; 3]);
    let stats = imu.fifo_stats();
    assert_eq!((stats.samples, stats.resets, stats.lost), (3, 1, 35));
    imu.destroy().done();
}

/// Issue 24 item 6: MPU-6500 and MPU-9250 were handled with MPU-6050 formulas.
#[test]
fn mpu6500_and_mpu9250_are_rejected_clearly() {
    for id in [0x70, 0x71] {
        let expect = [I2c::write_read(ADDR, vec![0x75], vec![id])];
        let mut imu = Mpu6050::new(I2cMock::new(&expect), ADDR);
        let err = imu.init(&mut NoopDelay, mpu_config());
        assert_eq!(err, Err(Error::UnsupportedDevice { found: id }));
        assert!(err.unwrap_err().to_string().contains("not supported"));
        imu.destroy().done();
    }
}

// ---- Against the simulator ----

/// 1 kHz: one tick per millisecond.
fn config() -> Mpu6050Config {
    Mpu6050Config {
        dlpf: Dlpf::Hz44,
        sample_rate_divider: 0,
        ..Mpu6050Config::default()
    }
}

fn reader(seed: u64) -> (Rc<RefCell<Sim>>, Mpu6050<SimI2c>) {
    let sim = Sim::new(Model::Mpu6050, seed);
    let mut imu = Mpu6050::new(SimI2c(sim.clone()), 0x68);
    imu.init(&mut NoDelay, config()).unwrap();
    imu.enable_fifo().unwrap();
    (sim, imu)
}

/// Item 1: a bus error inside `recover` left the FIFO off for good (the next `recover`
/// returned Ok without enabling it, and `read_fifo` said FifoDisabled forever).
#[test]
fn recover_that_fails_part_way_is_finished_by_the_next_one() {
    let (sim, mut imu) = reader(1);
    expect_samples(&sim, &mut imu, 5);
    // The FIFO re-enable inside recover fails at its last USER_CTRL write.
    common::recover_after_a_failed_recover(
        &sim,
        &mut imu,
        (Kind::Write(mpu::USER_CTRL), 2),
        |imu, us| imu.recover(&mut NoDelay, us),
        0x68,
    );
    expect_samples(&sim, &mut imu, 7);
    let stats = imu.fifo_stats();
    assert_eq!((stats.resets, stats.lost, stats.samples), (1, 20, 12));
}

/// Item 2: FIFO_COUNT fails after INT_STATUS (cleared by the read) reported an overflow; the
/// retry read the wrapped FIFO as data (misaligned by 1024 - 85 x 12 = 4 bytes).
#[test]
fn overflow_survives_a_failed_count_read() {
    let (sim, mut imu) = reader(2);
    sim.borrow_mut().tick(100);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_COUNTH), 0, 0);
    let mut out = [RawSample::default(); 128];
    common::overflow_after_a_bus_error(&mut imu, &mut out, 85);
    let stats = imu.fifo_stats();
    assert_eq!((stats.overflows, stats.discarded), (1, 85));
    expect_samples(&sim, &mut imu, 9);
    assert_eq!(
        sim.borrow().dropped,
        15,
        "100 - 85 packets damaged by the chip"
    );
}

/// Item 2: the second USER_CTRL write of the overflow reset fails; the next call reported a
/// SensorReset that never happened (`resets 1, lost 15, overflows 0`).
#[test]
fn overflow_survives_a_failed_reset_write() {
    let (sim, mut imu) = reader(3);
    sim.borrow_mut().tick(100);
    sim.borrow_mut().fail(Kind::Write(mpu::USER_CTRL), 1, 0);
    let mut out = [RawSample::default(); 128];
    common::overflow_after_a_bus_error(&mut imu, &mut out, 85);
    let stats = imu.fifo_stats();
    assert_eq!((stats.overflows, stats.resets, stats.lost), (1, 0, 0));
    expect_samples(&sim, &mut imu, 4);
}

/// Item 3: a FIFO read that fails with 5 bytes clocked out left every later packet
/// misaligned, with `malformed 0`. The FIFO is now reset and the samples counted.
#[test]
fn fifo_read_failing_part_way_resets_the_fifo() {
    let (sim, mut imu) = reader(4);
    sim.borrow_mut().tick(20);
    let mut out = [RawSample::default(); 128];
    let data = (Kind::Read(mpu::FIFO_R_W), 5);
    common::resync_after_a_failed_data_read(&sim, &mut imu, &mut out, data, 20);
    let stats = imu.fifo_stats();
    assert_eq!(
        (stats.resyncs, stats.discarded, stats.discarded_bytes),
        (1, 20, 240)
    );
    for _ in 0..10 {
        expect_samples(&sim, &mut imu, 51);
    }
}

/// Item 3, with the reset itself failing: finished by the next call, counted once.
#[test]
fn fifo_read_failing_then_its_reset_failing() {
    let (sim, mut imu) = reader(5);
    sim.borrow_mut().tick(30);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 1, 7);
    sim.borrow_mut().fail(Kind::Write(mpu::FIFO_EN), 1, 0);
    let mut out = [RawSample::default(); 128];
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    sim.borrow_mut().tick(3); // the channels are off: nothing enters
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoResync { discarded: 30 })
    );
    expect_samples(&sim, &mut imu, 12);
}

/// Item 7: the outage was a `u32` of microseconds, capped at 71.6 minutes.
#[test]
fn lost_over_a_two_hour_outage() {
    let sim = Sim::new(Model::Mpu6050, 6);
    let mut imu = Mpu6050::new(SimI2c(sim.clone()), 0x68);
    imu.init(&mut NoDelay, Mpu6050Config::default()).unwrap(); // 100 Hz
    imu.enable_fifo().unwrap();
    sim.borrow_mut().glitch();
    assert_eq!(imu.recover(&mut NoDelay, 7_200_100_000), Ok(0x68));
    assert_eq!(imu.fifo_stats().lost, 720_010);
}

/// Item 8: with SDA stuck high, INT_STATUS and FIFO_COUNT read 0xFF: 65535 bytes were taken
/// as 5461 discarded samples, though at most 85 fit. A count above the FIFO's size is no
/// count: nothing is read or counted from it (counting a full FIFO, 85, would count 80
/// samples the chip never wrote, at every call while the bus is stuck). The overflow flag read
/// as set is kept: once the bus is back, the FIFO is reset and its 5 real samples counted.
#[test]
fn count_above_the_fifo_size_is_no_count() {
    let (sim, mut imu) = reader(7);
    sim.borrow_mut().tick(5);
    let mut out = [RawSample::default(); 128];
    common::stuck_high_count_is_no_count(&sim, &mut imu, &mut out, 3, 5);
    expect_samples(&sim, &mut imu, 6);
}

/// Item 8: the overflow flag is lost (a failed INT_STATUS read that cleared it), but the count
/// of a full FIFO still says overflow; the misaligned packets were read as data.
#[test]
fn full_fifo_without_its_flag_is_an_overflow() {
    let (sim, mut imu) = reader(8);
    sim.borrow_mut().tick(90);
    sim.borrow_mut()
        .fail_applied(Kind::Read(mpu::INT_STATUS), 0);
    let mut out = [RawSample::default(); 128];
    common::overflow_after_a_bus_error(&mut imu, &mut out, 85);
    expect_samples(&sim, &mut imu, 3);
}

/// Item 9: the FIFO is reset with its channels off (ArduPilot's `_fifo_reset`, and the register
/// map's "FIFO_RESET ... while FIFO_EN equals 0").
#[test]
fn fifo_resets_with_the_channels_off() {
    let (sim, mut imu) = reader(9);
    let mut out = [RawSample::default(); 128];
    sim.borrow_mut().tick(100);
    assert!(matches!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { .. })
    ));
    sim.borrow_mut().tick(10);
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 3);
    assert!(matches!(
        imu.read_fifo(&mut out),
        Err(Error::FifoResync { .. })
    ));
    sim.borrow_mut().glitch();
    imu.recover(&mut NoDelay, 1000).unwrap();
    expect_samples(&sim, &mut imu, 5);
    assert_eq!(sim.borrow().resets_with_channels_on, 0);
}

/// Issue 24 acceptance: >= 10^5 samples with faults at 1 % of every kind of transfer; every
/// sample delivered well-formed or counted, exactly; samples flow again after one recover.
#[test]
fn random_bus_faults_lose_nothing_uncounted() {
    let (sim, mut imu) = reader(2024);
    let recover = |imu: &mut Mpu6050<SimI2c>, us| imu.recover(&mut NoDelay, us).map(|_| ());
    common::random_bus_faults(&sim, &mut imu, recover, 11, "MPU-6050");
    assert_eq!(sim.borrow().resets_with_channels_on, 0);
}

/// The async reader ([`Mpu6050Async`]) on the same session as the blocking one, faults
/// included, its bus suspending at every transfer: the same transfers, faults, samples and
/// counts, figure for figure.
#[test]
fn async_reader_agrees_with_the_blocking_one_under_random_faults() {
    let (sim, mut imu) = reader(2024);
    let recover = |imu: &mut Mpu6050<SimI2c>, us| imu.recover(&mut NoDelay, us).map(|_| ());
    let blocking = fault_run(&sim, &mut imu, recover, 11, 0.01, 100_000);

    let sim = Sim::new(Model::Mpu6050, 2024);
    let mut imu = Awaited(Mpu6050Async::new(AsyncBus(SimI2c(sim.clone())), 0x68));
    block_on(imu.0.init(&mut AsyncNoDelay, config())).unwrap();
    block_on(imu.0.enable_fifo()).unwrap();
    let recover = |imu: &mut Awaited<Mpu6050Async<AsyncBus<SimI2c>>>, us| {
        block_on(imu.0.recover(&mut AsyncNoDelay, us)).map(|_| ())
    };
    let awaited = fault_run(&sim, &mut imu, recover, 11, 0.01, 100_000);
    assert!(
        awaited.delivered >= 100_000 && awaited.faults > 1000,
        "{awaited:#?}"
    );
    assert_eq!(format!("{blocking:?}"), format!("{awaited:?}"));
}

/// The random-fault run with samples arriving during the reader's transfers (5 % of transfers; I2C acknowledges every
/// byte, so no slips), besides the failed transfers: every sample delivered
/// well-formed or counted, exactly; the blocking and the async reader alike.
#[test]
fn random_faults_arrivals_during_transfers_and_slips_lose_nothing_uncounted() {
    let (sim, mut imu) = reader(2025);
    sim.borrow_mut().arrivals = 0.05;
    let recover = |imu: &mut Mpu6050<SimI2c>, us| imu.recover(&mut NoDelay, us).map(|_| ());
    let blocking = fault_run(&sim, &mut imu, recover, 13, 0.01, 100_000);
    println!("{blocking:#?}, slips {}", sim.borrow().slipped);

    let sim = Sim::new(Model::Mpu6050, 2025);
    let mut imu = Awaited(Mpu6050Async::new(AsyncBus(SimI2c(sim.clone())), 0x68));
    block_on(imu.0.init(&mut AsyncNoDelay, config())).unwrap();
    block_on(imu.0.enable_fifo()).unwrap();
    sim.borrow_mut().arrivals = 0.05;
    let recover = |imu: &mut Awaited<Mpu6050Async<AsyncBus<SimI2c>>>, us| {
        block_on(imu.0.recover(&mut AsyncNoDelay, us)).map(|_| ())
    };
    let awaited = fault_run(&sim, &mut imu, recover, 13, 0.01, 100_000);
    assert_eq!(format!("{blocking:?}"), format!("{awaited:?}"));
}
