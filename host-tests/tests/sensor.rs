//! The sensor readers against mocked buses (embedded-hal-mock 0.11, `eh1`); every mock ends
//! with `.done()`, which fails the test if an expected transfer did not happen.

use embedded_hal::i2c::ErrorKind;
use embedded_hal::spi::{ErrorType, Operation, SpiDevice};
use embedded_hal_mock::eh1::delay::NoopDelay;
use embedded_hal_mock::eh1::i2c::{Mock as I2cMock, Transaction as I2c};
use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as Spi};
use imu_ar::sensor::{
    AccelRange, AccelUnit, Dlpf, Error, GyroRange, GyroUnit, Icm42688, Icm42688Config,
    IcmAccelRange, IcmGyroRange, ImuReader, Mpu6050, Mpu6050Config, Odr, RawSample, Replay, Scale,
};

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
        I2c::write_read(ADDR, vec![0x72], held.to_be_bytes().to_vec()), // FIFO_COUNT
    ];
    if held == 0 {
        v.push(I2c::write_read(ADDR, vec![0x6B], vec![0x01])); // PWR_MGMT_1: awake, PLL
    }
    v.extend([
        I2c::write(ADDR, vec![0x6A, 0x04]), // USER_CTRL: FIFO_RESET
        I2c::write(ADDR, vec![0x6A, 0x40]), // USER_CTRL: FIFO_EN
        I2c::write(ADDR, vec![0x23, 0x78]), // FIFO_EN: XG YG ZG ACCEL
    ]);
    v
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
    for (range, counts) in gyro {
        assert_eq!(range.counts_per_dps(), counts, "{range:?}");
    }
    let accel = [
        (AccelRange::G2, 16384.0),
        (AccelRange::G4, 8192.0),
        (AccelRange::G8, 4096.0),
        (AccelRange::G16, 2048.0),
    ];
    for (range, counts) in accel {
        assert_eq!(range.counts_per_g(), counts, "{range:?}");
    }
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
    // The next call asks for fewer samples than there are.
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 41])); // 3 packets + 5 bytes
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 41]));
    expect.push(I2c::write_read(ADDR, vec![0x74], packets[..2].concat()));
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
    expect.extend(mpu_fifo_reset(1024));
    expect.push(I2c::write_read(ADDR, vec![0x3A], vec![0x00]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 12]));
    expect.push(I2c::write_read(ADDR, vec![0x72], vec![0, 12]));
    expect.push(I2c::write_read(
        ADDR,
        vec![0x74],
        mpu_packet([1, 2, 3], [4, 5, 6]),
    ));
    let mut imu = Mpu6050::new(I2cMock::new(&expect), ADDR);
    imu.init(&mut NoopDelay, mpu_config()).unwrap();
    imu.enable_fifo().unwrap();
    let mut out = [RawSample::default(); 4];
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { discarded: 85 })
    );
    assert_eq!(imu.read_fifo(&mut out), Ok(1));
    let stats = imu.fifo_stats();
    assert_eq!(
        (stats.overflows, stats.discarded, stats.samples),
        (1, 85, 1)
    );
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
    let mut imu = Mpu6050::new(I2cMock::new(&expect), ADDR);
    imu.init(&mut NoopDelay, mpu_config()).unwrap();
    imu.enable_fifo().unwrap();
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
    let mut imu = Mpu6050::new(I2cMock::new(&expect), ADDR);
    imu.init(&mut NoopDelay, mpu_config()).unwrap();
    imu.enable_fifo().unwrap();
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

// ---- ICM-42688-P ----

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
        spi_read(0x2E, held.to_be_bytes().to_vec()), // FIFO_COUNT
    ]
    .concat();
    if held == 0 {
        v.extend(spi_read(0x4E, vec![0x0F])); // PWR_MGMT0: low noise
    }
    v.extend(spi_write(0x4B, 0x02)); // SIGNAL_PATH_RESET: FIFO_FLUSH
    v.extend(spi_write(0x5F, 0x07)); // FIFO_CONFIG1: temp, gyro, accel (packet 3)
    v
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
    for (range, counts) in gyro {
        assert_eq!(range.counts_per_dps(), counts, "{range:?}");
    }
    let accel = [
        (IcmAccelRange::G16, 2048.0),
        (IcmAccelRange::G8, 4096.0),
        (IcmAccelRange::G4, 8192.0),
        (IcmAccelRange::G2, 16384.0),
    ];
    for (range, counts) in accel {
        assert_eq!(range.counts_per_g(), counts, "{range:?}");
    }
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

