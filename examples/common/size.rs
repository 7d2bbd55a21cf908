//! The driver of the `size_*` firmware, which measure the flash taken by one estimator: the
//! same samples, the same logging and the same exit in each, so that the difference between
//! an estimator's firmware and `size_base` is the estimator's own code (`tools/bench-report.sh`).

use core::hint::black_box;

use super::common;

/// Feeds 10,000 samples of an AR(1) record with an offset to `update` of `state`, then logs
/// `finish(state)` (a coefficient of the model, or NaN without one) and exits.
pub fn run<S>(mut state: S, update: impl Fn(&mut S, f32), finish: impl FnOnce(S) -> f32) -> ! {
    let (mut x, mut seed) = (0.0f32, 12345u32);
    for _ in 0..10_000 {
        seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        x = 0.9 * x + ((seed >> 8) as f32 / 16_777_216.0 - 0.5);
        update(&mut state, black_box(0.4 + x));
    }
    let a1 = finish(state);
    defmt::info!("a1 = {=f32}", a1);
    common::exit(a1.is_finite())
}
