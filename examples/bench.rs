//! Cost per sample on the emulated Cortex-M4F, in executed instructions.
//!
//! ```text
//! cargo qemu bench
//! ```
//!
//! QEMU runs with `-icount shift=0` (one instruction per virtual nanosecond), so SysTick on the
//! MPS2 processor clock (25 MHz) decrements once per 40 executed instructions.
//! The firmware checks that figure against a loop of known length (two instructions per
//! iteration), times batches of 1000 `update` calls on a prepared record (inputs through
//! `black_box`), subtracts the cost of the same loop without the call, and prints one line per
//! row: `<estimator> <scalar> p=<P> insns/sample=<N>`. These are instruction counts, not cycles.
//!
//! Rows: `lattice` (f32 and fixed), `rls` and `sftf` (f32) per sample at p = 1, 2, 4, 8, 16, 32, and at
//! p = 3, 5, 6, 7 for the f32 lattice and RLS (where one overtakes the other); `extract` per
//! request of the exact coefficients of order p; `frame6` per six-axis frame of order-4
//! lattices; `lattice-prior` and `lattice-gated` (f32, p = 4 and 8) per sample of the lattice
//! from a prior (with its ladder) and behind the innovation gate (k = 5); `thermal` per sample of one axis through the temperature compensation stage
//! (`imu_ar::thermal::ThermalBias`, p its number of coefficients: degree p - 1) on a
//! 25 to 45 deg C ramp. Then the state of one channel, `<estimator> <scalar> p=<P> bytes=<N>`
//! (`size_of` on the target). Last, one fit of the composite noise model from a 20-octave
//! `AllanStream`, without and with an AR(8) part: `noise fit ... insns/fit=<N> stack=<B>`, and
//! the bytes of the stream, the model and the octaves.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/mod.rs"]
mod common;

#[cfg(target_os = "none")]
mod firmware {
    use core::hint::black_box;

