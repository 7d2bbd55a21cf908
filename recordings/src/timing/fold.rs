//! A clock's stamps folded on its period: the rate where the intervals cannot tell it.
//!
//! A clock at `f` Hz stamps its samples at `t0 + k / f`, each rounded to the stamps'
//! quantum, some lost, some caught up late, some written twice. Folded on the right
//! frequency (each stamp's phase, `f t` modulo one) the stamps bunch within the quantum's
//! share of a period (`q f`); folded on any other they spread as the phase drifts. The
//! frequency where they bunch most (the largest Rayleigh power `|sum e^(2 pi i f t)|^2 / n`)
//! needs no interval to be read, so a lost sample, which leaves an interval of two periods
//! that rounds like one (a period between one and two quanta), or a host's stall caught up
//! on, does not move it. Where several samples share a stamp (a clock faster than its
//! quantum), the stamps that hold two (its beat with the quantum) are folded instead.
//!
//! The peak is found on the first stamps, then on four times as many around it, and so on;
//! the period then is the least-squares line through the stamps, each given the nearest
//! place on the fold's lattice, and that line is checked stretch by stretch: every stretch
//! of a one-rate record bunches at the same phase.

use std::f64::consts::TAU;

/// The stamps a search starts with.
const FIRST: usize = 2048;
/// The most times a search folds at once.
const EACH: usize = 16_384;
/// Stretches a fit is checked in.
const STRETCHES: usize = 16;
/// The most phasor sums a search may take (bins times stamps).
const BUDGET: f64 = 4e8;

/// The Rayleigh power a frequency must pass among `bins` searched: noise alone passes it
/// once in about 160,000 searches.
fn threshold(bins: usize) -> f64 {
    (bins as f64).ln() + 12.0
}

/// About `most` of `n` things picked at random: the `i`-th where splitmix64 of its number is
/// a multiple of `ceil(n / most)` (the same pick every time). A clock's every m-th sample
/// keeps its phase, but folds alike on rates the m-th part of the clock's apart; a random
/// pick folds on one.
#[derive(Clone, Copy)]
struct Pick {
    /// The odd part of the divisor's inverse modulo 2^64, its power of two, and the
    /// largest quotient: `h` is a multiple of the divisor where `h` times the inverse,
    /// rotated right by the power, is no more than it (Granlund and Montgomery's test,
    /// without a division for each thing).
    inverse: u64,
    twos: u32,
    limit: u64,
}

impl Pick {
    fn new(n: usize, most: usize) -> Self {
        let every = (n.div_ceil(most.max(1)) as u64).max(1);
        let twos = every.trailing_zeros();
        let odd = every >> twos;
        // Newton's iteration doubles the bits right of an odd number's inverse: 3 to 96.
        let mut inverse = odd;
        for _ in 0..5 {
            inverse = inverse.wrapping_mul(2u64.wrapping_sub(odd.wrapping_mul(inverse)));
        }
        Pick {
            inverse,
            twos,
            limit: u64::MAX / every,
        }
    }

    /// Whether the `i`-th thing is picked.
    #[inline]
    fn picked(self, i: usize) -> bool {
        let mut z = (i as u64).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        self.divides(z ^ (z >> 31))
    }

    /// Whether `h` is a multiple of the divisor.
    #[inline]
    fn divides(self, h: u64) -> bool {
        h.wrapping_mul(self.inverse).rotate_right(self.twos) <= self.limit
    }
}

/// About `most` of the times `t`, picked at random where they are more.
fn thin(t: &[f64], most: usize) -> Vec<f64> {
    let pick = Pick::new(t.len(), most);
    t.iter()
        .enumerate()
        .filter(|&(i, _)| pick.picked(i))
        .map(|(_, &x)| x)
        .collect()
}

