//! A NOR flash in RAM for the tests of `imu_ar::persist::FlashStore`, with NOR's rules
//! enforced and power cuts injected.
//!
//! - Erasing sets bytes to `0xFF`; writing can only clear bits (`cell &= byte`).
//! - Reads, writes and erases must be aligned to `READ`, `WRITE` and `ERASE` bytes and lie
//!   inside the flash.
//! - A write unit may be written once between erases (as on flash with ECC); a second write
//!   to a unit of which a byte was programmed is [`RamFlashError::Rewrite`].
//! - [`RamFlash::cut_after`] cuts the power after a number of byte operations (a byte erased
//!   or written counts one; erases proceed from low to high addresses): the operation in
//!   progress stops there and fails with [`RamFlashError::PowerCut`], and every later one
//!   fails too until [`RamFlash::power_on`].

use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash,
};

/// What went wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RamFlashError {
    /// An offset or length is not a multiple of the operation's unit.
    NotAligned,
    /// Beyond the end of the flash.
    OutOfBounds,
    /// A write unit written twice without an erase between.
    Rewrite,
    /// The power is cut.
    PowerCut,
    /// A read that the test made fail ([`RamFlash::fail_reads_at`]).
    ReadFault,
}

impl NorFlashError for RamFlashError {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            Self::NotAligned => NorFlashErrorKind::NotAligned,
            Self::OutOfBounds => NorFlashErrorKind::OutOfBounds,
            _ => NorFlashErrorKind::Other,
        }
    }
}

/// A NOR flash of `mem.len()` bytes with read, write and erase units `READ`, `WRITE` and
/// `ERASE`.
#[derive(Clone, Debug)]
pub struct RamFlash<const READ: usize, const WRITE: usize, const ERASE: usize> {
    mem: Vec<u8>,
    written: Vec<bool>,
    budget: Option<usize>,
    off: bool,
    read_fault: Option<std::ops::Range<usize>>,
    /// Bytes erased or written so far.
    pub ops: usize,
    /// Erase calls so far.
    pub erases: usize,
}

impl<const READ: usize, const WRITE: usize, const ERASE: usize> RamFlash<READ, WRITE, ERASE> {
    /// An erased flash of `units` erase units.
    pub fn new(units: usize) -> Self {
        let len = units * ERASE;
        Self {
            mem: vec![0xFF; len],
            written: vec![false; len / WRITE],
            budget: None,
            off: false,
            read_fault: None,
            ops: 0,
            erases: 0,
        }
    }

    /// Cuts the power after `n` more byte operations.
    pub fn cut_after(&mut self, n: usize) {
        self.budget = Some(n);
    }

    /// Power back on, with no cut pending: a reboot.
    pub fn power_on(&mut self) {
        self.off = false;
        self.budget = None;
    }

    /// Makes every read that touches `range` fail.
    pub fn fail_reads_at(&mut self, range: std::ops::Range<usize>) {
        self.read_fault = Some(range);
    }

    /// The contents.
    pub fn bytes(&self) -> &[u8] {
        &self.mem
    }

    /// The contents, to damage them as time might (a bit flipped at rest).
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.mem
    }

    /// One byte operation: false once the budget is spent (the power is then off).
    fn spend(&mut self) -> bool {
        match &mut self.budget {
            Some(0) => {
                self.off = true;
                false
            }
            Some(n) => {
                *n -= 1;
                self.ops += 1;
                true
            }
            None => {
                self.ops += 1;
                true
            }
        }
    }

    fn check(&self, offset: u32, len: usize, unit: usize) -> Result<usize, RamFlashError> {
        let at = offset as usize;
        if self.off {
            return Err(RamFlashError::PowerCut);
        }
        if !at.is_multiple_of(unit) || !len.is_multiple_of(unit) {
            return Err(RamFlashError::NotAligned);
        }
        if at + len > self.mem.len() {
            return Err(RamFlashError::OutOfBounds);
        }
        Ok(at)
    }
}

impl<const READ: usize, const WRITE: usize, const ERASE: usize> ErrorType
    for RamFlash<READ, WRITE, ERASE>
{
    type Error = RamFlashError;
}

impl<const READ: usize, const WRITE: usize, const ERASE: usize> ReadNorFlash
    for RamFlash<READ, WRITE, ERASE>
{
    const READ_SIZE: usize = READ;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let at = self.check(offset, bytes.len(), READ)?;
        if let Some(fault) = &self.read_fault
            && at < fault.end
            && fault.start < at + bytes.len()
        {
            return Err(RamFlashError::ReadFault);
        }
        bytes.copy_from_slice(&self.mem[at..at + bytes.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        self.mem.len()
    }
}

impl<const READ: usize, const WRITE: usize, const ERASE: usize> NorFlash
    for RamFlash<READ, WRITE, ERASE>
{
    const WRITE_SIZE: usize = WRITE;
    const ERASE_SIZE: usize = ERASE;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        let len = (to as usize)
            .checked_sub(from as usize)
            .ok_or(RamFlashError::OutOfBounds)?;
        let at = self.check(from, len, ERASE)?;
        self.erases += 1;
        for i in at..at + len {
            if !self.spend() {
                return Err(RamFlashError::PowerCut);
            }
            self.mem[i] = 0xFF;
            // A write unit is writable again once all of it is erased.
            if (i + 1).is_multiple_of(WRITE) {
                self.written[i / WRITE] = false;
            }
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let at = self.check(offset, bytes.len(), WRITE)?;
        let units = at / WRITE..(at + bytes.len()) / WRITE;
        if self.written[units.clone()].iter().any(|w| *w) {
            return Err(RamFlashError::Rewrite);
        }
        for (i, b) in bytes.iter().enumerate() {
            if !self.spend() {
                return Err(RamFlashError::PowerCut);
            }
            // A unit is programmed (and may not be written again) from its first byte on.
            self.written[(at + i) / WRITE] = true;
            self.mem[at + i] &= b;
        }
        Ok(())
    }
}
