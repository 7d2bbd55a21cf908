//! A register-level simulator of the MPU-6050 (I2C) and the ICM-42688-P (SPI), built from their
//! register maps, for the reader tests:
//!
//! - INT_STATUS bits clear on read (FIFO_OFLOW_INT, bit 4, on the MPU-6050; FIFO_FULL_INT, bit
//!   1, on the ICM-42688-P);
//! - a full FIFO (1024 bytes; 2048) overwrites its oldest bytes and keeps writing;
//! - an empty FIFO data register repeats the last byte read;
//! - any chosen bus transfer can be made to fail, and every transfer can fail at random: a
//!   failed FIFO read clocks some bytes out first, a failed register read may have cleared
//!   INT_STATUS, a failed write may or may not have been applied.
//!
//! Time advances only through [`Sim::tick`], one sample period per tick, between reader calls.
//! Each tick's sample carries its tick number, so every delivered sample can be checked
//! against what the chip produced ([`decode`]).
//!
//! This module is the chip-independent part; each chip's registers, register side effects,
//! FIFO packet and bus are in its own module ([`mpu6050`], [`icm42688`]); buses that act at a
//! chosen transfer are in [`hooks`], and the run with random bus faults is in [`run`].

#![allow(dead_code)]

pub mod asynch;
pub mod hooks;
pub mod icm42688;
pub mod mpu6050;
pub mod run;

use std::cell::RefCell;
use std::collections::{BTreeMap, VecDeque};
use std::rc::Rc;

use imu_ar::sensor::RawSample;
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};

/// The simulated chip.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// MPU-6050 at I2C address 0x68.
    Mpu6050,
    /// ICM-42688-P on SPI.
    Icm42688,
}

impl Model {
    fn chip(self) -> &'static Chip {
        match self {
            Model::Mpu6050 => &mpu6050::CHIP,
            Model::Icm42688 => &icm42688::CHIP,
        }
    }
}

/// What differs between the simulated chips.
pub struct Chip {
    /// WHO_AM_I's answer.
    id: u8,
    /// Bytes per FIFO packet.
    packet: usize,
    /// FIFO size in bytes.
    fifo_bytes: usize,
    /// INT_STATUS, FIFO_COUNTH, WHO_AM_I and the FIFO data register.
    int_status: u8,
    fifo_counth: u8,
    who_am_i: u8,
    fifo_data: u8,
    /// INT_STATUS bits set when the full FIFO overwrites a byte, and when it becomes full.
    overwrite_flag: u8,
    full_flag: u8,
    /// The register and bit that reset the chip.
    reset: (u8, u8),
    /// Sets the registers that are not 0 at power-on.
    power_on: fn(&mut [u8; 128]),
    /// Whether the FIFO takes samples, by the registers.
    accepting: fn(&[u8; 128]) -> bool,
    /// The FIFO packet of tick `seq` with these accelerometer and gyro values.
    packet_of: fn(&mut Sim, u64, [i16; 3], [i16; 3]) -> Vec<u8>,
    /// What a register write other than the reset does besides storing its value: returns
    /// the value stored, if any.
    write: fn(&mut Sim, u8, u8) -> Option<u8>,
}

/// A kind of bus transfer: a write to a register, or a read starting at one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Kind {
    /// A register write.
    Write(u8),
    /// A (burst) read from a register.
    Read(u8),
}

/// A scheduled fault.
struct Rule {
    kind: Kind,
    skip: u32,
    clock_out: usize,
    apply: bool,
}

/// How a transfer fails.
struct Fault {
    clock_out: usize,
    apply: bool,
}

/// The simulated chip and its bus.
pub struct Sim {
    pub model: Model,
    regs: [u8; 128],
    fifo: VecDeque<u8>,
    /// Position, within its packet, of the FIFO's first byte.
    head: usize,
    last: u8,
    int_status: u8,
    gyro_startup: u32,
    rng: ChaCha8Rng,
    rules: Vec<Rule>,
    /// Probability of a random fault at each transfer.
    pub rate: f64,
    /// Probability that one to three samples arrive right before a transfer (samples keep
    /// arriving while the reader works).
    pub arrivals: f64,
    /// Probability that a FIFO data read slips a byte: it takes one byte fewer out of the
    /// FIFO than it returns, its last byte repeating the one before, and reports success (SPI
    /// has no acknowledge).
    pub slips: f64,
    /// Slips made.
    pub slipped: u64,
    /// Every read returns 0xFF (SDA stuck high).
    pub stuck_high: bool,
    /// The sensor is unplugged: every transfer fails and does nothing.
    pub unplugged: bool,
    /// WHO_AM_I answered by the chip.
    pub who_am_i: u8,
    /// Transfers by kind.
    pub transfers: BTreeMap<Kind, u64>,
    /// Faults injected by kind.
    pub injected: BTreeMap<Kind, u64>,
    /// Sample periods elapsed.
    pub ticks: u64,
    /// Samples written into the FIFO.
    pub produced: u64,
    /// Packets damaged by the FIFO overwriting its oldest bytes.
    pub dropped: u64,
    /// Ticks at which the FIFO took no sample (off, or its channels off).
    pub paused: Vec<u64>,
    /// The FIFO has overwritten bytes since it was last emptied by a reset.
    pub overflowed: bool,
    /// FIFO resets (MPU-6050 USER_CTRL.FIFO_RESET) done with the FIFO or its channels on.
    pub resets_with_channels_on: u64,
}

