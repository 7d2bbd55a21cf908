//! Red team: one fault at every transfer of one `read_fifo` call, for every fault kind, FIFO
//! fill and `out` length, on both chips and both readers; then a clean bus, recovering the way
//! a board loop does. Checks: no panic, no garbage or out-of-order sample, every tick
//! accounted for within the documented bounds, samples flow again, and the async reader gives
//! the blocking one's results figure for figure.

use std::cell::RefCell;
use std::rc::Rc;

use embedded_hal::i2c::{self, I2c};
use embedded_hal::spi::{self, Operation, SpiDevice};
use imu_ar::sensor::{
    Dlpf, Error, FifoStats, Icm42688, Icm42688Async, Icm42688Config, Mpu6050, Mpu6050Async,
    Mpu6050Config, Odr, RawSample,
};

use crate::sim::asynch::{AsyncBus, AsyncNoDelay, block_on};
use crate::sim::hooks::{Action, HookedI2c, HookedSpi, Hooks};
use crate::sim::icm42688::{self as icm, SimSpi};
use crate::sim::mpu6050::SimI2c;
use crate::sim::{Kind, Model, NoDelay, Sim, decode};

type Trace = Rc<RefCell<Vec<(Kind, usize)>>>;

/// A bus that records every transfer's kind and length.
pub struct Traced<B> {
    inner: B,
    trace: Trace,
}

impl<B: i2c::ErrorType> i2c::ErrorType for Traced<B> {
    type Error = B::Error;
}