#[test]
fn icm42688_fifo_packets_malformed_empty_and_partial() {
    let mut expect = icm_init();
    expect.extend(icm_fifo_enable());
    expect.extend(spi_read(0x2D, vec![0x08])); // INT_STATUS: data ready
    expect.extend(spi_read(0x2E, vec![0, 3 * 16 + 7])); // 3 packets and 7 stray bytes
    let data = [
        icm_packet(0x68, [1, 2, 3], [4, 5, 6], 10),
        icm_packet(0x28, [0; 3], [7, 8, 9], 0), // gyro only: malformed for this layout
        icm_packet(0x6A, [-1, -2, -3], [-4, -5, -6], -5),
    ]
    .concat();
    expect.extend(spi_read(0x30, data));
    // An empty-FIFO header inside the counted bytes is a damaged header: counted as malformed;
    // the packet after it, clocked out in the same transaction, is delivered.
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 32]));
    expect.extend(spi_read(
        0x30,
        [
            icm_packet(0x80, [0; 3], [0; 3], 0),
            icm_packet(0x68, [9; 3], [9; 3], 0),
        ]
        .concat(),
    ));
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
    assert_eq!(imu.read_fifo(&mut out), Ok(1));
    assert_eq!((out[0].accel, out[0].gyro), ([9; 3], [9; 3]));
    let stats = imu.fifo_stats();
    assert_eq!((stats.samples, stats.malformed), (3, 2));
    imu.destroy().done();
}

#[test]
fn icm42688_fifo_overflow_is_counted_and_recovered() {
    let mut expect = icm_init();
    expect.extend(icm_fifo_enable());
    expect.extend(spi_read(0x2D, vec![0x02])); // FIFO_FULL_INT
    expect.extend(spi_read(0x2E, vec![0x08, 0x00])); // 2048 bytes
    expect.extend(icm_fifo_reset(2048));
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 16]));
    expect.extend(spi_read(0x30, icm_packet(0x68, [1; 3], [2; 3], 0)));
    let mut imu = Icm42688::new(SpiMock::new(&expect));
    imu.init(&mut NoopDelay, icm_config()).unwrap();
    imu.enable_fifo().unwrap();
    let mut out = [RawSample::default(); 4];
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { discarded: 128 })
    );
    assert_eq!(imu.read_fifo(&mut out), Ok(1));
    let stats = imu.fifo_stats();
    assert_eq!(
        (stats.overflows, stats.discarded, stats.samples),
        (1, 128, 1)
    );
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
    expect.extend(spi_read(0x30, icm_packet(0x68, [1; 3], [2; 3], 0)));
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 0]));
    expect.extend(spi_read(0x16, vec![0x00])); // FIFO_CONFIG after a reset: bypass
    expect.extend(icm_init());
    expect.extend(icm_fifo_enable());
    expect.extend(spi_read(0x2D, vec![0x08]));
    expect.extend(spi_read(0x2E, vec![0, 0]));
    expect.extend(spi_read(0x16, vec![0x40])); // stream mode: simply empty
    let mut imu = Icm42688::new(SpiMock::new(&expect));
    imu.init(&mut NoopDelay, icm_config()).unwrap();
    imu.enable_fifo().unwrap();
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
    let steps = 5;
    for fail_at in 0..steps {
        // The mock expects the transactions before the failing one, then a full init.
        let transactions: Vec<Vec<Spi<u8>>> = vec![
            spi_read(0x75, vec![0x47]),
            spi_write(0x11, 0x01),
            spi_write(0x4F, 3 << 5 | 8),
            spi_write(0x50, 2 << 5 | 8),
            spi_write(0x4E, 0x0F),
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
            Ok(()),
            "step {fail_at}"
        );
        imu.destroy().inner.done();
    }
}