/// The sample of tick `seq`: small values, never a rail nor the invalid marker.
pub fn sample(seq: u64) -> ([i16; 3], [i16; 3]) {
    let f = |v: u64| i16::try_from(v).unwrap();
    (
        [
            f(seq & 0x3FFF),
            f((seq >> 14) & 0x3FFF),
            f(1000 + seq % 977),
        ],
        [-f(seq % 1013), f((seq * 7) % 2003), f((seq >> 28) & 0x3FFF)],
    )
}

/// The tick of a delivered sample, if it is exactly one the chip produced.
pub fn decode(s: &RawSample) -> Option<u64> {
    let part = |v: i16| u64::try_from(v).ok();
    let seq = part(s.accel[0])? | part(s.accel[1])? << 14 | part(s.gyro[2])? << 28;
    (sample(seq) == (s.accel, s.gyro)).then_some(seq)
}

impl Sim {
    /// A chip after power-on, with no faults.
    pub fn new(model: Model, seed: u64) -> Rc<RefCell<Self>> {
        let mut sim = Self {
            model,
            regs: [0; 128],
            fifo: VecDeque::new(),
            head: 0,
            last: 0,
            int_status: 0,
            gyro_startup: 0,
            rng: ChaCha8Rng::seed_from_u64(seed),
            rules: Vec::new(),
            rate: 0.0,
            arrivals: 0.0,
            slips: 0.0,
            slipped: 0,
            stuck_high: false,
            unplugged: false,
            who_am_i: model.chip().id,
            transfers: BTreeMap::new(),
            injected: BTreeMap::new(),
            ticks: 0,
            produced: 0,
            dropped: 0,
            paused: Vec::new(),
            overflowed: false,
            resets_with_channels_on: 0,
        };
        sim.power_on_registers();
        Rc::new(RefCell::new(sim))
    }

    fn packet_len(&self) -> usize {
        self.model.chip().packet
    }

    fn capacity(&self) -> usize {
        self.model.chip().fifo_bytes
    }

    fn power_on_registers(&mut self) {
        self.regs = [0; 128];
        (self.model.chip().power_on)(&mut self.regs);
        self.int_status = 0;
        self.gyro_startup = 0;
        self.clear_fifo();
    }

    /// Packets that begin in the FIFO.
    pub fn fifo_packets(&self) -> u64 {
        let p = self.packet_len();
        let first = (p - self.head) % p;
        if self.fifo.len() > first {
            ((self.fifo.len() - 1 - first) / p + 1) as u64
        } else {
            0
        }
    }

    /// Bytes in the FIFO.
    pub fn fifo_len(&self) -> usize {
        self.fifo.len()
    }

    fn clear_fifo(&mut self) {
        self.fifo.clear();
        self.head = 0;
        self.overflowed = false;
    }

    /// The chip resets itself (a supply glitch): configuration gone, FIFO off and empty.
    pub fn glitch(&mut self) {
        self.power_on_registers();
    }

    /// Fails the `skip`-th next transfer of `kind` (0: the next one); a FIFO read clocks
    /// `clock_out` bytes out first, a write is not applied.
    pub fn fail(&mut self, kind: Kind, skip: u32, clock_out: usize) {
        self.rules.push(Rule {
            kind,
            skip,
            clock_out,
            apply: false,
        });
    }

    /// Fails the `skip`-th next transfer of `kind` after applying it (a write that took
    /// effect, a read whose side effects happened).
    pub fn fail_applied(&mut self, kind: Kind, skip: u32) {
        self.rules.push(Rule {
            kind,
            skip,
            clock_out: usize::MAX,
            apply: true,
        });
    }

    /// Whether the FIFO takes samples now.
    fn accepting(&self) -> bool {
        (self.model.chip().accepting)(&self.regs)
    }

    /// `n` sample periods: each writes a sample into the FIFO if it is on.
    pub fn tick(&mut self, n: u64) {
        for _ in 0..n {
            let seq = self.ticks;
            self.ticks += 1;
            if !self.accepting() {
                self.paused.push(seq);
                continue;
            }
            let (a, g) = sample(seq);
            let bytes = (self.model.chip().packet_of)(self, seq, a, g);
            self.produced += 1;
            for b in bytes {
                self.push(b);
            }
        }
    }

