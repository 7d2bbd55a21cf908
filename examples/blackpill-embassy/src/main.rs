//! imu-ar on a real board under embassy: a WeAct STM32F411 "Black Pill" reading an MPU-6050
//! over async I2C1 (DMA, 400 kHz) with the library's async reader, learning an AR(4) model and
//! a streaming Allan deviation of every axis online, logged over RTT with defmt.
//!
//! It is the blocking example (`examples/blackpill`) on embassy-stm32, embassy-executor and
//! embassy-time, less the flash persistence: the reader is
//! [`Mpu6050Async`](imu_ar::sensor::Mpu6050Async), the loop
//! [`FifoLoop::pass_async`](imu_ar::sensor::FifoLoop::pass_async), and the task sleeps in
//! `Timer::after_millis(50)` between passes, so the executor leaves the core in WFE (Sleep
//! mode) while it waits; the I2C transfers run on DMA and wake it through their interrupts.
//! Every 1,000 samples (10 s) it logs each axis's model, the Allan deviation measured since
//! boot ([`AllanStream`]) beside the one the model predicts, at four averaging times, and the
//! FIFO counts.
//!
//! The loop's clock is the DWT cycle counter, as in the blocking example. It must keep counting
//! while the executor waits in WFE: `embassy_stm32::init` sets DBGMCU's DBG_SLEEP
//! (`Config::enable_debug_during_sleep`, on by default), which keeps the core clocked in Sleep
//! mode. With that turned off, or with embassy-stm32's `low-power` feature (Stop mode), the
//! counter could stop during the waits and the outages `FifoLoop` measures would come out short;
//! such a firmware would count microseconds with `embassy_time::Instant` instead.
//!
//! Wiring (3.3 V logic): MPU-6050 VCC to 3V3, GND to GND, SCL to PB6, SDA to PB7 (the GY-521
//! breakout has its own pull-ups), AD0 open or to GND (address 0x68).
//!
//! ```text
//! cargo install probe-rs-tools      # once
//! cd examples/blackpill-embassy
//! cargo run --release               # builds, flashes through the probe, prints the defmt log
//! ```
//!
//! CI builds it (`cargo build --release` in this directory), but it has never been flashed to
//! a board: the machines that build it have no probe and no board, so its first run on
//! hardware is its first test.
#![no_std]
#![no_main]

use cortex_m::peripheral::DWT;
use defmt_rtt as _;
use embassy_executor::Spawner;
use embassy_stm32::i2c::{self, I2c};
use embassy_stm32::time::Hertz;
use embassy_stm32::{bind_interrupts, dma, peripherals, rcc};
use embassy_time::{Delay, Timer};
use imu_ar::allan::AllanStream;
use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
use imu_ar::sensor::{
    AccelUnit, CycleClock, FifoLoop, GyroUnit, Mpu6050Async, Mpu6050Config, Pass, RawSample,
};
use panic_probe as _;

bind_interrupts!(struct Irqs {
    I2C1_EV => i2c::EventInterruptHandler<peripherals::I2C1>;
    I2C1_ER => i2c::ErrorInterruptHandler<peripherals::I2C1>;
    DMA1_STREAM6 => dma::InterruptHandler<peripherals::DMA1_CH6>;
    DMA1_STREAM0 => dma::InterruptHandler<peripherals::DMA1_CH0>;
});

const NAMES: [&str; 6] = ["gx", "gy", "gz", "ax", "ay", "az"];
/// The wait after DEVICE_RESET inside `init` and `recover`.
const INIT_DELAY_US: u64 = 100_000;
/// Samples between reports: 10 s at 100 Hz.
const REPORT_EVERY: u32 = 1000;
/// Octaves of the streaming Allan variance: averaging factors m = 1, 2, 4, .., 2^11 samples
/// (0.01 s to 20.48 s at 100 Hz), 56 bytes each.
const OCTAVES: usize = 12;
/// The octaves logged: m = 1, 8, 64 and 512 samples.
const LOGGED: [usize; 4] = [0, 3, 6, 9];

/// The Black Pill's clocks: its 25 MHz crystal, and the PLL at 84 MHz as in the blocking
/// example (VCO 25 / 25 x 336 = 336 MHz, / 4), APB1 at 42 MHz (its limit is 50 MHz).
fn board_config() -> embassy_stm32::Config {
    use embassy_stm32::rcc::{
        AHBPrescaler, APBPrescaler, Hse, HseMode, Pll, PllMul, PllPDiv, PllPreDiv, PllSource,
        Sysclk,
    };
    let mut config = embassy_stm32::Config::default();
    config.rcc.hse = Some(Hse {
        freq: Hertz::mhz(25),
        mode: HseMode::Oscillator,
    });
    config.rcc.pll_src = PllSource::HSE;
    config.rcc.pll = Some(Pll {
        prediv: PllPreDiv::DIV25,
        mul: PllMul::MUL336,
        divp: Some(PllPDiv::DIV4),
        divq: None,
        divr: None,
    });
    config.rcc.sys = Sysclk::PLL1_P;
    config.rcc.ahb_pre = AHBPrescaler::DIV1;
    config.rcc.apb1_pre = APBPrescaler::DIV2;
    config.rcc.apb2_pre = APBPrescaler::DIV1;
    config
}

