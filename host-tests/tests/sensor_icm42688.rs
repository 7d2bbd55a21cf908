//! The ICM-42688-P reader against the register-level simulator (`sim`): each defect of issue
//! 24 that the simulator reproduces, and a long run with random bus faults.

mod sim;

use std::cell::RefCell;
use std::rc::Rc;

use imu_ar::sensor::{Error, Icm42688, Icm42688Config, ImuReader, Odr, RawSample};
use sim::{Kind, Model, NoDelay, Sim, SimSpi, decode, icm};

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

fn expect_samples(sim: &Rc<RefCell<Sim>>, imu: &mut Icm42688<SimSpi>, n: u64) {
    let first = sim.borrow().ticks;
    sim.borrow_mut().tick(n);
    let mut out = [RawSample::default(); 160];
    let k = imu.read_fifo(&mut out).expect("samples flow");
    let seqs: Vec<Option<u64>> = out[..k].iter().map(decode).collect();
    let expected: Vec<Option<u64>> = (first..first + n).map(Some).collect();
    assert_eq!(seqs, expected, "the samples the chip produced, well-formed");
}

/// Item 1: a failed FIFO enable inside `recover` left the FIFO off for good.
#[test]
fn recover_that_fails_part_way_is_finished_by_the_next_one() {
    let (sim, mut imu) = reader(1);
    expect_samples(&sim, &mut imu, 5);
    sim.borrow_mut().glitch();
    let mut out = [RawSample::default(); 16];
    assert_eq!(imu.read_fifo(&mut out), Err(Error::SensorReset));
    sim.borrow_mut().fail(Kind::Write(icm::FIFO_CONFIG), 0, 0);
    assert!(matches!(
        imu.recover(&mut NoDelay, 10_000),
        Err(Error::Bus(_))
    ));
    assert_eq!(imu.read_fifo(&mut out), Err(Error::FifoNotRunning));
    assert_eq!(imu.recover(&mut NoDelay, 20_000), Ok(0x47));
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
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { discarded: 128 })
    );
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
    assert!(matches!(imu.read_fifo(&mut out), Err(Error::Bus(_))));
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { discarded: 128 })
    );
    expect_samples(&sim, &mut imu, 4);
}

/// Item 3 (both chips): a FIFO read that fails part-way is followed by a flush.
#[test]
fn fifo_read_failing_part_way_flushes_the_fifo() {
    let (sim, mut imu) = reader(4);
    sim.borrow_mut().tick(20);
    sim.borrow_mut().fail(Kind::Read(icm::FIFO_DATA), 0, 21);
    let mut out = [RawSample::default(); 160];
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoResync { discarded: 20 })
    );
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
    sim.borrow_mut().stuck_high = true;
    let mut out = [RawSample::default(); 160];
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::BadFifoCount { count: 0xFFFF })
    );
    assert_eq!(imu.fifo_stats().discarded, 0);
    sim.borrow_mut().stuck_high = false;
    assert_eq!(
        imu.read_fifo(&mut out),
        Err(Error::FifoOverflow { discarded: 5 })
    );
    expect_samples(&sim, &mut imu, 6);
}

/// Issue 24 acceptance, as for the MPU-6050.
#[test]
fn random_bus_faults_lose_nothing_uncounted() {
    let (sim, mut imu) = reader(2024);
    let figures = sim::fault_run(
        &sim,
        &mut imu,
        |imu, us| imu.recover(&mut NoDelay, us).map(|_| ()),
        12,
        0.01,
        100_000,
    );
    println!("ICM-42688-P {figures:#?}");
    assert!(figures.delivered >= 100_000);
    assert!(figures.stats.overflows > 0 && figures.stats.resyncs > 0);
    assert!(figures.stats.invalid > 0);
}
