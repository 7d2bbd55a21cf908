//! imu-ar on a real board: a WeAct STM32F411 "Black Pill" reading an MPU-6050 over I2C1 and
//! learning an AR(4) model of every axis online, logged over RTT with defmt.
//!
//! The six models are saved every five minutes as one record in the last two flash sectors
//! (`imu_ar::persist::FlashStore` over the HAL's `embedded-storage` flash driver) and loaded
//! and logged at boot. A power cut during a save leaves the previous save. One save in about
//! 680 erases a 128 KiB sector first, which stalls the CPU for 2 to 4 s (the F411's erase
//! time at 8-bit parallelism): the MPU-6050's FIFO overflows then, and the loop accounts for
//! the lost samples as for any overflow.
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

use cortex_m::peripheral::DWT;
use cortex_m_rt::entry;
use defmt_rtt as _;
use imu_ar::ArModel;
use imu_ar::persist::{FlashStore, Record, StoreError};
use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
use imu_ar::sensor::{
    AccelUnit, CycleClock, FifoLoop, GyroUnit, ImuReader, Mpu6050, Mpu6050Config, Pass, RawSample,
};
use panic_probe as _;
use stm32f4xx_hal::flash::{FlashExt, LockedFlash};
use stm32f4xx_hal::{i2c::I2c, pac, prelude::*};

const NAMES: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];
/// The models of the six axes, saved and loaded as one record (184 bytes).
type Models = [ArModel<f32, 4>; 6];
/// Where they are kept: sectors 6 and 7 of the STM32F411CE, offsets from the start of flash
/// (0x0800_0000); `memory.x` keeps the firmware out of them.
const STORE: core::ops::Range<u32> = 0x4_0000..0x8_0000;
/// Samples between saves: five minutes at 100 Hz.
const SAVE_EVERY: u32 = 30_000;
/// The wait after DEVICE_RESET inside `init` and `recover`.
const INIT_DELAY_US: u64 = 100_000;

/// The models saved last, if any.
fn load(flash: &mut LockedFlash) -> Option<Models> {
    let mut unlocked = flash.unlocked();
    let mut buf = [0u8; <Models as Record>::LEN];
    let loaded = FlashStore::new(&mut unlocked, STORE).and_then(|mut s| s.load(&mut buf));
    match loaded {
        Ok(models) => Some(models),
        Err(StoreError::Empty) => {
            defmt::info!("no saved models");
            None
        }
        Err(e) => {
            defmt::warn!("saved models not loaded: {}", defmt::Debug2Format(&e));
            None
        }
    }
}

/// Saves the six axes' current models, once every axis has one.
fn save(flash: &mut LockedFlash, axes: &[Lattice<f32, 4>; 6], config: &Config<f32>) {
    let Some(models) = models(axes, config) else {
        return;
    };
    let mut unlocked = flash.unlocked();
    let mut buf = [0u8; <Models as Record>::LEN];
    let saved = FlashStore::new(&mut unlocked, STORE).and_then(|mut s| s.save(&models, &mut buf));
    match saved {
        Ok(seq) => defmt::info!("models saved (entry {=u32})", seq),
        Err(e) => defmt::warn!("models not saved: {}", defmt::Debug2Format(&e)),
    }
}

fn models(axes: &[Lattice<f32, 4>; 6], config: &Config<f32>) -> Option<Models> {
    let mut out = [axes[0].model(config)?; 6];
    for (slot, lattice) in out.iter_mut().zip(axes) {
        *slot = lattice.model(config)?;
    }
    Some(out)
}