#[test]
fn replay_serves_the_record() {
    let scale = Scale {
        gyro_counts_per_dps: 131.0,
        accel_counts_per_g: 16384.0,
    };
    let record: Vec<RawSample> = (0..5i16)
        .map(|i| RawSample {
            gyro: [i; 3],
            ..Default::default()
        })
        .collect();
    let mut replay = Replay::new(&record, scale);
    let mut out = [RawSample::default(); 3];
    assert_eq!(replay.read_fifo(&mut out), Ok(3));
    assert_eq!(replay.read().map(|s| s.gyro[0]), Ok(3));
    assert_eq!(replay.read_fifo(&mut out), Ok(1));
    assert_eq!(replay.read(), Err(Error::NoData));
    assert_eq!((replay.remaining(), replay.fifo_stats().samples), (0, 4));
    replay.rewind();
    assert_eq!(replay.remaining(), 5);
    assert_eq!(replay.scale(), scale);
}

/// Issue 24 item 4: the ICM-42688-P's invalid-data marker (-32768; -128 for the FIFO
/// temperature) was delivered as a real sample: -1998 deg/s at +-2000 deg/s, -36.8 deg C.
#[test]
fn icm42688_invalid_marker_is_skipped_and_counted() {
    let mut expect = icm_init();
    expect.extend(icm_fifo_enable());
    expect.extend(spi_read(0x2D, vec![0x00]));
    expect.extend(spi_read(0x2E, vec![0, 4 * 16]));
    let data = [
        icm_packet(0x68, [1, 2, 3], [i16::MIN; 3], 10),
        icm_packet(0x68, [i16::MIN, 0, 0], [4, 5, 6], 10),
        icm_packet(0x68, [1, 2, 3], [4, 5, 6], i8::MIN),
        icm_packet(0x68, [7, 8, 9], [10, 11, 12], 10),
    ]
    .concat();
    expect.extend(spi_read(0x30, data));
    let mut burst = Vec::new();
    for v in [1325i16, 0, 0, 0, i16::MIN, i16::MIN, i16::MIN] {
        burst.extend(v.to_be_bytes());
    }
    expect.extend(spi_read(0x1D, burst));
    let mut imu = Icm42688::new(SpiMock::new(&expect));
    imu.init(&mut NoopDelay, icm_config()).unwrap();
    imu.enable_fifo().unwrap();
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

/// Issue 24 item 5: a limit at the nominal range never fires (the rail of +-1000 deg/s is
/// 32767 / 32.8 = 998.99 deg/s); the limit from the scale rejects every clipped reading, per
/// channel, and the raw-count test needs no limit at all.
#[test]
fn saturation_limits_from_the_scale_fire_at_the_rails() {
    use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
    let scale = Scale {
        gyro_counts_per_dps: IcmGyroRange::Dps1000.counts_per_dps(),
        accel_counts_per_g: IcmAccelRange::G2.counts_per_g(),
    };
    let rail = RawSample {
        gyro: [i16::MAX, 0, i16::MIN],
        accel: [0, i16::MIN, 0],
        temperature: None,
    };
    assert!(rail.gyro_clipped() && rail.accel_clipped() && rail.clipped());
    assert!(!RawSample::default().clipped());
    let config = Config::new(0.999f32, 0.001).unwrap();
    let base = Channel::new(1e-4).unwrap();
    let nominal = base.with_saturation(1000.0).unwrap();
    let gyro = base
        .with_saturation(scale.gyro_saturation(GyroUnit::DegPerSec))
        .unwrap();
    let accel = base
        .with_saturation(scale.accel_saturation(AccelUnit::G))
        .unwrap();
    let g = scale.gyro(rail.gyro, GyroUnit::DegPerSec);
    let a = scale.accel(rail.accel, AccelUnit::G);
    let mut l = Lattice::<f32, 2>::new(&config, &nominal);
    l.update(&config, g[0]);
    assert_eq!(
        l.health().saturated,
        0,
        "the nominal range lets the rail through"
    );
    let mut l = Lattice::<f32, 2>::new(&config, &gyro);
    for x in [
        g[0],
        g[2],
        scale.gyro([i16::MAX - 1; 3], GyroUnit::DegPerSec)[0],
    ] {
        l.update(&config, x);
    }
    assert_eq!((l.health().saturated, l.health().samples), (2, 1));
    let mut l = Lattice::<f32, 2>::new(&config, &accel);
    for x in [a[1], scale.accel([i16::MIN + 2; 3], AccelUnit::G)[0]] {
        l.update(&config, x);
    }
    assert_eq!((l.health().saturated, l.health().samples), (1, 1));
    // Per channel: the gyro's limit in g would let every clipped accel sample through.
    assert!(scale.gyro_saturation(GyroUnit::DegPerSec) > a[1].abs());
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
