//! The long run with random bus faults that each chip's tests end with ([`fault_run`]).

use std::cell::RefCell;
use std::rc::Rc;

use imu_ar::sensor::{Error, FifoStats, ImuReader, RawSample};
use rand_chacha::ChaCha8Rng;
use rand_core::{RngCore, SeedableRng};

use super::{Sim, decode};

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
///
/// With samples arriving during transfers (`Sim::arrivals`) or byte slips (`Sim::slips`) the
/// sum is within its bounds instead: at most `unsure` below the ticks, at most one per slip
/// above them.
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
    let arrived_or_slipped = sim.borrow().arrivals > 0.0 || sim.borrow().slips > 0.0;
    sim.borrow_mut().rate = 0.0;
    sim.borrow_mut().arrivals = 0.0;
    sim.borrow_mut().slips = 0.0;
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
    let slipped = sim.slipped;
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
    let counted = delivered
        + stats.discarded
        + stats.invalid
        + stats.malformed
        + stats.lost
        + figures.dropped_by_chip
        + paused_outside
        + figures.left_in_fifo;
    if arrived_or_slipped {
        // Samples arriving while a failed transfer clocks out bytes look the same to the
        // counts as a transfer that clocked out more (`FifoStats::unsure`); a slipped byte
        // can make one sample count twice.
        assert!(
            counted <= figures.ticks + slipped && figures.ticks <= counted + stats.unsure,
            "every tick accounted for within the bounds: {counted} counted, {slipped} slips, \
             {figures:#?}"
        );
    } else {
        assert_eq!(
            figures.ticks, counted,
            "every tick accounted for: {figures:#?}"
        );
    }
    figures
}
