//! The readers' I/O edge. The chip logic (`driver.rs`, `fifo.rs`) is written once, as `async`
//! functions over these traits; a blocking bus implements them with futures that are ready at
//! once, and [`block`] runs those to completion in one poll. An `embedded-hal-async` bus
//! implements them by awaiting its transfers. Every register decision, packet check, count and
//! recovery rule is therefore the same code for the blocking and the async readers.

use core::future::Future;
use core::pin::pin;
use core::task::{Context, Poll, Waker};

use embedded_hal::spi::Operation;

/// An async bus wrapped for the async readers ([`Mpu6050Async`](super::Mpu6050Async),
/// [`Icm42688Async`](super::Icm42688Async)): an `embedded-hal-async` I2C bus or SPI device.
#[derive(Debug)]
pub struct Async<B>(pub(crate) B);

/// Register transfers on an I2C bus.
#[allow(async_fn_in_trait)]
pub trait I2cIo {
    /// The bus's error.
    type Error;
    /// Writes `bytes` to the device at `address`.
    async fn write(&mut self, address: u8, bytes: &[u8]) -> Result<(), Self::Error>;
    /// Writes `bytes`, then reads `buf`, in one transaction.
    async fn write_read(
        &mut self,
        address: u8,
        bytes: &[u8],
        buf: &mut [u8],
    ) -> Result<(), Self::Error>;
}

impl<B: embedded_hal::i2c::I2c> I2cIo for B {
    type Error = B::Error;

    async fn write(&mut self, address: u8, bytes: &[u8]) -> Result<(), B::Error> {
        embedded_hal::i2c::I2c::write(self, address, bytes)
    }

    async fn write_read(
        &mut self,
        address: u8,
        bytes: &[u8],
        buf: &mut [u8],
    ) -> Result<(), B::Error> {
        embedded_hal::i2c::I2c::write_read(self, address, bytes, buf)
    }
}

impl<B: embedded_hal_async::i2c::I2c> I2cIo for Async<B> {
    type Error = B::Error;

    async fn write(&mut self, address: u8, bytes: &[u8]) -> Result<(), B::Error> {
        self.0.write(address, bytes).await
    }

    async fn write_read(
        &mut self,
        address: u8,
        bytes: &[u8],
        buf: &mut [u8],
    ) -> Result<(), B::Error> {
        self.0.write_read(address, bytes, buf).await
    }
}

/// Register transfers on an SPI device.
#[allow(async_fn_in_trait)]
pub trait SpiIo {
    /// The device's error.
    type Error;
    /// Runs `operations` as one transaction (chip select held).
    async fn transaction(
        &mut self,
        operations: &mut [Operation<'_, u8>],
    ) -> Result<(), Self::Error>;
}

impl<B: embedded_hal::spi::SpiDevice> SpiIo for B {
    type Error = B::Error;

    async fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), B::Error> {
        embedded_hal::spi::SpiDevice::transaction(self, operations)
    }
}

impl<B: embedded_hal_async::spi::SpiDevice> SpiIo for Async<B> {
    type Error = B::Error;

    async fn transaction(&mut self, operations: &mut [Operation<'_, u8>]) -> Result<(), B::Error> {
        self.0.transaction(operations).await
    }
}

/// A delay in milliseconds.
#[allow(async_fn_in_trait)]
pub trait Wait {
    /// Waits `ms` milliseconds.
    async fn ms(&mut self, ms: u32);
}

/// A blocking delay as a [`Wait`].
pub struct BlockingWait<'a, D>(pub &'a mut D);

impl<D: embedded_hal::delay::DelayNs> Wait for BlockingWait<'_, D> {
    async fn ms(&mut self, ms: u32) {
        self.0.delay_ms(ms);
    }
}

/// An async delay as a [`Wait`].
pub struct AsyncWait<'a, D>(pub &'a mut D);

impl<D: embedded_hal_async::delay::DelayNs> Wait for AsyncWait<'_, D> {
    async fn ms(&mut self, ms: u32) {
        self.0.delay_ms(ms).await;
    }
}

/// Runs `future` to completion. The blocking readers' futures await nothing but blocking
/// transfers, so they are ready at the first poll; the loop only states that no other outcome
/// is handled.
pub(crate) fn block<F: Future>(future: F) -> F::Output {
    let mut future = pin!(future);
    let mut cx = Context::from_waker(Waker::noop());
    loop {
        if let Poll::Ready(v) = future.as_mut().poll(&mut cx) {
            return v;
        }
    }
}