    fn push(&mut self, b: u8) {
        let (p, cap) = (self.packet_len(), self.capacity());
        if self.fifo.len() == cap {
            self.fifo.pop_front();
            if self.head == 0 {
                self.dropped += 1;
            }
            self.head = (self.head + 1) % p;
            self.overflowed = true;
            self.int_status |= self.model.chip().overwrite_flag;
        }
        self.fifo.push_back(b);
        if self.fifo.len() == cap {
            self.int_status |= self.model.chip().full_flag;
        }
    }

    fn pop(&mut self) -> u8 {
        if let Some(b) = self.fifo.pop_front() {
            self.head = (self.head + 1) % self.packet_len();
            self.last = b;
        }
        self.last
    }

    fn decide(&mut self, kind: Kind, len: usize) -> Option<Fault> {
        *self.transfers.entry(kind).or_default() += 1;
        if self.unplugged {
            return Some(Fault {
                clock_out: 0,
                apply: false,
            });
        }
        let mut fault = None;
        if let Some(i) = self.rules.iter().position(|r| r.kind == kind) {
            if self.rules[i].skip == 0 {
                let r = self.rules.remove(i);
                fault = Some(Fault {
                    clock_out: r.clock_out.min(len),
                    apply: r.apply,
                });
            } else {
                self.rules[i].skip -= 1;
            }
        }
        if fault.is_none() && self.rate > 0.0 {
            let draw = self.rng.next_u64() as f64 / u64::MAX as f64;
            if draw < self.rate {
                let r = self.rng.next_u64();
                fault = Some(Fault {
                    clock_out: (r % (len as u64 + 1)) as usize,
                    apply: r & (1 << 40) != 0,
                });
            }
        }
        if fault.is_some() {
            *self.injected.entry(kind).or_default() += 1;
        }
        fault
    }

    fn is_fifo_data(&self, reg: u8) -> bool {
        reg == self.model.chip().fifo_data
    }

    fn read_reg(&mut self, reg: u8, count: u16) -> u8 {
        if self.stuck_high {
            return 0xFF;
        }
        let chip = self.model.chip();
        let (status, counth, who) = (chip.int_status, chip.fifo_counth, chip.who_am_i);
        if reg == status {
            std::mem::take(&mut self.int_status)
        } else if reg == counth {
            (count >> 8) as u8
        } else if reg == counth + 1 {
            count as u8
        } else if reg == who {
            self.who_am_i
        } else if self.is_fifo_data(reg) {
            self.pop()
        } else {
            self.regs[usize::from(reg & 0x7F)]
        }
    }

    /// A read of `buf.len()` bytes from `reg` (auto-incrementing, except the FIFO data
    /// register); `limit` bytes at most are clocked out.
    fn read(&mut self, reg: u8, buf: &mut [u8], limit: usize) {
        let count = self.fifo.len() as u16;
        let mut r = reg;
        for b in buf.iter_mut().take(limit) {
            *b = self.read_reg(r, count);
            if !self.is_fifo_data(r) {
                r = r.wrapping_add(1);
            }
        }
    }

    fn write(&mut self, reg: u8, value: u8) {
        let chip = self.model.chip();
        let (reset, bit) = chip.reset;
        if reg == reset && value & bit != 0 {
            self.power_on_registers();
        } else if let Some(v) = (chip.write)(self, reg, value) {
            self.regs[usize::from(reg & 0x7F)] = v;
        }
    }

    /// One transfer: `Err(())` when it fails.
    fn transfer(&mut self, kind: Kind, buf: &mut [u8]) -> Result<(), ()> {
        if self.arrivals > 0.0 && !self.unplugged {
            let draw = self.rng.next_u64() as f64 / u64::MAX as f64;
            if draw < self.arrivals {
                let n = 1 + self.rng.next_u64() % 3;
                self.tick(n);
            }
        }
        let fault = self.decide(kind, buf.len());
        match (kind, fault) {
            (Kind::Write(reg), None) => {
                self.write(reg, buf[0]);
                Ok(())
            }
            (Kind::Write(reg), Some(f)) => {
                if f.apply {
                    self.write(reg, buf[0]);
                }
                Err(())
            }
            (Kind::Read(reg), None) => {
                let n = buf.len();
                let slip = self.slips > 0.0
                    && n > 1
                    && self.is_fifo_data(reg)
                    && (self.rng.next_u64() as f64 / u64::MAX as f64) < self.slips;
                if slip {
                    self.slipped += 1;
                    self.read(reg, &mut buf[..n - 1], n - 1);
                    buf[n - 1] = buf[n - 2];
                } else {
                    self.read(reg, buf, n);
                }
                Ok(())
            }
            (Kind::Read(reg), Some(f)) => {
                let n = if self.is_fifo_data(reg) {
                    f.clock_out
                } else if f.apply {
                    buf.len()
                } else {
                    0
                };
                self.read(reg, buf, n);
                Err(())
            }
        }
    }
}

/// No delay: the simulator's time advances only by [`Sim::tick`].
pub struct NoDelay;

impl embedded_hal::delay::DelayNs for NoDelay {
    fn delay_ns(&mut self, _: u32) {}
}
