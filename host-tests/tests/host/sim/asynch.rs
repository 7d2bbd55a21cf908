//! The simulator's buses as `embedded-hal-async` buses, and a minimal executor: the async
//! readers ([`Mpu6050Async`], [`Icm42688Async`]) run the simulated sessions the blocking ones
//! run, so that the two can be compared transfer for transfer.

use std::future::Future;
use std::pin::{Pin, pin};
use std::task::{Context, Poll, Waker};

use embedded_hal::i2c::{self, I2c};
use embedded_hal::spi::{self, Operation, SpiDevice};
use imu_ar::sensor::{
    Error, FifoStats, Icm42688Async, ImuReader, Mpu6050Async, RawSample, Scale, Thermometer,
};

/// A blocking simulated bus as an async one. Every transfer suspends once before it runs, as
/// a transfer by DMA does, so the readers' futures are really suspended and resumed.
pub struct AsyncBus<B>(pub B);

/// Pending at its first poll, ready at the second.
struct YieldOnce(bool);

impl Future for YieldOnce {
    type Output = ();

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<()> {
        if self.0 {
            Poll::Ready(())
        } else {
            self.0 = true;
            cx.waker().wake_by_ref();
            Poll::Pending
        }
    }
}

impl<B: i2c::ErrorType> i2c::ErrorType for AsyncBus<B> {
    type Error = B::Error;
}

impl<B: I2c> embedded_hal_async::i2c::I2c for AsyncBus<B> {
    async fn transaction(
        &mut self,
        address: u8,
        operations: &mut [i2c::Operation<'_>],
    ) -> Result<(), Self::Error> {
        YieldOnce(false).await;
        self.0.transaction(address, operations)
    }
}

impl<B: spi::ErrorType> spi::ErrorType for AsyncBus<B> {
    type Error = B::Error;
}

impl<B: SpiDevice> embedded_hal_async::spi::SpiDevice for AsyncBus<B> {
    async fn transaction(
        &mut self,
        operations: &mut [Operation<'_, u8>],
    ) -> Result<(), Self::Error> {
        YieldOnce(false).await;
        self.0.transaction(operations)
    }
}

/// A delay that takes no time.
pub struct AsyncNoDelay;

impl embedded_hal_async::delay::DelayNs for AsyncNoDelay {
    async fn delay_ns(&mut self, _: u32) {}
}

/// Polls `future` until it is ready (the simulated buses wake at once).
pub fn block_on<F: Future>(future: F) -> F::Output {
    let mut future = pin!(future);
    let mut cx = Context::from_waker(Waker::noop());
    for _ in 0..1_000_000 {
        if let Poll::Ready(v) = future.as_mut().poll(&mut cx) {
            return v;
        }
    }
    panic!("a reader's future never completed");
}

/// An async reader driven to completion call by call: an [`ImuReader`], so that the tests and
/// the fault run written for the blocking readers run it unchanged.
pub struct Awaited<D>(pub D);

macro_rules! awaited {
    ($reader:ty, $error:ty) => {
        impl ImuReader for Awaited<$reader> {
            type BusError = $error;

            fn scale(&self) -> Scale {
                self.0.scale()
            }

            fn read(&mut self) -> Result<RawSample, Error<$error>> {
                block_on(self.0.read())
            }

            fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<$error>> {
                block_on(self.0.read_fifo(out))
            }

            fn fifo_stats(&self) -> FifoStats {
                self.0.fifo_stats()
            }

            fn thermometer(&self) -> Option<Thermometer> {
                Some(self.0.thermometer())
            }
        }
    };
}

awaited!(
    Mpu6050Async<AsyncBus<super::mpu6050::SimI2c>>,
    i2c::ErrorKind
);
awaited!(
    Mpu6050Async<AsyncBus<super::hooks::HookedI2c>>,
    i2c::ErrorKind
);
awaited!(
    Icm42688Async<AsyncBus<super::icm42688::SimSpi>>,
    spi::ErrorKind
);
awaited!(
    Icm42688Async<AsyncBus<super::hooks::HookedSpi>>,
    spi::ErrorKind
);
