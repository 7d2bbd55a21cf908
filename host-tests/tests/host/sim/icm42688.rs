//! The simulated ICM-42688-P (DS-000347, bank 0): its registers, what its register writes do,
//! its FIFO packet 3 with the gyro's start-up, and its SPI device.

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::spi::{self, Operation, SpiDevice};

use super::{Chip, Kind, Sim};

pub const DEVICE_CONFIG: u8 = 0x11;
pub const FIFO_CONFIG: u8 = 0x16;
pub const INT_STATUS: u8 = 0x2D;
pub const FIFO_COUNTH: u8 = 0x2E;
pub const FIFO_DATA: u8 = 0x30;
pub const SIGNAL_PATH_RESET: u8 = 0x4B;
pub const PWR_MGMT0: u8 = 0x4E;
pub const FIFO_CONFIG1: u8 = 0x5F;
pub const WHO_AM_I: u8 = 0x75;
pub const PACKET: usize = 16;
pub const FIFO_BYTES: usize = 2048;
/// Samples with the invalid gyro marker after the gyro is switched on (30 ms at 1 kHz).
pub const GYRO_STARTUP: u32 = 30;

/// The ICM-42688-P: FIFO_FULL_INT (bit 1) is set when the FIFO becomes full.
pub(super) const CHIP: Chip = Chip {
    id: 0x47,
    packet: PACKET,
    fifo_bytes: FIFO_BYTES,
    int_status: INT_STATUS,
    fifo_counth: FIFO_COUNTH,
    who_am_i: WHO_AM_I,
    fifo_data: FIFO_DATA,
    overwrite_flag: 0,
    full_flag: 0x02,
    reset: (DEVICE_CONFIG, 0x01), // SOFT_RESET_CONFIG
    power_on,
    accepting,
    packet_of,
    write,
};

/// Every register 0 at power-on: FIFO in bypass mode, sensors off.
fn power_on(_: &mut [u8; 128]) {}

/// Stream mode, the gyro and accelerometer channels on, and both sensors in low-noise mode.
fn accepting(regs: &[u8; 128]) -> bool {
    let r = |a: u8| regs[usize::from(a)];
    r(FIFO_CONFIG) == 0x40 && r(FIFO_CONFIG1) & 0x03 == 0x03 && r(PWR_MGMT0) & 0x0F == 0x0F
}

/// Packet 3: header, accelerometer, gyro (the invalid marker while the gyro starts),
/// temperature, timestamp.
fn packet_of(sim: &mut Sim, seq: u64, a: [i16; 3], mut g: [i16; 3]) -> Vec<u8> {
    if sim.gyro_startup > 0 {
        sim.gyro_startup -= 1;
        g = [i16::MIN; 3];
    }
    let mut bytes = Vec::with_capacity(16);
    bytes.push(0x68);
    bytes.extend(a.iter().chain(&g).flat_map(|v| v.to_be_bytes()));
    bytes.push(20);
    bytes.extend((seq as u16).to_be_bytes());
    bytes
}

/// SIGNAL_PATH_RESET.FIFO_FLUSH empties the FIFO (the register is not stored); the gyro
/// switched on by PWR_MGMT0 starts with invalid samples.
fn write(sim: &mut Sim, reg: u8, value: u8) -> Option<u8> {
    match reg {
        SIGNAL_PATH_RESET => {
            if value & 0x02 != 0 {
                sim.clear_fifo();
            }
            None
        }
        PWR_MGMT0 => {
            let gyro_on = |v: u8| v & 0x0C == 0x0C;
            if gyro_on(value) && !gyro_on(sim.regs[usize::from(PWR_MGMT0)]) {
                sim.gyro_startup = GYRO_STARTUP;
            }
            Some(value)
        }
        _ => Some(value),
    }
}

/// The SPI device of a simulated ICM-42688-P.
pub struct SimSpi(pub Rc<RefCell<Sim>>);

impl spi::ErrorType for SimSpi {
    type Error = spi::ErrorKind;
}

impl SpiDevice for SimSpi {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        let mut sim = self.0.borrow_mut();
        let fail = spi::ErrorKind::Overrun;
        match ops {
            [Operation::Write(w)] if w.len() == 2 => {
                let mut v = [w[1]];
                sim.transfer(Kind::Write(w[0]), &mut v).map_err(|()| fail)
            }
            [Operation::Write(w), Operation::Read(r)] if w.len() == 1 && w[0] & 0x80 != 0 => {
                sim.transfer(Kind::Read(w[0] & 0x7F), r).map_err(|()| fail)
            }
            _ => panic!("unexpected SPI transaction"),
        }
    }
}