/// The distinct stamps of `stamps` (ns, in order; `distinct` of them), as s from the first,
/// in one pass for each of `sets`: the first `all` of them, then about `most` more picked at
/// random from the rest.
pub(super) fn times<const N: usize>(
    stamps: &[i64],
    distinct: usize,
    sets: [(usize, usize); N],
) -> [Vec<f64>; N] {
    let mut x: [Vec<f64>; N] = std::array::from_fn(|k| {
        let (all, most) = sets[k];
        Vec::with_capacity(all.min(distinct) + most.min(distinct.saturating_sub(all)) + 16)
    });
    let Some(&first) = stamps.first() else {
        return x;
    };
    let picks = sets.map(|(all, most)| Pick::new(distinct.saturating_sub(all), most));
    let mut i = 0;
    let mut last = None;
    for &s in stamps {
        if last == Some(s) {
            continue;
        }
        last = Some(s);
        for ((out, &(all, _)), pick) in x.iter_mut().zip(&sets).zip(picks) {
            if i < all || pick.picked(i - all) {
                // (Stamps in order: the difference fits an i64 but where the span passes
                // 292 years.)
                out.push(match s.checked_sub(first) {
                    Some(d) => d as f64 * 1e-9,
                    None => (i128::from(s) - i128::from(first)) as f64 * 1e-9,
                });
            }
        }
        i += 1;
    }
    x
}

/// The phasor sums of the times `t` (s) at `bins` frequencies from `lo` Hz, `step` Hz apart,
/// into `acc`.
fn sums(t: &[f64], lo: f64, step: f64, bins: usize, acc: &mut Vec<(f64, f64)>) {
    acc.clear();
    acc.resize(bins, (0.0, 0.0));
    for &x in t {
        let (s, c) = (TAU * (lo * x).fract()).sin_cos();
        let (ds, dc) = (TAU * (step * x).fract()).sin_cos();
        let (mut re, mut im) = (c, s);
        for a in acc.iter_mut() {
            a.0 += re;
            a.1 += im;
            (re, im) = (re * dc - im * ds, re * ds + im * dc);
        }
    }
}

/// The bin of the largest power in `acc` (sums over `n` times), its power, and the peak's
/// place between its neighbours (a parabola through the three, in bins).
fn best(acc: &[(f64, f64)], n: usize) -> (f64, f64) {
    let power = |a: &(f64, f64)| (a.0 * a.0 + a.1 * a.1) / n as f64;
    let (j, p) = acc
        .iter()
        .map(power)
        .enumerate()
        .fold((0, -1.0), |b, (j, p)| if p > b.1 { (j, p) } else { b });
    let shift = if j > 0 && j + 1 < acc.len() {
        let (l, r) = (power(&acc[j - 1]), power(&acc[j + 1]));
        let d = l - 2.0 * p + r;
        if d < 0.0 {
            (0.5 * (l - r) / d).clamp(-0.5, 0.5)
        } else {
            0.0
        }
    } else {
        0.0
    };
    (j as f64 + shift, p)
}

/// Where the times `t` (s from the first, in order) fold tightest between `lo` and `hi` Hz:
/// the frequency, Hz, where it stands out over the whole record; `None` where no frequency
/// stands out, or one does only over part of it (a drifting clock, two rates).
pub(super) fn fold(t: &[f64], lo: f64, hi: f64) -> Option<f64> {
    let n = t.len();
    if n < 16 || !(hi > lo && lo > 0.0) {
        return None;
    }
    let mut acc = Vec::new();
    // The first `k` times, about [`EACH`] of them where they are more.
    let first = |k: usize| thin(&t[..k], EACH);
    let mut k = n.min(FIRST);
    // The whole band on the first stamps, more of them where nothing stands out; from 16
    // times round the stamps searched (times evenly spread over a span sum to `n sinc(f
    // span)`: under 16 times round, a few thousand at random pass the threshold as though
    // they beat).
    let mut f = loop {
        let span = t[k - 1] - t[0];
        if span <= 0.0 {
            return None;
        }
        let from = lo.max(16.0 / span);
        if from < hi {
            let step = 0.25 / span;
            let bins = ((hi - from) / step).ceil() as usize + 1;
            let x = first(k);
            if bins as f64 * x.len() as f64 > BUDGET {
                return None;
            }
            sums(&x, from, step, bins, &mut acc);
            let (j, p) = best(&acc, x.len());
            if p > threshold(bins) {
                break from + j * step;
            }
        }
        if k == n {
            return None;
        }
        k = n.min(4 * k);
    };
    // Around the peak, on the stamps within four times the span at a time: the band
    // searched is some 33 bins whatever the record's length.
    while k < n {
        let span = t[k - 1] - t[0];
        let half = 1.0 / span;
        k = (k + t[k..].partition_point(|&x| x - t[0] <= 4.0 * span)).clamp(k + 1, n);
        let step = 0.25 / (t[k - 1] - t[0]);
        // (Not below the band: the times' own spread sums highest near 0 Hz.)
        let from = (f - half).max(lo);
        let bins = ((f + half - from) / step).ceil() as usize + 1;
        let x = first(k);
        sums(&x, from, step, bins, &mut acc);
        let (j, p) = best(&acc, x.len());
        if p <= threshold(bins) {
            return None;
        }
        f = from + j * step;
    }
    Some(f)
}

