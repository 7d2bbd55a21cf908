//! Proof that the per-sample paths cannot panic: this firmware calls every estimator's
//! `update` (and the model hand-over) on inputs the compiler cannot see, and its panic handler
//! calls a function that does not exist. If any panic path survived optimisation, the link
//! would fail with an undefined `imu_ar_panic_path_is_reachable`.
//!
//! ```text
//! cargo qemu nopanic
//! ```
//!
//! It runs as well: the estimators get a short synthetic record and the firmware exits 0 when
//! every output is finite. Nothing is logged, since the logger has panic paths of its own.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::hint::black_box;

    use cortex_m_rt::{ExceptionFrame, entry, exception};
    use cortex_m_semihosting::debug;
    use imu_ar::allan::AllanStream;
    use imu_ar::fixed_point::{FixedConfig, FixedLattice};
    use imu_ar::recursive::{Config, Lattice, OrderRule, OrderSelector, Rls, RlsInit, Sftf};

    unsafe extern "C" {
        /// Deliberately undefined: referencing it from a live panic path breaks the link.
        fn imu_ar_panic_path_is_reachable() -> !;
    }

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        unsafe { imu_ar_panic_path_is_reachable() }
    }

    #[exception]
    unsafe fn HardFault(_: &ExceptionFrame) -> ! {
        debug_exit(false)
    }

    fn exercise<const P: usize>(config: &Config<f32>, x: &[f32]) -> bool {
        let mut lattice = Lattice::<f32, P>::new(config);
        let mut rls = Rls::<f32, P>::new(config, RlsInit::ShiftConsistent);
        let mut sftf = Sftf::<f32, P>::new(config);
        let mut selector = OrderSelector::<f32, P>::new(OrderRule::Pls, 100, 3);
        let mut allan = AllanStream::<12>::new();
        let mut fixed = match FixedConfig::new(config, black_box(2.0)) {
            Ok(f) => (f, FixedLattice::<P>::new(&f)),
            Err(_) => return false,
        };
        let mut finite = true;
        for &v in x {
            let v = black_box(v);
            if let Some(e) = lattice.update(config, v) {
                finite &= e.is_finite();
                selector.update(config, &lattice);
            }
            if let Some(e) = rls.update(config, v) {
                finite &= e.is_finite();
            }
            if let Some(e) = sftf.update(config, v) {
                finite &= e.is_finite();
            }
            allan.push(v);
            black_box(fixed.1.update(&fixed.0, v));
            black_box(fixed.1.update_counts(&fixed.0, black_box(v as i16)));
        }
        finite &= fixed.1.model(&fixed.0).is_some();
        let order = black_box(selector.order());
        finite &= order <= P;
        match (lattice.model(config), rls.model(config), sftf.model(config)) {
            (Some(a), Some(b), Some(c)) => {
                finite &= a.a()[0].is_finite() && b.a()[0].is_finite() && c.a()[0].is_finite()
            }
            _ => finite = false,
        }
        finite && black_box(lattice.coefficients(P)).is_some()
    }

    #[entry]
    fn main() -> ! {
        let config = match Config::new(black_box(0.99f32), black_box(0.1), black_box(0.01)) {
            Ok(c) => c,
            Err(_) => debug_exit(false),
        };
        let config = match config.with_saturation(black_box(1e3)) {
            Ok(c) => c,
            Err(_) => debug_exit(false),
        };
        // A deterministic AR(1)-like record with a NaN, an infinity and a saturated sample.
        let mut x = [0.0f32; 512];
        let mut state = 0.0f32;
        let mut seed = black_box(12345u32);
        for v in x.iter_mut() {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let w = (seed >> 8) as f32 / 16_777_216.0 - 0.5;
            state = 0.9 * state + w;
            *v = state;
        }
        x[100] = f32::NAN;
        x[200] = f32::INFINITY;
        x[300] = 5e3;
        let ok =
            exercise::<1>(&config, &x) & exercise::<4>(&config, &x) & exercise::<8>(&config, &x);
        debug_exit(ok)
    }

    fn debug_exit(success: bool) -> ! {
        debug::exit(if success {
            debug::EXIT_SUCCESS
        } else {
            debug::EXIT_FAILURE
        });
        loop {
            cortex_m::asm::bkpt();
        }
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("nopanic is firmware for the Cortex-M4F: run it with `cargo qemu nopanic`");
}
