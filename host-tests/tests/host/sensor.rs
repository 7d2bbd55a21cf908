//! What the sensor module does without a chip: the replay reader, and saturation limits from
//! a reader's scale. Each chip's reader is tested in its own file (`sensor_mpu6050.rs`,
//! `sensor_icm42688.rs`), and under bus faults in `sensor_faults.rs`.

use imu_ar::sensor::{
    AccelUnit, Error, GyroUnit, IcmAccelRange, IcmGyroRange, ImuReader, RawSample, Replay, Scale,
    Thermometer,
};

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
    // A replay knows no temperature formula unless given the recording chip's.
    let warm = RawSample {
        temperature: Some(1325),
        ..Default::default()
    };
    assert_eq!(replay.die_temperature(&warm), None);
    let replay = replay.with_thermometer(Thermometer::ICM42688);
    assert_eq!(
        replay.die_temperature(&warm),
        Some(Thermometer::ICM42688.celsius(1325))
    );
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
