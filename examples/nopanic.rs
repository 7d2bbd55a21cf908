//! Proof that the per-sample paths cannot panic: this firmware calls every estimator's
//! `update` (and the model hand-over) on inputs the compiler cannot see (plain, from a prior
//! behind the innovation gate, and from a settled start), and its panic handler
//! calls a function that does not exist. If any panic path survived optimisation, the link
//! would fail with an undefined `imu_ar_panic_path_is_reachable`.
//!
//! ```text
//! cargo qemu nopanic
//! ```
//!
//! The composite noise model's fit, check, IEEE 952 readings and filter form are called too
//! (from the firmware's `AllanStream`, with the lattice's model as the AR part), both models
//! go through the persistence layouts (encoding, decoding bytes the compiler cannot see) and
//! through a flash store on a NOR flash in RAM, and the thermal compensation stage's
//! per-sample path (`ThermalBias::update`, and its bias, compensation and leverage at a
//! temperature) runs in `f32` and `f64`.
//!
//! It runs as well: the estimators get a short synthetic record and the firmware exits 0 when
//! every output is finite. Nothing is logged, since the logger has panic paths of its own.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
mod firmware {
    use core::hint::black_box;

    use cortex_m_rt::{ExceptionFrame, entry, exception};
    use cortex_m_semihosting::debug;
    use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
    use imu_ar::Scalar;
    use imu_ar::allan::AllanStream;
    use imu_ar::model::{ArModel, ModelError};
    use imu_ar::noise::{FitConfig, NoiseError, NoiseModel, Octaves};
    use imu_ar::persist::{EncodeError, FlashStore, Record};
    use imu_ar::recursive::{Channel, Config, Estimator, FixedChannel, FixedConfig, Gate};
    use imu_ar::recursive::{FixedLattice, Lattice, OrderRule, OrderSelector, Rls, Settled, Sftf};
    use imu_ar::thermal::{ThermalBias, ThermalConfig};

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

    /// Every sample of `x` through `update`, then the model: whether every error and the
    /// model are finite. `on_sample` sees the estimator after each accepted sample.
    fn run<E: Estimator<f32, P>, const P: usize>(
        e: &mut E,
        config: &E::Config,
        x: &[f32],
        mut on_sample: impl FnMut(&E),
    ) -> bool {
        let mut finite = true;
        for &v in x {
            if let Some(err) = e.update(config, black_box(v)) {
                finite &= err.is_finite();
                on_sample(e);
            }
        }
        finite &= e.noise_variance().is_some_and(f32::is_finite) && e.mean().is_finite();
        finite && e.model(config).is_some_and(|m| m.a()[0].is_finite())
    }