impl<B: I2c> I2c for Traced<B> {
    fn transaction(
        &mut self,
        address: u8,
        ops: &mut [i2c::Operation<'_>],
    ) -> Result<(), Self::Error> {
        let rec = match &*ops {
            [i2c::Operation::Write(w)] => (Kind::Write(w[0]), w.len() - 1),
            [i2c::Operation::Write(w), i2c::Operation::Read(r)] => (Kind::Read(w[0]), r.len()),
            _ => panic!("unexpected"),
        };
        self.trace.borrow_mut().push(rec);
        self.inner.transaction(address, ops)
    }
}

impl<B: spi::ErrorType> spi::ErrorType for Traced<B> {
    type Error = B::Error;
}

impl<B: SpiDevice> SpiDevice for Traced<B> {
    fn transaction(&mut self, ops: &mut [Operation<'_, u8>]) -> Result<(), Self::Error> {
        let rec = match &*ops {
            [Operation::Write(w)] => (Kind::Write(w[0]), w.len() - 1),
            [Operation::Write(w), Operation::Read(r)] => (Kind::Read(w[0] & 0x7F), r.len()),
            _ => panic!("unexpected"),
        };
        self.trace.borrow_mut().push(rec);
        self.inner.transaction(ops)
    }
}

type E = Error<()>;

fn plain<X>(e: Error<X>) -> E {
    match e {
        Error::Bus(_) => Error::Bus(()),
        Error::WrongDevice { found } => Error::WrongDevice { found },
        Error::UnsupportedDevice { found } => Error::UnsupportedDevice { found },
        Error::FifoOverflow { discarded } => Error::FifoOverflow { discarded },
        Error::FifoResync { discarded } => Error::FifoResync { discarded },
        Error::BadFifoCount { count } => Error::BadFifoCount { count },
        Error::FifoDisabled => Error::FifoDisabled,
        Error::NotInitialised => Error::NotInitialised,
        Error::FifoNotRunning => Error::FifoNotRunning,
        Error::SensorReset => Error::SensorReset,
        Error::NoData => Error::NoData,
        Error::WriteNotApplied { register } => Error::WriteNotApplied { register },
    }
}

/// One reader on one simulated chip.
trait Rig {
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, E>;
    fn recover(&mut self, outage_us: u64) -> Result<u8, E>;
    fn stats(&self) -> FifoStats;
}

struct MpuB(Mpu6050<Traced<HookedI2c>>);
struct MpuA(Mpu6050Async<AsyncBus<Traced<HookedI2c>>>);
struct IcmB(Icm42688<Traced<HookedSpi>>);
struct IcmA(Icm42688Async<AsyncBus<Traced<HookedSpi>>>);

impl Rig for MpuB {
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, E> {
        use imu_ar::sensor::ImuReader;
        self.0.read_fifo(out).map_err(plain)
    }
    fn recover(&mut self, us: u64) -> Result<u8, E> {
        self.0.recover(&mut NoDelay, us).map_err(plain)
    }
    fn stats(&self) -> FifoStats {
        use imu_ar::sensor::ImuReader;
        self.0.fifo_stats()
    }
}
impl Rig for IcmB {
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, E> {
        use imu_ar::sensor::ImuReader;
        self.0.read_fifo(out).map_err(plain)
    }
    fn recover(&mut self, us: u64) -> Result<u8, E> {
        self.0.recover(&mut NoDelay, us).map_err(plain)
    }
    fn stats(&self) -> FifoStats {
        use imu_ar::sensor::ImuReader;
        self.0.fifo_stats()
    }
}
impl Rig for MpuA {
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, E> {
        block_on(self.0.read_fifo(out)).map_err(plain)
    }
    fn recover(&mut self, us: u64) -> Result<u8, E> {
        block_on(self.0.recover(&mut AsyncNoDelay, us)).map_err(plain)
    }
    fn stats(&self) -> FifoStats {
        self.0.fifo_stats()
    }
}
impl Rig for IcmA {
    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, E> {
        block_on(self.0.read_fifo(out)).map_err(plain)
    }
    fn recover(&mut self, us: u64) -> Result<u8, E> {
        block_on(self.0.recover(&mut AsyncNoDelay, us)).map_err(plain)
    }
    fn stats(&self) -> FifoStats {
        self.0.fifo_stats()
    }
}

struct Setup {
    sim: Rc<RefCell<Sim>>,
    hooks: Hooks,
    trace: Trace,
    rig: Box<dyn Rig>,
    /// Ticks before the test proper (the ICM's gyro start-up).
    t0: u64,
    base: FifoStats,
    p0: u64,
}

fn setup(model: Model, asynch: bool, seed: u64) -> Setup {
    let sim = Sim::new(model, seed);
    let hooks = Hooks::default();
    let trace: Trace = Rc::default();
    let mut rig: Box<dyn Rig> = match model {
        Model::Mpu6050 => {
            let bus = Traced {
                inner: HookedI2c {
                    sim: sim.clone(),
                    inner: SimI2c(sim.clone()),
                    hooks: hooks.clone(),
                },
                trace: trace.clone(),
            };
            let config = Mpu6050Config {
                dlpf: Dlpf::Hz44,
                sample_rate_divider: 0,
                ..Mpu6050Config::default()
            };
            if asynch {
                let mut r = Mpu6050Async::new(AsyncBus(bus), 0x68);
                block_on(r.init(&mut AsyncNoDelay, config)).unwrap();
                block_on(r.enable_fifo()).unwrap();
                Box::new(MpuA(r))
            } else {
                let mut r = Mpu6050::new(bus, 0x68);
                r.init(&mut NoDelay, config).unwrap();
                r.enable_fifo().unwrap();
                Box::new(MpuB(r))
            }
        }
        Model::Icm42688 => {
            let bus = Traced {
                inner: HookedSpi {
                    sim: sim.clone(),
                    inner: SimSpi(sim.clone()),
                    hooks: hooks.clone(),
                },
                trace: trace.clone(),
            };
            let config = Icm42688Config {
                odr: Odr::Hz1000,
                ..Icm42688Config::default()
            };
            if asynch {
                let mut r = Icm42688Async::new(AsyncBus(bus));
                block_on(r.init(&mut AsyncNoDelay, config)).unwrap();
                block_on(r.enable_fifo()).unwrap();
                Box::new(IcmA(r))
            } else {
                let mut r = Icm42688::new(bus);
                r.init(&mut NoDelay, config).unwrap();
                r.enable_fifo().unwrap();
                Box::new(IcmB(r))
            }
        }
    };
    if model == Model::Icm42688 {
        sim.borrow_mut().tick(u64::from(icm::GYRO_STARTUP));
        let mut out = [RawSample::default(); 8];
        assert_eq!(rig.read_fifo(&mut out), Ok(0));
    }
    trace.borrow_mut().clear();
    let t0 = sim.borrow().ticks;
    let base = rig.stats();
    let p0 = sim.borrow().produced;
    Setup {
        sim,
        hooks,
        trace,
        rig,
        t0,
        base,
        p0,
    }
}

#[derive(Clone, Debug)]
enum Fault {
    Fail(usize),
    FailApplied,
    Glitch,
    Tick(u64),
    Slip,
}

/// What a session did: the results of its calls and its final stats.
#[derive(Debug, PartialEq)]
struct Outcome {
    results: Vec<Result<usize, E>>,
    stats: FifoStats,
}

/// Runs: `fill` samples, the faulted call with `out_len`, then a clean settle phase.
/// Returns the outcome, or a description of the broken guarantee.
fn session(
    model: Model,
    asynch: bool,
    fill: u64,
    out_len: usize,
    fault: Option<(usize, Fault)>,
) -> Result<Outcome, String> {
    let mut s = setup(model, asynch, 4242);
    let sim = s.sim.clone();
    sim.borrow_mut().tick(fill);
    let mut results = Vec::new();
    if let Some((i, f)) = &fault {
        // The clean call's trace, recorded by a dry run of the same session.
        let trace = clean_trace(model, asynch, fill, out_len);
        let Some(&(kind, len)) = trace.get(*i) else {
            return Err("no such transfer".into());
        };
        let skip = trace[..*i].iter().filter(|(k, _)| *k == kind).count() as u32;
        match f {
            Fault::Fail(c) => sim.borrow_mut().fail(kind, skip, *c),
            Fault::FailApplied => sim.borrow_mut().fail_applied(kind, skip),
            Fault::Glitch => s.hooks.add(kind, skip, Action::GlitchBefore),
            Fault::Tick(n) => s.hooks.add(kind, skip, Action::TickBefore(*n)),
            Fault::Slip => {
                if len < 2 {
                    return Err("no such transfer".into());
                }
                s.hooks.add(kind, skip, Action::Slip)
            }
        }
    }
    let mut out = vec![RawSample::default(); 256];
    let mut delivered = 0u64;
    let mut last_seq: Option<u64> = None;
    let mut last_accounted = s.t0;
    let mut outages: Vec<(u64, u64)> = Vec::new();
    let mut undrained = 0u64;
    let mut overcount_room = 0u64;
    let mut last = Err(Error::Bus(()));
    let mut dropped_at = 0;
    for call in 0..20 {
        let n = if call == 0 { out_len } else { 256 };
        if call > 0 {
            sim.borrow_mut().tick(3);
        }
        let before = sim.borrow().ticks;
        let held_before = sim.borrow().fifo_packets();
        let r = s.rig.read_fifo(&mut out[..n]);
        let after = sim.borrow().ticks;
        results.push(r);
        last = r;
        match r {
            Ok(k) => {
                for smp in &out[..k] {
                    let seq = decode(smp).ok_or(format!("garbage sample delivered: {smp:?}"))?;
                    if last_seq.is_some_and(|l| l >= seq) {
                        return Err(format!("out of order/duplicate: {seq}"));
                    }
                    last_seq = Some(seq);
                }
                delivered += k as u64;
                last_accounted = before;
                dropped_at = sim.borrow().dropped;
                // README: the outage is exact only if the read that began it emptied the FIFO.
                undrained = held_before.saturating_sub(k as u64);
            }
            Err(Error::FifoOverflow { .. } | Error::FifoResync { .. }) => {
                last_accounted = after;
                dropped_at = sim.borrow().dropped;
                undrained = 0;
            }
            Err(Error::SensorReset | Error::FifoNotRunning) => {
                let now = sim.borrow().ticks;
                let rr = s.rig.recover((now - last_accounted) * 1000);
                results.push(rr.map(usize::from));
                if rr.is_ok() {
                    outages.push((last_accounted, now));
                    last_accounted = now;
                    // Samples the full FIFO overwrote inside the outage are in `lost` too.
                    overcount_room += undrained + (sim.borrow().dropped - dropped_at);
                    undrained = 0;
                }
            }
            Err(Error::Bus(())) | Err(Error::BadFifoCount { .. }) => {}
            Err(e) => return Err(format!("unexpected {e:?}")),
        }
    }
    if !matches!(last, Ok(k) if k > 0) {
        return Err(format!("samples do not flow again: {results:?}"));
    }
    let st = s.rig.stats();
    let b = s.base;
    let sim = sim.borrow();
    let paused = sim
        .paused
        .iter()
        .filter(|&&t| t >= s.t0 && !outages.iter().any(|&(a, z)| (a..z).contains(&t)))
        .count() as u64;
    let counted = delivered
        + (st.discarded - b.discarded)
        + (st.invalid - b.invalid)
        + (st.malformed - b.malformed)
        + (st.lost - b.lost)
        + sim.dropped
        + paused
        + sim.fifo_packets();
    let ticks = sim.ticks - s.t0;
    let unsure = st.unsure - b.unsure;
    let slips = sim.slipped + u64::from(matches!(fault, Some((_, Fault::Slip))));
    let _ = s.p0;
    if !(counted <= ticks + slips + overcount_room && ticks <= counted + unsure + overcount_room) {
        return Err(format!(
            "accounting: {ticks} ticks, {counted} counted (delivered {delivered}), unsure \
             {unsure}, room {overcount_room}: {st:?}; {results:?}"
        ));
    }
    drop(s.trace);
    Ok(Outcome { results, stats: st })
}

fn clean_trace(model: Model, asynch: bool, fill: u64, out_len: usize) -> Vec<(Kind, usize)> {
    let mut s = setup(model, asynch, 4242);
    s.sim.borrow_mut().tick(fill);
    let mut out = vec![RawSample::default(); out_len];
    let _ = s.rig.read_fifo(&mut out);
    s.trace.borrow().clone()
}

fn faults(model: Model) -> Vec<Fault> {
    let mut v = vec![
        Fault::Fail(0),
        Fault::Fail(1),
        Fault::Fail(5),
        Fault::Fail(12),
        Fault::Fail(13),
        Fault::Fail(16),
        Fault::Fail(17),
        Fault::Fail(usize::MAX),
        Fault::FailApplied,
        Fault::Glitch,
        Fault::Tick(1),
        Fault::Tick(3),
    ];
    if model == Model::Icm42688 {
        v.push(Fault::Slip);
    }
    v
}

fn sweep(model: Model) -> Vec<String> {
    let full = if model == Model::Mpu6050 { 85 } else { 128 };
    let fills = [0u64, 1, 7, 8, 9, 16, full - 1, full, full + 3];
    let outs = [0usize, 1, 3, 8, 9, 256];
    let mut failures = Vec::new();
    for &fill in &fills {
        for &out_len in &outs {
            let n = clean_trace(model, false, fill, out_len).len();
            for i in 0..n {
                for f in faults(model) {
                    let b = session(model, false, fill, out_len, Some((i, f.clone())));
                    let a = session(model, true, fill, out_len, Some((i, f.clone())));
                    let tag = format!("{model:?} fill {fill} out {out_len} transfer {i} {f:?}");
                    match (&b, &a) {
                        (Err(e), _) if e == "no such transfer" => continue,
                        (Err(e), _) => failures.push(format!("{tag}: blocking: {e}")),
                        (Ok(_), Err(e)) => failures.push(format!("{tag}: async: {e}")),
                        (Ok(x), Ok(y)) if x != y => {
                            failures.push(format!("{tag}: async differs: {:?} vs {:?}", x, y))
                        }
                        _ => {}
                    }
                }
            }
        }
    }
    failures
}

fn report(model: Model) {
    let failures = sweep(model);
    let n = failures.len();
    let shown: Vec<&String> = failures.iter().take(40).collect();
    assert!(
        failures.is_empty(),
        "{n} failing fault positions, first ones:\n{}",
        shown
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join("\n")
    );
}

#[test]
fn mpu_fault_at_every_transfer_sweep() {
    report(Model::Mpu6050);
}

#[test]
fn icm_fault_at_every_transfer_sweep() {
    report(Model::Icm42688);
}