/// A lattice fitted to stamps: `t = origin + k period`, each stamp at its nearest place.
#[derive(Clone, Copy, Debug)]
pub(super) struct Fit {
    /// The period, s.
    pub period: f64,
    /// The time of place 0, s.
    pub origin: f64,
    /// Its standard error, s.
    pub sigma: f64,
    /// The share of the stamps in stretches that bunch at the lattice's phase.
    pub coherent: f64,
    /// The first stamp and the one past the last of the longest run of stretches that do
    /// not.
    pub off: Option<(usize, usize)>,
    /// The share of the times at the place of the time before, but after a gap: a lattice
    /// too coarse for them (a multiple of a clock's beat with its quantum folds as the
    /// clock does).
    pub crowded: f64,
}

impl Fit {
    /// The share of the times `t` (s, in order) within `window` cycles of their place, the
    /// share of the places from the first time's to the last's with a time so near, and
    /// how many places that is; the places within the stretches `hidden` (s, in order, apart:
    /// where no time can be) left out.
    pub fn cover(&self, t: &[f64], window: f64, hidden: &[(f64, f64)]) -> (f64, f64, f64) {
        let (mut near, mut places, mut last) = (0usize, 0usize, f64::NEG_INFINITY);
        for &x in t {
            let r = (x - self.origin) / self.period;
            if (r - r.round()).abs() <= window {
                near += 1;
                if r.round() > last {
                    places += 1;
                    last = r.round();
                }
            }
        }
        let ends = |x: f64| ((x - self.origin) / self.period).round();
        let all = match (t.first(), t.last()) {
            (Some(&a), Some(&b)) => {
                let unseen: f64 = hidden
                    .iter()
                    .map(|&(from, to)| ((to.min(b) - from.max(a)) / self.period).floor().max(0.0))
                    .sum();
                (ends(b) - ends(a) + 1.0 - unseen).max(1.0)
            }
            _ => 1.0,
        };
        (
            near as f64 / t.len().max(1) as f64,
            places as f64 / all,
            all,
        )
    }
}

impl Fit {
    /// How far from their places (cycles, 0.02 to 0.3) the times of `sets` bunch: past
    /// it, every hundredth of a cycle holds no more of them than those 0.3 cycles off or
    /// more do, give or take three standard errors.
    pub fn reach(&self, sets: &[&[f64]]) -> f64 {
        let mut bins = [0u32; 50];
        for &x in sets.iter().flat_map(|s| s.iter()) {
            let r = (x - self.origin) / self.period;
            let off = ((r - r.round()).abs() * 100.0) as usize;
            bins[off.min(49)] += 1;
        }
        let far = bins[30..50].iter().sum::<u32>() as f64 / 20.0;
        let last = bins[..30]
            .iter()
            .rposition(|&b| b as f64 > far + 3.0 * far.max(1.0).sqrt())
            .map_or(0, |i| i + 1);
        (last as f64 / 100.0).clamp(0.02, 0.3)
    }

    /// How many of the times `t` (s) lie within `window` cycles of their place.
    pub fn near(&self, t: &[f64], window: f64) -> usize {
        t.iter()
            .filter(|&&x| {
                let r = (x - self.origin) / self.period;
                (r - r.round()).abs() <= window
            })
            .count()
    }
}