    fn exercise<const P: usize>(config: &Config<f32>, channel: &Channel<f32>, x: &[f32]) -> bool {
        let mut selector = OrderSelector::<f32, P>::new(OrderRule::Pls, 100, 3);
        let mut lattice = Lattice::<f32, P>::new(config, channel);
        let mut finite = run(&mut lattice, config, x, |l| {
            selector.update(config, l);
        });
        finite &= run(&mut Rls::<f32, P>::new(config, channel), config, x, |_| {});
        finite &= run(&mut Sftf::<f32, P>::new(config, channel), config, x, |_| {});
        let (Ok(fixed_config), Ok(fixed_channel)) = (
            FixedConfig::new(config),
            FixedChannel::new(channel, black_box(2.0)),
        ) else {
            return false;
        };
        let mut fixed = FixedLattice::<P>::new(&fixed_config, &fixed_channel);
        finite &= run(&mut fixed, &fixed_config, x, |_| {});
        for &v in x {
            black_box(fixed.update_counts(&fixed_config, black_box(v as i16)));
        }
        // Every estimator from a prior, behind the innovation gate.
        let Ok(gate) = Gate::new(black_box(5.0), black_box(16)) else {
            return false;
        };
        let gated = config.with_gate(gate);
        let a0 = [black_box(0.1f32); P];
        let Ok(mut l) = Lattice::<f32, P>::with_prior(&gated, channel, &a0) else {
            return false;
        };
        finite &= run(&mut l, &gated, x, |_| {});
        let (Ok(mut rls), Ok(mut sftf)) = (
            Rls::<f32, P>::with_prior(&gated, channel, &a0),
            Sftf::<f32, P>::with_prior(&gated, channel, &a0),
        ) else {
            return false;
        };
        finite &= run(&mut rls, &gated, x, |_| {});
        finite &= run(&mut sftf, &gated, x, |_| {});
        // A settled start on the first 32 samples (their batch fit as the prior).
        let mut settled: Settled<_, f32, 32> =
            Settled::new(Lattice::<f32, P>::new(config, channel));
        finite &= run(&mut settled, config, x, |_| {});
        let mut settled: Settled<_, f32, 32> = Settled::new(Rls::<f32, P>::new(config, channel));
        finite &= run(&mut settled, config, x, |_| {});
        let mut settled: Settled<_, f32, 32> = Settled::new(Sftf::<f32, P>::new(config, channel));
        finite &= run(&mut settled, config, x, |_| {});
        let (Ok(fixed_gated), Ok(fixed_channel)) = (
            FixedConfig::new(&gated),
            FixedChannel::new(channel, black_box(2.0)),
        ) else {
            return false;
        };
        let Ok(mut fixed) = FixedLattice::<P>::with_prior(&fixed_gated, &fixed_channel, &a0) else {
            return false;
        };
        finite &= run(&mut fixed, &fixed_gated, x, |_| {});
        for &v in x {
            black_box(fixed.update_counts(&fixed_gated, black_box(v as i16)));
        }
        let mut allan = AllanStream::<12>::new();
        for &v in x {
            allan.push(black_box(v));
        }
        let order = black_box(selector.order());
        finite &= order <= P;
        finite &= noise::<P>(&allan, lattice.model(config).as_ref());
        finite &= lattice.model(config).is_some_and(|m| persist(&m));
        finite && black_box(lattice.coefficients(P)).is_some()
    }

    /// Two erase units of NOR flash in RAM; every access checked, none can panic.
    struct Ram([u8; 2048]);

    impl ErrorType for Ram {
        type Error = NorFlashErrorKind;
    }

    impl ReadNorFlash for Ram {
        const READ_SIZE: usize = 1;

        fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
            let at = offset as usize;
            let range = at..at.saturating_add(bytes.len());
            let src = self.0.get(range).ok_or(NorFlashErrorKind::OutOfBounds)?;
            bytes.iter_mut().zip(src).for_each(|(d, s)| *d = *s);
            Ok(())
        }