#[embassy_executor::main]
async fn main(_spawner: Spawner) {
    let p = embassy_stm32::init(board_config());
    let sysclk = rcc::clocks(&p.RCC).sys.to_hertz().expect("system clock").0;
    let mut cp = cortex_m::Peripherals::take().expect("core peripherals");
    cp.DCB.enable_trace();
    cp.DWT.enable_cycle_counter();
    // Microseconds from the 32-bit cycle counter, extended on every pass of the loop (it wraps
    // every 51 s at 84 MHz, and the sensor may be away for longer).
    let clock = CycleClock::new(sysclk / 1_000_000, DWT::cycle_count());

    let mut i2c_config = i2c::Config::default();
    i2c_config.frequency = Hertz::khz(400);
    // TX on DMA1 stream 6 and RX on stream 0 (both channel 1, RM0383 table 27).
    let i2c = I2c::new(
        p.I2C1, p.PB6, p.PB7, p.DMA1_CH6, p.DMA1_CH0, Irqs, i2c_config,
    );
    let mut delay = Delay;

    let mut imu = Mpu6050Async::new(i2c, 0x68);
    let config = Mpu6050Config::default(); // +-250 deg/s, +-2 g, 44 Hz filter, 100 Hz
    match imu.init(&mut delay, config).await {
        Ok(id) => defmt::info!("MPU-6050 found (WHO_AM_I 0x{=u8:02x})", id),
        Err(e) => defmt::panic!("MPU-6050 init failed: {}", e),
    }
    if let Err(e) = imu.enable_fifo().await {
        defmt::panic!("FIFO enable failed: {}", e);
    }

    // One configuration for the six axes; each channel's regularisation (about 0.1 x its
    // variance, in (deg/s)^2 or g^2) and saturation limit in its own units. The limit comes
    // from the channel's range: a clipped reading (at the rails of the i16 counts) is at or
    // beyond it.
    let scale = imu.scale();
    let rate_hz = config.sample_rate_hz();
    let shared = Config::new(0.9995f32, 1.0 / rate_hz).expect("valid configuration");
    let gyro = Channel::new(1e-4)
        .and_then(|c| c.with_saturation(scale.gyro_saturation(GyroUnit::DegPerSec)))
        .expect("valid gyro channel");
    let accel = Channel::new(1e-6)
        .and_then(|c| c.with_saturation(scale.accel_saturation(AccelUnit::G)))
        .expect("valid accel channel");
    let mut axes: [Lattice<f32, 4>; 6] =
        core::array::from_fn(|i| Lattice::new(&shared, if i < 3 { &gyro } else { &accel }));
    // The Allan variance of everything since boot (no forgetting), per axis.
    let mut allan = [AllanStream::<OCTAVES>::new(); 6];
    let taus = LOGGED.map(|level| (1u32 << level) as f32 / rate_hz);
    defmt::info!("Allan deviations at tau = {} s", taus);

    let mut batch = [RawSample::default(); 32];
    let mut samples = 0u32;
    // The loop's FIFO logic is the library's (`FifoLoop`), tested on the host against the
    // chip simulator: each pass reads the clock, then the FIFO, and recovers the chip with the
    // outage since the last read that accounted for the FIFO (init's reset takes 100 ms).
    let mut fifo = FifoLoop::new(clock, DWT::cycle_count(), INIT_DELAY_US);
    loop {
        Timer::after_millis(50).await;
        let n = match fifo
            .pass_async(DWT::cycle_count, &mut imu, &mut delay, &mut batch)
            .await
        {
            Pass::Samples(n) => n,
            Pass::Dropped(e) => {
                defmt::warn!("FIFO: {}", e);
                continue;
            }
            Pass::Recovered { outage_us } => {
                defmt::warn!("MPU-6050 recovered after {=u64} us", outage_us);
                continue;
            }
            // read_fifo says FifoNotRunning until a recovery succeeds.
            Pass::RecoveryFailed(e) => {
                defmt::warn!("recovery failed: {}", e);
                continue;
            }
            Pass::Failed(e) => {
                defmt::warn!("FIFO: {}", e);
                continue;
            }
        };
        for s in &batch[..n] {
            let gyro = scale.gyro(s.gyro, GyroUnit::DegPerSec);
            let accel = scale.accel(s.accel, AccelUnit::G);
            for ((lattice, stream), x) in axes
                .iter_mut()
                .zip(allan.iter_mut())
                .zip(gyro.into_iter().chain(accel))
            {
                lattice.update(&shared, x);
                stream.push(x);
            }
            samples += 1;
            if samples.is_multiple_of(REPORT_EVERY) {
                report(&axes, &allan, &shared);
                defmt::info!("FIFO: {}", imu.fifo_stats());
            }
        }
    }
}

/// Logs each axis's model, and its Allan deviations at the `LOGGED` octaves: measured, and
/// as its current model predicts them (`None` before there is one).
fn report(axes: &[Lattice<f32, 4>; 6], allan: &[AllanStream<OCTAVES>; 6], shared: &Config<f32>) {
    for ((name, lattice), stream) in NAMES.iter().zip(axes).zip(allan) {
        let model = lattice.model(shared);
        if let Some(m) = &model {
            defmt::info!(
                "{=str}: a={=[?]} sigma^2={=f32} mean={=f32} {}",
                name,
                m.a().as_slice(),
                m.noise_variance(),
                m.mean(),
                lattice.health()
            );
        }
        let measured = LOGGED.map(|level| stream.avar(level).map(|v| libm::sqrtf(v as f32)));
        let predicted = LOGGED.map(|level| {
            let m = model.as_ref()?;
            m.allan_variance(1 << level).ok().map(libm::sqrtf)
        });
        defmt::info!("{=str}: adev={} model adev={}", name, measured, predicted);
    }
}
