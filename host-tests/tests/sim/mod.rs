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

#![allow(dead_code)]

use std::cell::RefCell;
use std::collections::{BTreeMap, VecDeque};
use std::rc::Rc;

use embedded_hal::i2c::{self, I2c};
use embedded_hal::spi::{self, Operation, SpiDevice};
use imu_ar::sensor::{Error, FifoStats, ImuReader, RawSample};
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

/// MPU-6050 registers (RM-MPU-6000A-00).
pub mod mpu {
    pub const FIFO_EN: u8 = 0x23;
    pub const INT_STATUS: u8 = 0x3A;
    pub const USER_CTRL: u8 = 0x6A;
    pub const PWR_MGMT_1: u8 = 0x6B;
    pub const FIFO_COUNTH: u8 = 0x72;
    pub const FIFO_R_W: u8 = 0x74;
    pub const WHO_AM_I: u8 = 0x75;
    pub const PACKET: usize = 12;
    pub const FIFO_BYTES: usize = 1024;
}

/// ICM-42688-P registers (DS-000347, bank 0).
pub mod icm {
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
    /// Every read returns 0xFF (SDA stuck high).
    pub stuck_high: bool,
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
            stuck_high: false,
            who_am_i: match model {
                Model::Mpu6050 => 0x68,
                Model::Icm42688 => 0x47,
            },
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
        match self.model {
            Model::Mpu6050 => mpu::PACKET,
            Model::Icm42688 => icm::PACKET,
        }
    }

    fn capacity(&self) -> usize {
        match self.model {
            Model::Mpu6050 => mpu::FIFO_BYTES,
            Model::Icm42688 => icm::FIFO_BYTES,
        }
    }

    fn power_on_registers(&mut self) {
        self.regs = [0; 128];
        if self.model == Model::Mpu6050 {
            self.regs[usize::from(mpu::PWR_MGMT_1)] = 0x40; // SLEEP
        }
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
        let r = |a: u8| self.regs[usize::from(a)];
        match self.model {
            Model::Mpu6050 => {
                r(mpu::PWR_MGMT_1) & 0x40 == 0
                    && r(mpu::USER_CTRL) & 0x40 != 0
                    && r(mpu::FIFO_EN) & 0x78 == 0x78
            }
            Model::Icm42688 => {
                r(icm::FIFO_CONFIG) == 0x40
                    && r(icm::FIFO_CONFIG1) & 0x03 == 0x03
                    && r(icm::PWR_MGMT0) & 0x0F == 0x0F
            }
        }
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
            let (a, mut g) = sample(seq);
            let mut bytes = Vec::with_capacity(16);
            match self.model {
                Model::Mpu6050 => {
                    bytes.extend(a.iter().chain(&g).flat_map(|v| v.to_be_bytes()));
                }
                Model::Icm42688 => {
                    if self.gyro_startup > 0 {
                        self.gyro_startup -= 1;
                        g = [i16::MIN; 3];
                    }
                    bytes.push(0x68);
                    bytes.extend(a.iter().chain(&g).flat_map(|v| v.to_be_bytes()));
                    bytes.push(20);
                    bytes.extend((seq as u16).to_be_bytes());
                }
            }
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
            if self.model == Model::Mpu6050 {
                self.int_status |= 0x10;
            }
        }
        self.fifo.push_back(b);
        if self.model == Model::Icm42688 && self.fifo.len() == cap {
            self.int_status |= 0x02;
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
        match self.model {
            Model::Mpu6050 => reg == mpu::FIFO_R_W,
            Model::Icm42688 => reg == icm::FIFO_DATA,
        }
    }

    fn read_reg(&mut self, reg: u8, count: u16) -> u8 {
        if self.stuck_high {
            return 0xFF;
        }
        let (status, counth, who) = match self.model {
            Model::Mpu6050 => (mpu::INT_STATUS, mpu::FIFO_COUNTH, mpu::WHO_AM_I),
            Model::Icm42688 => (icm::INT_STATUS, icm::FIFO_COUNTH, icm::WHO_AM_I),
        };
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
        let i = usize::from(reg & 0x7F);
        match (self.model, reg) {
            (Model::Mpu6050, mpu::PWR_MGMT_1) if value & 0x80 != 0 => self.power_on_registers(),
            (Model::Mpu6050, mpu::USER_CTRL) => {
                if value & 0x04 != 0 {
                    if value & 0x40 != 0 || self.regs[usize::from(mpu::FIFO_EN)] != 0 {
                        self.resets_with_channels_on += 1;
                    }
                    self.clear_fifo();
                }
                self.regs[i] = value & !0x04;
            }
            (Model::Icm42688, icm::DEVICE_CONFIG) if value & 0x01 != 0 => {
                self.power_on_registers();
            }
            (Model::Icm42688, icm::SIGNAL_PATH_RESET) => {
                if value & 0x02 != 0 {
                    self.clear_fifo();
                }
            }
            (Model::Icm42688, icm::PWR_MGMT0) => {
                if value & 0x0C == 0x0C && self.regs[i] & 0x0C != 0x0C {
                    self.gyro_startup = icm::GYRO_STARTUP;
                }
                self.regs[i] = value;
            }
            _ => self.regs[i] = value,
        }
    }

    /// One transfer: `Err(())` when it fails.
    fn transfer(&mut self, kind: Kind, buf: &mut [u8]) -> Result<(), ()> {
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
                self.read(reg, buf, n);
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

/// No delay: the simulator's time advances only by [`Sim::tick`].
pub struct NoDelay;

impl embedded_hal::delay::DelayNs for NoDelay {
    fn delay_ns(&mut self, _: u32) {}
}

/// Checks delivered samples: each exactly one the chip produced, in order.
fn accept(out: &[RawSample], last_seq: &mut Option<u64>) -> u64 {
    for s in out {
        let seq = decode(s).unwrap_or_else(|| panic!("a malformed sample delivered: {s:?}"));
        assert!(last_seq.is_none_or(|l| l < seq), "out of order: {seq}");
        *last_seq = Some(seq);
    }
    out.len() as u64
}

/// What a run with random bus faults did.
#[derive(Debug)]
pub struct Figures {
    pub ticks: u64,
    pub produced: u64,
    pub delivered: u64,
    pub stats: FifoStats,
    pub dropped_by_chip: u64,
    pub paused_outside_outages: u64,
    pub left_in_fifo: u64,
    pub transfers: u64,
    pub faults: u64,
    pub kinds: usize,
    pub recoveries: u64,
    pub failed_recoveries: u64,
    pub overflows_forced: u64,
}

/// Runs `reader` on `sim` with faults at `rate` on every transfer until `target` samples were
/// delivered, calling `recover` the way a board loop does; then stops the faults, recovers
/// once and checks that samples flow. Every delivered sample is checked against the chip's,
/// in order; at the end every tick is accounted for:
///
/// `ticks = delivered + discarded + invalid + malformed + lost + dropped by the chip while
/// full + ticks with the FIFO's channels off outside an outage + left in the FIFO`.
pub fn fault_run<R: ImuReader>(
    sim: &Rc<RefCell<Sim>>,
    reader: &mut R,
    mut recover: impl FnMut(&mut R, u64) -> Result<(), Error<R::BusError>>,
    seed: u64,
    rate: f64,
    target: u64,
) -> Figures
where
    R::BusError: std::fmt::Debug,
{
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = vec![RawSample::default(); 256];
    let mut last_accounted = sim.borrow().ticks;
    let mut dropped_at_accounting = sim.borrow().dropped;
    let mut last_seq: Option<u64> = None;
    let mut outages: Vec<(u64, u64)> = Vec::new();
    let (mut delivered, mut recoveries, mut failed, mut forced) = (0u64, 0, 0, 0);
    let capacity = sim.borrow().capacity() / sim.borrow().packet_len();
    sim.borrow_mut().rate = rate;

    let mut try_recover = |reader: &mut R,
                           last_accounted: &mut u64,
                           dropped_at: &mut u64,
                           outages: &mut Vec<(u64, u64)>|
     -> bool {
        let now = sim.borrow().ticks;
        match recover(reader, (now - *last_accounted) * 1000) {
            Ok(()) => {
                assert_eq!(
                    sim.borrow().dropped,
                    *dropped_at,
                    "an overflow inside an outage would be counted twice"
                );
                outages.push((*last_accounted, now));
                *last_accounted = now;
                true
            }
            Err(Error::Bus(_)) => false,
            Err(e) => panic!("recover: {e:?}"),
        }
    };

    while delivered < target {
        let n = if rng.next_u32() % 1000 < 3 {
            forced += 1;
            capacity as u64 + 20
        } else {
            u64::from(rng.next_u32() % 13)
        };
        sim.borrow_mut().tick(n);
        let now = sim.borrow().ticks;
        let res = reader.read_fifo(&mut out);
        match res {
            Ok(k) => {
                delivered += accept(&out[..k], &mut last_seq);
                last_accounted = now;
                dropped_at_accounting = sim.borrow().dropped;
                if rng.next_u32() % 20 == 0 {
                    // A suspected glitch: recover anyway, a few samples later.
                    sim.borrow_mut().tick(u64::from(rng.next_u32() % 13));
                    if try_recover(
                        reader,
                        &mut last_accounted,
                        &mut dropped_at_accounting,
                        &mut outages,
                    ) {
                        recoveries += 1;
                    } else {
                        failed += 1;
                    }
                }
            }
            Err(Error::FifoOverflow { .. } | Error::FifoResync { .. }) => {
                last_accounted = now;
                dropped_at_accounting = sim.borrow().dropped;
            }
            Err(Error::Bus(_)) => {}
            Err(Error::FifoNotRunning | Error::SensorReset) => {
                if try_recover(
                    reader,
                    &mut last_accounted,
                    &mut dropped_at_accounting,
                    &mut outages,
                ) {
                    recoveries += 1;
                } else {
                    failed += 1;
                }
            }
            Err(e) => panic!("read_fifo: {e:?}"),
        }
    }

    // The faults stop: one recovery, and samples flow again.
    sim.borrow_mut().rate = 0.0;
    sim.borrow_mut().tick(5);
    assert!(
        try_recover(
            reader,
            &mut last_accounted,
            &mut dropped_at_accounting,
            &mut outages
        ),
        "recover after the faults stopped"
    );
    recoveries += 1;
    sim.borrow_mut().tick(50);
    let k = reader
        .read_fifo(&mut out)
        .expect("samples after one recover");
    assert!(k > 0, "no samples after one recover");
    delivered += accept(&out[..k], &mut last_seq);

    let sim = sim.borrow();
    let paused_outside = sim
        .paused
        .iter()
        .filter(|&&t| !outages.iter().any(|&(a, b)| (a..b).contains(&t)))
        .count() as u64;
    let stats = reader.fifo_stats();
    let figures = Figures {
        ticks: sim.ticks,
        produced: sim.produced,
        delivered,
        stats,
        dropped_by_chip: sim.dropped,
        paused_outside_outages: paused_outside,
        left_in_fifo: sim.fifo_packets(),
        transfers: sim.transfers.values().sum(),
        faults: sim.injected.values().sum(),
        kinds: sim.transfers.len(),
        recoveries,
        failed_recoveries: failed,
        overflows_forced: forced,
    };
    assert_eq!(stats.samples, delivered);
    let fault_rate = figures.faults as f64 / figures.transfers as f64;
    assert!(
        (0.8 * rate..1.2 * rate).contains(&fault_rate),
        "fault rate {fault_rate}"
    );
    for kind in sim.transfers.keys() {
        assert!(
            sim.injected.get(kind).copied().unwrap_or(0) > 0,
            "no fault at {kind:?}: {figures:#?}"
        );
    }
    assert_eq!(
        figures.ticks,
        delivered
            + stats.discarded
            + stats.invalid
            + stats.malformed
            + stats.lost
            + figures.dropped_by_chip
            + paused_outside
            + figures.left_in_fifo,
        "every tick accounted for: {figures:#?}"
    );
    figures
}