        fn capacity(&self) -> usize {
            self.0.len()
        }
    }

    impl NorFlash for Ram {
        const WRITE_SIZE: usize = 4;
        const ERASE_SIZE: usize = 1024;

        fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
            let cells = self.0.get_mut(from as usize..to as usize);
            cells.ok_or(NorFlashErrorKind::OutOfBounds)?.fill(0xFF);
            Ok(())
        }

        fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
            let at = offset as usize;
            let range = at..at.saturating_add(bytes.len());
            let dst = self
                .0
                .get_mut(range)
                .ok_or(NorFlashErrorKind::OutOfBounds)?;
            dst.iter_mut().zip(bytes).for_each(|(d, s)| *d &= *s);
            Ok(())
        }
    }

    /// `model` encoded and decoded (from bytes the compiler cannot see), then saved to and
    /// loaded from a flash store: whether both give it back. A model that is not stationary
    /// is refused by the encoder, with a typed error.
    fn persist<M: Record + PartialEq>(model: &M) -> bool {
        let mut buf = [0u8; 512];
        match model.encode(&mut buf) {
            Ok(_) => {}
            Err(e) => return matches!(black_box(e), EncodeError::Ar(_)),
        }
        let decoded = M::decode(black_box(&buf));
        let mut flash = Ram([0xFF; 2048]);
        let Ok(mut store) = FlashStore::new(&mut flash, 0..black_box(2048)) else {
            return false;
        };
        let saved = store.save(model, &mut buf).is_ok();
        let loaded = store.load::<M>(&mut buf);
        saved && decoded.as_ref() == Ok(model) && loaded.as_ref() == Ok(model)
    }

    /// The composite noise model from the stream, with the lattice's model as its AR part when
    /// there is one: its check, IEEE 952 readings and filter form.
    fn noise<const P: usize>(allan: &AllanStream<12>, ar: Option<&ArModel<f32, P>>) -> bool {
        let ar = ar.and_then(|m| {
            let a = m.a().map(f64::from);
            let dt = f64::from(m.dt());
            ArModel::new(a, f64::from(m.noise_variance()), 0.0, dt).ok()
        });
        let Ok(octaves) = Octaves::from_stream(allan, black_box(0.01)) else {
            return false;
        };
        let config = FitConfig::new(black_box(2))
            .with_oscillators(black_box(true))
            .with_identification(black_box(true));
        let fitted = NoiseModel::<P, 2>::identify(&octaves, ar.as_ref(), &config).and_then(|fit| {
            let model = fit.model;
            let check = model.check(&octaves)?;
            let whole = model.check_whole(&octaves)?;
            let form = model.kalman(black_box(0.1), black_box(1e-4))?;
            let uncertainty = model.uncertainty(&octaves)?;
            Ok((
                model.ieee952(&octaves),
                check.explained_up_to().or(whole.explained_up_to()),
                form,
                model,
                uncertainty
                    .white_noise
                    .high
                    .max(uncertainty.random_walk.high),
            ))
        });
        match fitted {
            Ok((ieee, _, form, model, high)) => {
                ieee.white_noise.is_finite()
                    && form.white_psd.is_finite()
                    && !high.is_nan()
                    && persist(&model)
            }
            // An AR part the lattice's model cannot give (not stationary) is a typed error.
            Err(e) => matches!(black_box(e), NoiseError::Ar(ModelError::Unstable { .. })),
        }
    }

    /// The thermal stage with `N` coefficients over `x` on a temperature ramp that leaves its
    /// range (and a NaN temperature): whether every residual, bias, compensation and leverage
    /// is finite.
    fn thermal<T: Scalar, const N: usize>(x: &[f32]) -> bool {
        let config = ThermalConfig::<T, N>::new(
            T::from_f64(black_box(0.999)),
            T::from_f64(black_box(20.0)),
            T::from_f64(black_box(50.0)),
        )
        .and_then(|c| c.with_delta(T::from_f64(black_box(0.5))));
        let stage = config.and_then(|c| {
            ThermalBias::with_prior(&c, [T::from_f64(black_box(0.1)); N])
                .and_then(|s| s.with_saturation(T::from_f64(black_box(1e3))))
                .map(|s| (c, s, ThermalBias::new(&c)))
        });
        let Ok((config, mut stage, mut plain)) = stage else {
            return false;
        };
        let mut finite = true;
        for (i, &v) in x.iter().enumerate() {
            let celsius = if i == 50 {
                T::from_f64(f64::NAN)
            } else {
                T::from_f64(15.0 + 0.08 * i as f64)
            };
            let v = T::from_f64(f64::from(v));
            for s in [&mut stage, &mut plain] {
                if let Some(r) = s.update(&config, black_box(v), black_box(celsius)) {
                    finite &= r.is_finite();
                }
            }
        }
        let t = T::from_f64(black_box(33.0));
        finite &= stage.bias(&config, t).is_some_and(|b| b.is_finite());
        finite &= stage.leverage(&config, t).is_some_and(|l| l.is_finite());
        finite &= stage
            .compensate(&config, T::from_f64(black_box(0.4)), t)
            .is_some_and(|r| r.is_finite());
        finite &= stage.per_kelvin(&config).iter().all(|b| b.is_finite());
        finite && black_box(stage.health()).rejected() > 0
    }

    #[entry]
    fn main() -> ! {
        let config = match Config::new(black_box(0.99f32), black_box(0.01)) {
            Ok(c) => c,
            Err(_) => debug_exit(false),
        };
        let channel =
            match Channel::new(black_box(0.1)).and_then(|c| c.with_saturation(black_box(1e3))) {
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
        let ok = exercise::<1>(&config, &channel, &x)
            & exercise::<4>(&config, &channel, &x)
            & exercise::<8>(&config, &channel, &x)
            & thermal::<f32, 1>(&x)
            & thermal::<f32, 4>(&x)
            & thermal::<f64, 4>(&x);
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