/// The least-squares line `t = origin + k period` through the times `t` (s) each at its
/// place on the lattice `(origin, period)`, those more than `window` cycles off it left out:
/// the line's origin, period and the period's standard error.
fn line(t: &[f64], (origin, period): (f64, f64), window: f64) -> Option<(f64, f64, f64)> {
    let place = |x: f64| ((x - origin) / period).round();
    let kept = |x: &&f64| ((**x - origin) / period - place(**x)).abs() <= window;
    let (mut m, mut sk, mut st) = (0.0, 0.0, 0.0);
    for &x in t.iter().filter(kept) {
        m += 1.0;
        sk += place(x);
        st += x;
    }
    if m < 3.0 {
        return None;
    }
    let (kb, tb) = (sk / m, st / m);
    let (mut skk, mut skt) = (0.0, 0.0);
    for &x in t.iter().filter(kept) {
        let dk = place(x) - kb;
        skk += dk * dk;
        skt += dk * (x - tb);
    }
    if skk <= 0.0 {
        return None;
    }
    let p = skt / skk;
    let rss: f64 = t
        .iter()
        .filter(kept)
        .map(|&x| (x - tb - p * (place(x) - kb)).powi(2))
        .sum();
    Some((tb - p * kb, p, (rss / (m - 2.0).max(1.0) / skk).sqrt()))
}

