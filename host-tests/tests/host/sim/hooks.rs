//! Buses that act at a chosen transfer of the simulated chip: advance the chip's clock right
//! before it (on real hardware samples keep arriving while the reader works: a 1 kHz MPU-6050
//! on 400 kHz I2C writes a sample every ~13 transfers), or corrupt the bytes of a read (a bit
//! error on the wire).

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::i2c::{self, I2c};
use embedded_hal::spi::{self, Operation, SpiDevice};

use super::icm42688::SimSpi;
use super::mpu6050::SimI2c;
use super::{Kind, Sim};

/// What a hook does at its transfer.
#[derive(Clone)]
pub enum Action {
    /// The chip writes `n` samples right before the transfer.
    TickBefore(u64),
    /// The chip resets itself right before the transfer (a supply glitch).
    GlitchBefore,
    /// The read returns these bytes at these offsets (after the chip's own answer).
    Overwrite(Vec<(usize, u8)>),
    /// The read takes one byte fewer out of the chip than it returns, and reports success (a
    /// byte slip: SPI has no acknowledge); its last byte repeats the one before.
    Slip,
    /// The write carries these bytes at these offsets instead of its own (a bit error on the
    /// wire, which SPI does not see).
    Corrupt(Vec<(usize, u8)>),
}

/// An action at the `skip`-th next transfer of `kind`.
struct Hook {
    kind: Kind,
    skip: u32,
    action: Action,
}

/// The hooks of a bus, shared with the test that adds them.
#[derive(Default, Clone)]
pub struct Hooks(Rc<RefCell<Vec<Hook>>>);

impl Hooks {
    /// Does `action` at the `skip`-th next transfer of `kind` (0: the next one).
    pub fn add(&self, kind: Kind, skip: u32, action: Action) {
        self.0.borrow_mut().push(Hook { kind, skip, action });
    }

    /// The action due at this transfer of `kind`, if any.
    fn due(&self, kind: Kind) -> Option<Action> {
        let mut hooks = self.0.borrow_mut();
        let i = hooks.iter().position(|h| h.kind == kind)?;
        if hooks[i].skip == 0 {
            Some(hooks.remove(i).action)
        } else {
            hooks[i].skip -= 1;
            None
        }
    }

    fn around(
        &self,
        sim: &Rc<RefCell<Sim>>,
        kind: Kind,
        buf: Option<&mut [u8]>,
        transfer: impl FnOnce(Option<&mut [u8]>) -> bool,
    ) -> bool {
        let action = self.due(kind);
        if let Some(Action::TickBefore(n)) = &action {
            sim.borrow_mut().tick(*n);
        }
        if let Some(Action::GlitchBefore) = &action {
            sim.borrow_mut().glitch();
        }
        match buf {
            Some(buf) if matches!(action, Some(Action::Slip)) && buf.len() > 1 => {
                let last = buf.len() - 1;
                let ok = transfer(Some(&mut buf[..last]));
                buf[last] = buf[last - 1];
                ok
            }
            Some(buf) => {
                if let Some(Action::Corrupt(bytes)) = &action {
                    for &(i, b) in bytes {
                        buf[i] = b;
                    }
                }
                let ok = transfer(Some(&mut *buf));
                if let Some(Action::Overwrite(bytes)) = action {
                    for (i, b) in bytes {
                        buf[i] = b;
                    }
                }
                ok
            }
            None => transfer(None),
        }
    }
}

/// The simulated MPU-6050's I2C bus with hooks.
pub struct HookedI2c {
    pub sim: Rc<RefCell<Sim>>,
    pub inner: SimI2c,
    pub hooks: Hooks,
}

impl i2c::ErrorType for HookedI2c {
    type Error = i2c::ErrorKind;
}

impl I2c for HookedI2c {
    fn transaction(
        &mut self,
        address: u8,
        ops: &mut [i2c::Operation<'_>],
    ) -> Result<(), Self::Error> {
        let kind = match &*ops {
            [i2c::Operation::Write(w)] => Kind::Write(w[0]),
            [i2c::Operation::Write(w), i2c::Operation::Read(_)] => Kind::Read(w[0]),
            _ => panic!("unexpected I2C transaction"),
        };
        let mut result = Ok(());
        let inner = &mut self.inner;
        match ops {
            [i2c::Operation::Write(w), i2c::Operation::Read(r)] => {
                let w: &[u8] = w;
                self.hooks.around(&self.sim, kind, Some(&mut **r), |r| {
                    result = inner.write_read(address, w, r.unwrap());
                    result.is_ok()
                });
            }
            _ => {
                self.hooks.around(&self.sim, kind, None, |_| {
                    result = inner.transaction(address, ops);
                    result.is_ok()
                });
            }
        }
        result
    }
}

/// The simulated ICM-42688-P's SPI device with hooks.
pub struct HookedSpi {
    pub sim: Rc<RefCell<Sim>>,
    pub inner: SimSpi,
    pub hooks: Hooks,
}

impl spi::ErrorType for HookedSpi {
    type Error = spi::ErrorKind;
}

impl SpiDevice for HookedSpi {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        let mut result = Ok(());
        let inner = &mut self.inner;
        match ops {
            [Operation::Write(w)] => {
                let kind = Kind::Write(w[0]);
                let mut sent = w.to_vec();
                self.hooks.around(&self.sim, kind, Some(&mut sent), |w| {
                    result = inner.write(w.unwrap_or_default());
                    result.is_ok()
                });
            }
            [Operation::Write(w), Operation::Read(r)] => {
                let kind = Kind::Read(w[0] & 0x7F);
                let w: &[u8] = w;
                self.hooks.around(&self.sim, kind, Some(&mut **r), |r| {
                    result =
                        inner.transaction(&mut [Operation::Write(w), Operation::Read(r.unwrap())]);
                    result.is_ok()
                });
            }
            _ => panic!("unexpected SPI transaction"),
        }
        result
    }
}
