//! The simulated MPU-6050 (RM-MPU-6000A-00): its registers, what its register writes do, and
//! its I2C bus at address 0x68.

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::i2c::{self, I2c};

use super::{Chip, Kind, Sim};

pub const FIFO_EN: u8 = 0x23;
pub const INT_STATUS: u8 = 0x3A;
pub const USER_CTRL: u8 = 0x6A;
pub const PWR_MGMT_1: u8 = 0x6B;
pub const FIFO_COUNTH: u8 = 0x72;
pub const FIFO_R_W: u8 = 0x74;
pub const WHO_AM_I: u8 = 0x75;
pub const PACKET: usize = 12;
pub const FIFO_BYTES: usize = 1024;

/// The MPU-6050: FIFO_OFLOW_INT (bit 4) is set when the full FIFO overwrites a byte.
pub(super) const CHIP: Chip = Chip {
    id: 0x68,
    packet: PACKET,
    fifo_bytes: FIFO_BYTES,
    int_status: INT_STATUS,
    fifo_counth: FIFO_COUNTH,
    who_am_i: WHO_AM_I,
    fifo_data: FIFO_R_W,
    overwrite_flag: 0x10,
    full_flag: 0,
    reset: (PWR_MGMT_1, 0x80), // DEVICE_RESET
    power_on,
    accepting,
    packet_of,
    write,
};

fn power_on(regs: &mut [u8; 128]) {
    regs[usize::from(PWR_MGMT_1)] = 0x40; // SLEEP
}

/// Awake, the FIFO on, and its accelerometer and gyro channels on.
fn accepting(regs: &[u8; 128]) -> bool {
    let r = |a: u8| regs[usize::from(a)];
    r(PWR_MGMT_1) & 0x40 == 0 && r(USER_CTRL) & 0x40 != 0 && r(FIFO_EN) & 0x78 == 0x78
}

/// Accelerometer then gyro, big-endian, no header.
fn packet_of(_: &mut Sim, _: u64, a: [i16; 3], g: [i16; 3]) -> Vec<u8> {
    a.iter().chain(&g).flat_map(|v| v.to_be_bytes()).collect()
}

/// USER_CTRL.FIFO_RESET empties the FIFO (counted when the FIFO or its channels are on) and
/// clears itself.
fn write(sim: &mut Sim, reg: u8, value: u8) -> Option<u8> {
    if reg != USER_CTRL || value & 0x04 == 0 {
        return Some(value);
    }
    if value & 0x40 != 0 || sim.regs[usize::from(FIFO_EN)] != 0 {
        sim.resets_with_channels_on += 1;
    }
    sim.clear_fifo();
    Some(value & !0x04)
}

/// The I2C bus of a simulated MPU-6050.
pub struct SimI2c(pub Rc<RefCell<Sim>>);

impl i2c::ErrorType for SimI2c {
    type Error = i2c::ErrorKind;
}

impl I2c for SimI2c {
    fn transaction(
        &mut self,
        address: u8,
        ops: &mut [i2c::Operation<'_>],
    ) -> Result<(), Self::Error> {
        let fail = i2c::ErrorKind::ArbitrationLoss;
        if address != 0x68 {
            return Err(i2c::ErrorKind::NoAcknowledge(
                i2c::NoAcknowledgeSource::Address,
            ));
        }
        let mut sim = self.0.borrow_mut();
        match ops {
            [i2c::Operation::Write(w)] if w.len() == 2 => {
                let mut v = [w[1]];
                sim.transfer(Kind::Write(w[0]), &mut v).map_err(|()| fail)
            }
            [i2c::Operation::Write(w), i2c::Operation::Read(r)] if w.len() == 1 => {
                sim.transfer(Kind::Read(w[0]), r).map_err(|()| fail)
            }
            _ => panic!("unexpected I2C transaction"),
        }
    }
}