/// The least-squares lattice through the times `t` (s, in order) near the frequency `hz`,
/// each time at its nearest place: three rounds, the later ones without the times more than
/// `window` cycles off their place (a host's late stamps). `None` where its stretches are
/// too few to tell whether they bunch.
pub(super) fn fit(t: &[f64], hz: f64, window: f64) -> Option<Fit> {
    let n = t.len();
    if n < 16 {
        return None;
    }
    let phase = |x: f64, hz: f64| (TAU * (hz * x).fract()).sin_cos();
    let (s, c) = t
        .iter()
        .map(|&x| phase(x, hz))
        .fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let mut period = 1.0 / hz;
    let mut origin = s.atan2(c) / TAU * period;
    let mut sigma = f64::INFINITY;
    for round in 0..3 {
        let line = line(t, (origin, period), if round == 0 { 0.5 } else { window })?;
        (origin, period, sigma) = line;
        if period.is_nan() || period <= 0.0 {
            return None;
        }
    }
    // Each half's own line, its places kept: a clock whose phase wanders (stamps summed
    // from jittered intervals) has halves that differ by more than their lines' errors.
    let (_, a, _) = line(&t[..n / 2], (origin, period), window)?;
    let (_, b, _) = line(&t[n / 2..], (origin, period), window)?;
    let sigma = sigma.max((a - b).abs() / 4.0);
    // Each stretch's mean phasor about the lattice, against the record's: as many
    // stretches (up to 16, at least 4) as the bunching stands out in, each stretch's mean
    // straying by its standard error (the record's spread about its mean, over twice the
    // stretch's length) by chance, half the record's bunching three times that.
    let phasor = |x: f64| {
        let r = (x - origin) / period;
        (TAU * (r - r.round())).sin_cos()
    };
    let (s, c) = t
        .iter()
        .map(|&x| phasor(x))
        .fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
    let amp = (c * c + s * s).sqrt() / n as f64;
    let (dc, ds) = (c / (amp * n as f64), s / (amp * n as f64));
    let stretches = (2..=STRETCHES.ilog2())
        .rev()
        .map(|b| 1usize << b)
        .find(|&m| {
            let len = (n / m) as f64;
            0.5 * amp >= 3.0 * ((1.0 - amp * amp).max(1.0 / len) / (2.0 * len)).sqrt()
        })?;
    let len = n / stretches;
    let fits: Vec<bool> = (0..stretches)
        .map(|j| {
            let end = if j + 1 == stretches { n } else { (j + 1) * len };
            let (s, c) = t[j * len..end]
                .iter()
                .map(|&x| phasor(x))
                .fold((0.0, 0.0), |a, p| (a.0 + p.0, a.1 + p.1));
            (c * dc + s * ds) / (end - j * len) as f64 >= 0.5 * amp
        })
        .collect();
    let coherent = fits.iter().filter(|&&f| f).count() as f64 / stretches as f64;
    let mut off: Option<(usize, usize)> = None;
    let mut run = None;
    for (j, &f) in fits.iter().chain([true].iter()).enumerate() {
        match (f, run) {
            (false, None) => run = Some(j),
            (true, Some(from)) => {
                let end = if j == stretches { n } else { j * len };
                if off.is_none_or(|(a, b)| end - from * len > b - a) {
                    off = Some((from * len, end));
                }
                run = None;
            }
            _ => {}
        }
    }
    let place = |x: f64| ((x - origin) / period).round();
    // (A host's late stamps, caught up on after a stall's gap, come closer than the period
    // and may share the place of the sample after them.)
    let crowded = t
        .windows(3)
        .filter(|w| {
            let regular = |iv: f64| (0.75 * period..1.5 * period).contains(&iv);
            regular(w[1] - w[0]) && regular(w[2] - w[1]) && place(w[1]) == place(w[2])
        })
        .count() as f64
        / n as f64;
    Some(Fit {
        crowded,
        period,
        origin,
        sigma,
        coherent,
        off,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sample times of a clock at `hz` from `t0` s, each floored to `q` s, with the samples
    /// `lost` says dropped.
    fn floored(hz: f64, n: usize, q: f64, mut lost: impl FnMut(usize) -> bool) -> Vec<f64> {
        let t0 = 0.123_456_7;
        let first = (t0 / q).floor() * q;
        (0..n)
            .filter(|&k| !lost(k))
            .map(|k| ((t0 + k as f64 / hz) / q).floor() * q - first)
            .collect()
    }

    #[test]
    fn a_clock_between_one_and_two_quanta_folds_on_its_rate_through_losses() {
        for hz in [550.0, 800.0, 950.0] {
            let mut next = crate::xorshift(7);
            let t = floored(hz, 100_000, 1e-3, |_| next().is_multiple_of(100));
            let f = fold(&t, 0.975 * hz, 1.025 * hz).expect("a peak");
            assert!((f / hz - 1.0).abs() < 2e-6, "{hz}: {f}");
            let fit = fit(&t, f, 0.5).unwrap_or_else(|| panic!("{hz}: {f}: no fit"));
            assert!((fit.period * hz - 1.0).abs() < 1e-7, "{hz}: {fit:?}");
            assert_eq!(fit.coherent, 1.0, "{hz}");
        }
    }

    #[test]
    fn the_pick_divides_as_the_remainder_does() {
        let mut next = crate::xorshift(0x0d1f_1de5_0000_0001);
        let mut every: Vec<u64> = (1..=2048).collect();
        every.extend([1 << 20, 3 << 40, u64::MAX / 7, u64::MAX]);
        for d in every {
            let pick = Pick::new(d as usize, 1);
            for k in 0..200u64 {
                let h = match k {
                    0..50 => k.wrapping_mul(d),
                    50..60 => k.wrapping_mul(d).wrapping_sub(1),
                    _ => next(),
                };
                assert_eq!(pick.divides(h), h.is_multiple_of(d), "{h} {d}");
            }
        }
    }

    #[test]
    fn noise_folds_on_no_rate() {
        let mut next = crate::xorshift(11);
        let mut x = 0.0;
        let t: Vec<f64> = (0..50_000)
            .map(|_| {
                x += 1e-3 * (next() % 2000) as f64 / 1000.0;
                x
            })
            .collect();
        assert_eq!(fold(&t, 950.0, 1050.0), None);
    }

    #[test]
    fn times_at_random_fold_on_no_slow_beat() {
        // Places a 1 kHz clock's samples lost at random leave, 2 % of a million (pass 54 F6:
        // the first 2048, a tenth of the span, summed near 16 times round the whole span,
        // then ever nearer 0 Hz, read a beat of 0.0048 Hz and refused the record).
        for seed in 1..4 {
            let mut next = crate::xorshift(seed);
            let t: Vec<f64> = (0..1_000_000)
                .filter(|_| next().is_multiple_of(50))
                .map(|k| k as f64 * 1e-3)
                .collect();
            let span = t[t.len() - 1] - t[0];
            assert_eq!(fold(&t, 16.0 / span, 450.0), None, "{seed}");
        }
    }

    #[test]
    fn two_rates_fold_as_one_only_in_part() {
        let mut t = floored(800.0, 70_000, 1e-3, |_| false);
        let end = *t.last().unwrap();
        t.extend((1..30_000).map(|k| ((end + k as f64 / 760.0) / 1e-3).floor() * 1e-3));
        if let Some(f) = fold(&t, 780.0, 820.0) {
            let fit = fit(&t, f, 0.5).expect("a fit");
            assert!(fit.coherent < 0.9, "{f}: {fit:?}");
        }
    }
}
