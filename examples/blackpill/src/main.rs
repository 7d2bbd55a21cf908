//! imu-ar on a real board: a WeAct STM32F411 "Black Pill" reading an MPU-6050 over I2C1 and
//! learning an AR(4) model of every axis online, logged over RTT with defmt.
//!
//! Wiring (3.3 V logic): MPU-6050 VCC to 3V3, GND to GND, SCL to PB6, SDA to PB7 (the GY-521
//! breakout has its own pull-ups), AD0 open or to GND (address 0x68).
//!
//! ```text
//! cargo install probe-rs-tools      # once
//! cd examples/blackpill
//! cargo run --release               # builds, flashes through the probe, prints the defmt log
//! ```
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use defmt_rtt as _;
use imu_ar::recursive::{Config, Lattice};
use imu_ar::sensor::{AccelUnit, Error, GyroUnit, ImuReader, Mpu6050, Mpu6050Config, RawSample};
use panic_probe as _;
use stm32f4xx_hal::{i2c::I2c, pac, prelude::*};

const NAMES: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];

#[entry]
fn main() -> ! {
    let dp = pac::Peripherals::take().expect("device peripherals");
    let cp = cortex_m::Peripherals::take().expect("core peripherals");
    let rcc = dp.RCC.constrain();
    let clocks = rcc.cfgr.use_hse(25.MHz()).sysclk(84.MHz()).freeze();
    let gpiob = dp.GPIOB.split();
    let i2c = I2c::new(dp.I2C1, (gpiob.pb6, gpiob.pb7), 400.kHz(), &clocks);
    let mut delay = cp.SYST.delay(&clocks);

    let mut imu = Mpu6050::new(i2c, 0x68);
    let config = Mpu6050Config::default(); // +-250 deg/s, +-2 g, 44 Hz filter, 100 Hz
    match imu.init(&mut delay, config) {
        Ok(id) => defmt::info!("MPU-6050 found (WHO_AM_I 0x{=u8:02x})", id),
        Err(e) => defmt::panic!("MPU-6050 init failed: {}", defmt::Debug2Format(&e)),
    }
    if let Err(e) = imu.enable_fifo() {
        defmt::panic!("FIFO enable failed: {}", defmt::Debug2Format(&e));
    }

    let estimator = Config::new(0.9995f32, 1e-4, 1.0 / config.sample_rate_hz())
        .expect("valid configuration")
        .with_saturation(240.0)
        .expect("valid saturation limit");
    let mut axes = [Lattice::<f32, 4>::new(&estimator); 6];
    let scale = imu.scale();
    let mut batch = [RawSample::default(); 32];
    let mut samples = 0u32;
    // Time since the last good FIFO read, by the polling period.
    let mut since_good_ms = 0u32;
    loop {
        delay.delay_ms(50u32);
        since_good_ms = since_good_ms.saturating_add(50);
        let n = match imu.read_fifo(&mut batch) {
            Ok(n) => n,
            Err(Error::SensorReset) => {
                // The outage runs until the FIFO is on again, after init's 100 ms.
                let outage_us = since_good_ms.saturating_add(100).saturating_mul(1000);
                match imu.recover(&mut delay, outage_us) {
                    Ok(_) => defmt::warn!("MPU-6050 reset itself: recovered"),
                    Err(e) => defmt::warn!("recovery failed: {}", defmt::Debug2Format(&e)),
                }
                continue;
            }
            Err(e) => {
                defmt::warn!("FIFO: {}", defmt::Debug2Format(&e));
                continue;
            }
        };
        since_good_ms = 0;
        for s in &batch[..n] {
            let gyro = scale.gyro(s.gyro, GyroUnit::DegPerSec);
            let accel = scale.accel(s.accel, AccelUnit::G);
            for (lattice, x) in axes.iter_mut().zip(gyro.into_iter().chain(accel)) {
                lattice.update(&estimator, x);
            }
            samples += 1;
            if samples.is_multiple_of(1000) {
                for (name, lattice) in NAMES.iter().zip(axes.iter_mut()) {
                    if let Some(m) = lattice.model(&estimator) {
                        defmt::info!(
                            "{=str}: a={=[?]} sigma^2={=f32} mean={=f32} {}",
                            name,
                            m.a().as_slice(),
                            m.noise_variance(),
                            m.mean(),
                            lattice.health()
                        );
                    }
                }
                defmt::info!("FIFO: {}", imu.fifo_stats());
            }
        }
    }
}
