//! Self test of the firmware frame on the emulated Cortex-M4F.
//!
//! ```text
//! cargo qemu selftest
//! ```
//!
//! Solves the Yule-Walker equations for `r = [1, 1/2, 1/10, 1/20]` in `f32` with the library's
//! Levinson-Durbin recursion, compares with the exact `a = [5/8, -11/40, 1/8]`, logs one defmt
//! line and exits 0 (1 when a coefficient is off by more than 2 f32 epsilons).
//!
//! To check that a failing firmware fails its run, build with `IMU_AR_SELFTEST_FAULT` set to
//! `panic`, `hardfault` or `hang`: the first two exit with status 1, the last is stopped by the
//! runner's timeout (`QEMU_RUN_TIMEOUT`, status 124).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(target_os = "none")]
#[path = "common/mod.rs"]
mod common;

#[cfg(target_os = "none")]
#[cortex_m_rt::entry]
fn main() -> ! {
    use core::hint::black_box;
    use imu_ar::batch::levinson_durbin;

    match option_env!("IMU_AR_SELFTEST_FAULT") {
        None | Some("") => {}
        Some("panic") => panic!("deliberate panic (IMU_AR_SELFTEST_FAULT=panic)"),
        Some("hardfault") => cortex_m::asm::udf(),
        Some("hang") => loop {
            cortex_m::asm::nop();
        },
        Some(other) => {
            defmt::error!("unknown IMU_AR_SELFTEST_FAULT={=str}", other);
            common::exit(false)
        }
    }

    let r: [f32; 4] = black_box([1.0, 0.5, 0.1, 0.05]);
    let exact = [5.0 / 8.0, -11.0 / 40.0, 1.0 / 8.0];
    let ok = match levinson_durbin::<f32, 3>(&r) {
        Ok(fit) => {
            let err = fit
                .a
                .iter()
                .zip(exact)
                .fold(0.0f32, |m, (a, b)| m.max((a - b).abs()));
            defmt::info!(
                "selftest: Levinson-Durbin f32 a = {}, E3 = {=f32}, max|a - exact| = {=f32}",
                fit.a,
                fit.error_power[2],
                err
            );
            err <= 2.0 * f32::EPSILON
        }
        Err(e) => {
            defmt::error!("selftest: Levinson-Durbin failed: {}", e);
            false
        }
    };
    common::exit(ok)
}

#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("selftest is firmware for the Cortex-M4F: run it with `cargo qemu selftest`");
}
