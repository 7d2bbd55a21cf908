//! The MPU-6050 reader against the register-level simulator (`sim`): each defect of issue 24
//! that the simulator reproduces, and a long run with random bus faults.

mod sim;

use std::cell::RefCell;
use std::rc::Rc;

use imu_ar::sensor::{Dlpf, Error, ImuReader, Mpu6050, Mpu6050Config, RawSample};
use sim::{Kind, Model, NoDelay, Sim, SimI2c, decode, mpu};

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

/// Reads once and checks that exactly the `n` samples the chip produced come out.
fn expect_samples(sim: &Rc<RefCell<Sim>>, imu: &mut Mpu6050<SimI2c>, n: u64) {
    let first = sim.borrow().ticks;
    sim.borrow_mut().tick(n);
    let mut out = [RawSample::default(); 128];
    let k = imu.read_fifo(&mut out).expect("samples flow");
    let seqs: Vec<Option<u64>> = out[..k].iter().map(decode).collect();
    let expected: Vec<Option<u64>> = (first..first + n).map(Some).collect();
    assert_eq!(seqs, expected, "the samples the chip produced, well-formed");
}

/// Item 1: a bus error inside `recover` left the FIFO off for good (the next `recover`
/// returned Ok without enabling it, and `read_fifo` said FifoDisabled forever).
#[test]
fn recover_that_fails_part_way_is_finished_by_the_next_one() {
    let (sim, mut imu) = reader(1);
    expect_samples(&sim, &mut imu, 5);
    sim.borrow_mut().glitch();
    let mut out = [RawSample::default(); 16];
    assert_eq!(imu.read_fifo(&mut out), Err(Error::SensorReset));
    // The FIFO re-enable inside recover fails at its last USER_CTRL write.
    sim.borrow_mut().fail(Kind::Write(mpu::USER_CTRL), 2, 0);
    assert!(matches!(
        imu.recover(&mut NoDelay, 10_000),
        Err(Error::Bus(_))
    ));
    assert_eq!(imu.read_fifo(&mut out), Err(Error::FifoNotRunning));
    assert_eq!(imu.recover(&mut NoDelay, 20_000), Ok(0x68));
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
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { discarded: 85 })
    );
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
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { discarded: 85 })
    );
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
    sim.borrow_mut().fail(Kind::Read(mpu::FIFO_R_W), 0, 5);
    let mut out = [RawSample::default(); 128];
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoResync { discarded: 20 })
    );
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
    sim.borrow_mut().stuck_high = true;
    let mut out = [RawSample::default(); 128];
    for _ in 0..3 {
        let err = imu.read_fifo(&mut out);
        assert_eq!(err, Err(Error::BadFifoCount { count: 0xFFFF }));
    }
    assert_eq!(imu.fifo_stats().discarded, 0);
    sim.borrow_mut().stuck_high = false;
    let err = imu.read_fifo(&mut out);
    assert_eq!(err, Err(Error::FifoOverflow { discarded: 5 }));
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
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { discarded: 85 })
    );
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
    let figures = sim::fault_run(
        &sim,
        &mut imu,
        |imu, us| imu.recover(&mut NoDelay, us).map(|_| ()),
        11,
        0.01,
        100_000,
    );
    println!("MPU-6050 {figures:#?}");
    assert!(figures.delivered >= 100_000);
    assert!(figures.stats.overflows > 0 && figures.stats.resyncs > 0);
    assert_eq!(sim.borrow().resets_with_channels_on, 0);
}