#[entry]
fn main() -> ! {
    let dp = pac::Peripherals::take().expect("device peripherals");
    let mut cp = cortex_m::Peripherals::take().expect("core peripherals");
    let rcc = dp.RCC.constrain();
    let clocks = rcc.cfgr.use_hse(25.MHz()).sysclk(84.MHz()).freeze();
    let gpiob = dp.GPIOB.split();
    let i2c = I2c::new(dp.I2C1, (gpiob.pb6, gpiob.pb7), 400.kHz(), &clocks);
    cp.DCB.enable_trace();
    cp.DWT.enable_cycle_counter();
    // Microseconds from the 32-bit cycle counter, extended on every pass of the loop (it wraps
    // every 51 s at 84 MHz, and the sensor may be away for longer).
    let clock = CycleClock::new(clocks.sysclk().raw() / 1_000_000, DWT::cycle_count());
    let mut delay = cp.SYST.delay(&clocks);
    let mut flash = LockedFlash::new(dp.FLASH);
    let saved = load(&mut flash);
    if let Some(saved) = &saved {
        for (name, m) in NAMES.iter().zip(saved) {
            defmt::info!(
                "{=str}: saved a={=[?]} sigma^2={=f32} mean={=f32}",
                name,
                m.a().as_slice(),
                m.noise_variance(),
                m.mean()
            );
        }
    }

    let mut imu = Mpu6050::new(i2c, 0x68);
    let config = Mpu6050Config::default(); // +-250 deg/s, +-2 g, 44 Hz filter, 100 Hz
    match imu.init(&mut delay, config) {
        Ok(id) => defmt::info!("MPU-6050 found (WHO_AM_I 0x{=u8:02x})", id),
        Err(e) => defmt::panic!("MPU-6050 init failed: {}", defmt::Debug2Format(&e)),
    }
    if let Err(e) = imu.enable_fifo() {
        defmt::panic!("FIFO enable failed: {}", defmt::Debug2Format(&e));
    }

    // One configuration for the six axes; each channel's regularisation (about 0.1 x its
    // variance, in (deg/s)^2 or g^2) and saturation limit in its own units. The limit comes
    // from the channel's range: a clipped reading (at the rails of the i16 counts) is at or
    // beyond it.
    let scale = imu.scale();
    let shared =
        Config::new(0.9995f32, 1.0 / config.sample_rate_hz()).expect("valid configuration");
    let gyro = Channel::new(1e-4)
        .and_then(|c| c.with_saturation(scale.gyro_saturation(GyroUnit::DegPerSec)))
        .expect("valid gyro channel");
    let accel = Channel::new(1e-6)
        .and_then(|c| c.with_saturation(scale.accel_saturation(AccelUnit::G)))
        .expect("valid accel channel");
    // The saved models are the prior at boot (their coefficients, with the channel's delta as
    // the weight); without one, the plain start.
    let mut axes: [Lattice<f32, 4>; 6] = core::array::from_fn(|i| {
        let channel = if i < 3 { &gyro } else { &accel };
        saved
            .as_ref()
            .and_then(|s| s.get(i))
            .and_then(|m| Lattice::with_prior(&shared, channel, m.a()).ok())
            .unwrap_or_else(|| Lattice::new(&shared, channel))
    });
    let mut batch = [RawSample::default(); 32];
    let mut samples = 0u32;
    // The loop's FIFO logic is the library's (`FifoLoop`), tested on the host against the
    // chip simulator: each pass reads the clock, then the FIFO, and recovers the chip with the
    // outage since the last read that accounted for the FIFO (init's reset takes 100 ms).
    let mut fifo = FifoLoop::new(clock, DWT::cycle_count(), INIT_DELAY_US);
    loop {
        delay.delay_ms(50u32);
        let n = match fifo.pass(DWT::cycle_count, &mut imu, &mut delay, &mut batch) {
            Pass::Samples(n) => n,
            Pass::Dropped(e) => {
                defmt::warn!("FIFO: {}", defmt::Debug2Format(&e));
                continue;
            }
            Pass::Recovered { outage_us } => {
                defmt::warn!("MPU-6050 recovered after {=u64} us", outage_us);
                continue;
            }
            // read_fifo says FifoNotRunning until a recovery succeeds.
            Pass::RecoveryFailed(e) => {
                defmt::warn!("recovery failed: {}", defmt::Debug2Format(&e));
                continue;
            }
            Pass::Failed(e) => {
                defmt::warn!("FIFO: {}", defmt::Debug2Format(&e));
                continue;
            }
        };
        for s in &batch[..n] {
            let gyro = scale.gyro(s.gyro, GyroUnit::DegPerSec);
            let accel = scale.accel(s.accel, AccelUnit::G);
            for (lattice, x) in axes.iter_mut().zip(gyro.into_iter().chain(accel)) {
                lattice.update(&shared, x);
            }
            samples += 1;
            if samples.is_multiple_of(1000) {
                for (name, lattice) in NAMES.iter().zip(&axes) {
                    if let Some(m) = lattice.model(&shared) {
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
            if samples.is_multiple_of(SAVE_EVERY) {
                save(&mut flash, &axes, &shared);
            }
        }
    }
}
