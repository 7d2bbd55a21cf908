//! Flash and RAM of the blocking MPU-6050 reader (`tools/footprint.sh size_reader
//! size_reader_async`): the reader on the simulated chip of the demo, `init`, `enable_fifo`
//! and 200 FIFO reads, the samples summed. `size_reader_async` is the same with the async
//! reader.
//!
//! ```text
//! cargo qemu size_reader
//! ```
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/mod.rs"]
mod common;
#[cfg(target_os = "none")]
#[path = "common/sim_imu.rs"]
#[allow(dead_code)]
mod sim_imu;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use imu_ar::sensor::{ImuReader, Mpu6050, Mpu6050Config, RawSample};
    struct NoDelay;
    impl embedded_hal::delay::DelayNs for NoDelay {
        fn delay_ns(&mut self, _: u32) {}
    }
    let mut imu = Mpu6050::new(sim_imu::SimImu::new(2010, false), 0x68);
    let ok = imu.init(&mut NoDelay, Mpu6050Config::default()).is_ok() && imu.enable_fifo().is_ok();
    let mut batch = [RawSample::default(); 16];
    let mut sum = 0i64;
    for _ in 0..200 {
        if let Ok(n) = imu.read_fifo(&mut batch) {
            sum += batch[..n].iter().map(|s| i64::from(s.gyro[0])).sum::<i64>();
        }
    }
    let stats = imu.fifo_stats();
    defmt::info!("samples {=u64}, sum {=i64}", stats.samples, sum);
    common::exit(ok && stats.samples > 0)
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("size_reader is firmware for the Cortex-M4F: run it with `cargo qemu size_reader`");
}
