//! Flash and RAM of the async MPU-6050 reader: `size_reader` with [`Mpu6050Async`] on the same
//! simulated chip behind an `embedded-hal-async` bus, driven by a one-future executor. It logs
//! the size of the `read_fifo` future, the RAM a task holds across the reader's awaits.
//!
//! ```text
//! cargo qemu size_reader_async
//! ```
//!
//! [`Mpu6050Async`]: imu_ar::sensor::Mpu6050Async
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
    use core::future::Future;
    use core::pin::pin;
    use core::task::{Context, Poll, Waker};
    use embedded_hal::i2c::{ErrorType, I2c, Operation};
    use imu_ar::sensor::{Mpu6050Async, Mpu6050Config, RawSample};

    /// The simulated chip's blocking bus as an async one.
    struct Bus(sim_imu::SimImu);
    impl ErrorType for Bus {
        type Error = <sim_imu::SimImu as ErrorType>::Error;
    }
    impl embedded_hal_async::i2c::I2c for Bus {
        async fn transaction(
            &mut self,
            address: u8,
            operations: &mut [Operation<'_>],
        ) -> Result<(), Self::Error> {
            self.0.transaction(address, operations)
        }
    }
    struct NoDelay;
    impl embedded_hal_async::delay::DelayNs for NoDelay {
        async fn delay_ns(&mut self, _: u32) {}
    }
    fn block_on<F: Future>(future: F) -> F::Output {
        let mut future = pin!(future);
        let mut cx = Context::from_waker(Waker::noop());
        loop {
            if let Poll::Ready(v) = future.as_mut().poll(&mut cx) {
                return v;
            }
        }
    }

    let mut imu = Mpu6050Async::new(Bus(sim_imu::SimImu::new(2010, false)), 0x68);
    let ok = block_on(imu.init(&mut NoDelay, Mpu6050Config::default())).is_ok()
        && block_on(imu.enable_fifo()).is_ok();
    let mut batch = [RawSample::default(); 16];
    let future_bytes = core::mem::size_of_val(&imu.read_fifo(&mut batch));
    let mut sum = 0i64;
    for _ in 0..200 {
        if let Ok(n) = block_on(imu.read_fifo(&mut batch)) {
            sum += batch[..n].iter().map(|s| i64::from(s.gyro[0])).sum::<i64>();
        }
    }
    let stats = imu.fifo_stats();
    defmt::info!(
        "samples {=u64}, sum {=i64}, read_fifo future {=usize} bytes",
        stats.samples,
        sum,
        future_bytes
    );
    common::exit(ok && stats.samples > 0)
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!(
        "size_reader_async is firmware for the Cortex-M4F: run it with `cargo qemu size_reader_async`"
    );
}