    use cortex_m::peripheral::{SYST, syst::SystClkSource};
    use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, FixedLattice};
    use imu_ar::recursive::{Gate, Lattice, Rls, Sftf};
    use imu_ar::thermal::{ThermalBias, ThermalConfig};
    use imu_ar::{
        ArModel,
        allan::AllanStream,
        noise::{FitConfig, NoiseModel, Octaves},
    };

    use super::common;

    const BATCH: usize = 1000;
    const RELOAD: u32 = 0x00FF_FFFF;

    /// SysTick ticks spent in `f` (less than 2^24 ticks, 671 million instructions).
    fn ticks(syst: &mut SYST, f: impl FnOnce()) -> u32 {
        syst.clear_current();
        let start = SYST::get_current();
        f();
        let end = SYST::get_current();
        start.wrapping_sub(end) & RELOAD
    }

    /// SysTick wraps counted by its exception while [`long_ticks`] has it enabled.
    static WRAPS: core::sync::atomic::AtomicU32 = core::sync::atomic::AtomicU32::new(0);

    #[cortex_m_rt::exception]
    fn SysTick() {
        use core::sync::atomic::Ordering::Relaxed;
        // The one writer besides `long_ticks`'s reset (single core, no nesting with itself).
        WRAPS.store(WRAPS.load(Relaxed).wrapping_add(1), Relaxed);
    }

    /// SysTick ticks spent in `f`, however many: each wrap of the 24-bit counter is counted by
    /// its exception (a few instructions per 671 million).
    fn long_ticks(syst: &mut SYST, f: impl FnOnce()) -> u64 {
        use core::sync::atomic::Ordering::Relaxed;
        syst.clear_current();
        WRAPS.store(0, Relaxed);
        syst.enable_interrupt();
        let start = SYST::get_current();
        f();
        let end = SYST::get_current();
        syst.disable_interrupt();
        let wraps = u64::from(WRAPS.load(Relaxed));
        // From `start` down to 0 (a cleared counter, 0, reloads first: a whole period), then
        // `wraps - 1` whole periods, then from RELOAD down to `end`.
        let period = u64::from(RELOAD) + 1;
        let start = match start {
            0 => period,
            s => u64::from(s),
        };
        (wraps * period + start).saturating_sub(u64::from(end))
    }

    /// Instructions per SysTick tick, from `subs; bne` loops of known length.
    fn calibrate(syst: &mut SYST) -> u32 {
        let spin = |n: u32| {
            // SAFETY: a register-only countdown loop, two instructions per iteration.
            unsafe {
                core::arch::asm!("1:", "subs {0}, {0}, #1", "bne 1b", inout(reg) n => _,
                    options(nomem, nostack));
            }
        };
        let long = ticks(syst, || spin(black_box(2_000_000)));
        let short = ticks(syst, || spin(black_box(1_000_000)));
        // 2,000,000 instructions more in the long run; the fixed overhead cancels.
        (2_000_000 + (long - short) / 2) / (long - short)
    }

    pub struct Bench {
        syst: SYST,
        per_tick: u32,
        x: [f32; BATCH],
        counts: [i16; BATCH],
        /// The die temperature of each sample of `x`, deg C: a ramp from 25 to 45.
        celsius: [f32; BATCH],
    }

    impl Bench {
        fn insns_per_sample(&mut self, body: impl Fn(usize)) -> u32 {
            let empty = ticks(&mut self.syst, || {
                for i in 0..BATCH {
                    black_box(i);
                }
            });
            let full = ticks(&mut self.syst, || {
                for i in 0..BATCH {
                    body(black_box(i));
                }
            });
            (full.saturating_sub(empty) * self.per_tick + BATCH as u32 / 2) / BATCH as u32
        }

        /// The settings of the f32 rows.
        fn f32_settings() -> (Config<f32>, Channel<f32>) {
            match (Config::new(0.999f32, 0.01), Channel::new(0.1)) {
                (Ok(config), Ok(channel)) => (config, channel),
                _ => common::exit(false),
            }
        }

        /// One row of an f32 estimator: instructions per `update`, then the state's size; a
        /// restart on the benchmark record would make the count meaningless, and fails.
        fn f32_row<E: Estimator<f32, P>, const P: usize>(
            &mut self,
            name: &str,
            mut state: E,
            config: &E::Config,
        ) {
            let x = self.x;
            let cell = core::cell::RefCell::new(&mut state);
            let n = self.insns_per_sample(|i| {
                black_box(cell.borrow_mut().update(config, black_box(x[i])));
            });
            defmt::info!("{=str} f32 p={=usize} insns/sample={=u32}", name, P, n);
            let bytes = core::mem::size_of::<E>();
            defmt::info!("{=str} f32 p={=usize} bytes={=usize}", name, P, bytes);
            let restarts = cell.borrow().health().restarts;
            if restarts > 0 {
                defmt::error!("{=str} f32 p={=usize}: {=u64} restarts", name, P, restarts);
                common::exit(false);
            }
        }

        fn lattice_f32<const P: usize>(&mut self) {
            let (config, channel) = Self::f32_settings();
            self.f32_row(
                "lattice",
                Lattice::<f32, P>::new(&config, &channel),
                &config,
            );
        }

        /// The f32 lattice from a prior (its joint-process ladder), and behind the gate.
        fn lattice_prior_gated_f32<const P: usize>(&mut self) {
            let (config, channel) = Self::f32_settings();
            let Ok(prior) = Lattice::<f32, P>::with_prior(&config, &channel, &[0.1; P]) else {
                common::exit(false)
            };
            self.f32_row("lattice-prior", prior, &config);
            let Ok(gate) = Gate::new(5.0, 16) else {
                common::exit(false)
            };
            let gated = config.with_gate(gate);
            self.f32_row(
                "lattice-gated",
                Lattice::<f32, P>::new(&gated, &channel),
                &gated,
            );
        }

        fn rls_f32<const P: usize>(&mut self) {
            let (config, channel) = Self::f32_settings();
            self.f32_row("rls", Rls::<f32, P>::new(&config, &channel), &config);
        }

        fn sftf_f32<const P: usize>(&mut self) {
            let (config, channel) = Self::f32_settings();
            self.f32_row("sftf", Sftf::<f32, P>::new(&config, &channel), &config);
        }

        fn lattice_fixed<const P: usize>(&mut self) {
            // delta 0.01: at 1e-3 the reflection coefficients of this small, quantised record
            // leave the I3F29 range in the start-up of p = 16 and 32, and every such sample
            // restarts the lattice; the row would time restarts, not the recursion.
            let (config, _) = Self::f32_settings();
            let (Ok(fixed), Ok(channel)) = (
                FixedConfig::new(&config),
                Channel::new(0.01).and_then(|c| FixedChannel::for_counts(&c, 0.05)),
            ) else {
                common::exit(false)
            };
            let mut state = FixedLattice::<P>::new(&fixed, &channel);
            let counts = self.counts;
            let cell = core::cell::RefCell::new(&mut state);
            let n = self.insns_per_sample(|i| {
                black_box(
                    cell.borrow_mut()
                        .update_counts(&fixed, black_box(counts[i])),
                );
            });
            defmt::info!("lattice fixed p={=usize} insns/sample={=u32}", P, n);
            let restarts = cell.borrow().health().restarts;
            if restarts != 0 {
                defmt::error!(
                    "lattice fixed p={=usize} restarted {=u64} times",
                    P,
                    restarts
                );
                common::exit(false);
            }
            let bytes = core::mem::size_of::<FixedLattice<P>>();
            defmt::info!("lattice fixed p={=usize} bytes={=usize}", P, bytes);
        }

        /// The exact transversal coefficients on request, after 1000 samples.
        fn extract_f32<const P: usize>(&mut self) {
            let (config, channel) = Self::f32_settings();
            let mut state = Lattice::<f32, P>::new(&config, &channel);
            for &v in &self.x {
                state.update(&config, v);
            }
            let n = self.insns_per_sample(|_| {
                black_box(black_box(&state).coefficients(P));
            });
            defmt::info!("extract f32 p={=usize} insns/sample={=u32}", P, n);
        }

        /// The thermal stage with `N` coefficients, per sample of one axis: instructions, then
        /// the state's size (the shared `ThermalConfig` not included).
        fn thermal_f32<const N: usize>(&mut self) {
            let Ok(config) = ThermalConfig::<f32, N>::new(0.9999, 20.0, 50.0) else {
                common::exit(false)
            };
            let mut state = ThermalBias::new(&config);
            let (x, celsius) = (self.x, self.celsius);
            let cell = core::cell::RefCell::new(&mut state);
            let n = self.insns_per_sample(|i| {
                black_box(cell.borrow_mut().update(
                    &config,
                    black_box(x[i]),
                    black_box(celsius[i]),
                ));
            });
            defmt::info!("thermal f32 p={=usize} insns/sample={=u32}", N, n);
            let bytes = core::mem::size_of::<ThermalBias<f32, N>>();
            defmt::info!("thermal f32 p={=usize} bytes={=usize}", N, bytes);
            let health = cell.borrow().health();
            if health.samples != BATCH as u64 || health.restarts > 0 {
                defmt::error!("thermal f32 p={=usize}: not every sample learned", N);
                common::exit(false);
            }
        }

        /// One six-axis frame: six order-4 lattices, one sample each.
        fn frame6_f32(&mut self) {
            let (config, channel) = Self::f32_settings();
            let mut axes = [Lattice::<f32, 4>::new(&config, &channel); 6];
            let x = self.x;
            let cell = core::cell::RefCell::new(&mut axes);
            let n = self.insns_per_sample(|i| {
                for (k, lattice) in cell.borrow_mut().iter_mut().enumerate() {
                    black_box(lattice.update(&config, black_box(x[(i + k) % BATCH])));
                }
            });
            defmt::info!("frame6 f32 p=4 insns/sample={=u32}", n);
        }

        /// One fit of the composite noise model from a 20-octave Allan stream (2^21 samples of
        /// white noise, a Gauss-Markov drift and a random walk), without and with an AR(8)
        /// part, as a curve fit and identified (with the intervals of its parameters):
        /// instructions, and the stack it used (painted before, scanned after).
        fn noise_fit(&mut self) {
            let mut stream = AllanStream::<20>::new();
            let (mut seed, mut drift, mut walk) = (777u32, 0.0f32, 0.0f32);
            let mut uniform = || {
                seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                (seed >> 8) as f32 / 16_777_216.0 - 0.5
            };
            for _ in 0..1u32 << 21 {
                drift = 0.999 * drift + 0.01 * uniform();
                walk += 1e-4 * uniform();
                stream.push(uniform() + drift + walk);
            }
            let dt = 0.01;
            let (Ok(octaves), Ok(ar)) = (
                Octaves::<20>::from_stream(&stream, dt),
                ArModel::new([0.5, -0.2, 0.1, 0.0, 0.0, 0.0, 0.0, 0.05], 0.08, 0.0, dt),
            ) else {
                common::exit(false)
            };
            let config = FitConfig::new(3);
            let identified = config.with_identification(true);
            let runs = [
                ("none", None, config, false),
                ("ar8", Some(&ar), config, false),
                ("none_identified", None, identified, true),
                ("ar8_identified", Some(&ar), identified, true),
            ];
            for (name, ar, config, intervals) in runs {
                let mut fitted = None;
                // The fit's frames start below this one; 1 KiB leaves room for the painter's.
                let top = stack_pointer() - 1024;
                paint_stack(top);
                // Identified, the fit and the 95 % intervals of its parameters.
                let n = long_ticks(&mut self.syst, || {
                    let fit = NoiseModel::<8, 3>::fit(black_box(&octaves), ar, &config);
                    if intervals {
                        let u = fit.as_ref().ok().map(|m| m.uncertainty(&octaves));
                        black_box(u.map(|u| u.map(|u| u.random_walk.high)));
                    }
                    fitted = Some(fit);
                }) * u64::from(self.per_tick);
                // The fit's stack: what it used below `top`, and the 1 KiB above it.
                let stack = stack_used(top) + 1024;
                let Some(Ok(model)) = fitted else {
                    defmt::error!("noise fit ({=str}) failed", name);
                    common::exit(false)
                };
                defmt::info!(
                    "noise fit octaves=20 gm=3 ar={=str} insns/fit={=u64} stack={=usize} terms={=usize}",
                    name,
                    n,
                    stack,
                    model.gauss_markov().len()
                );
            }
            defmt::info!(
                "noise state allan_stream_l20 bytes={=usize} noise_model_p8_g3 bytes={=usize} octaves_l20 bytes={=usize}",
                core::mem::size_of::<AllanStream<20>>(),
                core::mem::size_of::<NoiseModel<8, 3>>(),
                core::mem::size_of::<Octaves<20>>()
            );
        }
    }

    /// Bytes below the stack pointer that [`paint_stack`] fills and [`stack_used`] scans.
    const PAINTED: usize = 256 * 1024;
    const PAINT: u32 = 0x5AA5_C33C;

    fn stack_pointer() -> usize {
        cortex_m::register::msp::read() as usize
    }

    /// Fills the `PAINTED` bytes below `top` (free stack, below the live frames) with a
    /// pattern.
    #[inline(never)]
    fn paint_stack(top: usize) {
        for addr in (top - PAINTED..top).step_by(4) {
            // SAFETY: free stack below the live frames, 4 MiB of RAM on the board, word aligned.
            unsafe { core::ptr::write_volatile(addr as *mut u32, PAINT) };
        }
    }

    /// The bytes below `top` used since [`paint_stack`]: down to the lowest overwritten word.
    #[inline(never)]
    fn stack_used(top: usize) -> usize {
        let lowest = (top - PAINTED..top)
            .step_by(4)
            // SAFETY: the region written by `paint_stack`.
            .find(|&addr| unsafe { core::ptr::read_volatile(addr as *const u32) } != PAINT)
            .unwrap_or(top);
        top - lowest
    }

    pub fn run() -> ! {
        let Some(mut cp) = cortex_m::Peripherals::take() else {
            common::exit(false)
        };
        cp.SYST.set_clock_source(SystClkSource::Core);
        cp.SYST.set_reload(RELOAD);
        cp.SYST.enable_counter();
        let per_tick = calibrate(&mut cp.SYST);
        defmt::info!(
            "calibration: {=u32} instructions per SysTick tick",
            per_tick
        );

        // An AR(1) record with a gyro-like offset: 0.9 memory, uniform innovations.
        let mut x = [0.0f32; BATCH];
        let mut counts = [0i16; BATCH];
        let (mut state, mut seed) = (0.0f32, 12345u32);
        for (v, c) in x.iter_mut().zip(counts.iter_mut()) {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            state = 0.9 * state + ((seed >> 8) as f32 / 16_777_216.0 - 0.5);
            *v = 0.4 + state;
            *c = (*v * 20.0) as i16;
        }
        let celsius = core::array::from_fn(|i| 25.0 + 20.0 * i as f32 / BATCH as f32);
        let mut bench = Bench {
            syst: cp.SYST,
            per_tick,
            x,
            counts,
            celsius,
        };
        macro_rules! orders {
            ($f:ident) => {
                bench.$f::<1>();
                bench.$f::<2>();
                bench.$f::<4>();
                bench.$f::<8>();
                bench.$f::<16>();
                bench.$f::<32>();
            };
        }
        orders!(lattice_f32);
        orders!(lattice_fixed);
        orders!(rls_f32);
        orders!(sftf_f32);
        macro_rules! between {
            ($f:ident) => {
                bench.$f::<3>();
                bench.$f::<5>();
                bench.$f::<6>();
                bench.$f::<7>();
            };
        }
        between!(lattice_f32);
        between!(rls_f32);
        orders!(extract_f32);
        bench.lattice_prior_gated_f32::<4>();
        bench.lattice_prior_gated_f32::<8>();
        bench.frame6_f32();
        bench.thermal_f32::<1>();
        bench.thermal_f32::<2>();
        bench.thermal_f32::<4>();
        bench.noise_fit();
        common::exit(per_tick > 0)
    }
}

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    firmware::run()
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("bench is firmware for the Cortex-M4F: run it with `cargo qemu bench`");
}
