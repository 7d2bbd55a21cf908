//! `imu-ar`: characterise a recorded sensor log with the library's estimators.
//!
//! ```text
//! imu-ar fit FILE.. --column C --method ls|yule-walker|burg|rls|lattice --order P
//!     [--scalar f64|f32|fixed] [--lambda L] [--delta D] [--scale S] [--no-demean] [--decimate M]
//!     [--rate HZ] [--json]
//! imu-ar compare FILE.. --column C --order P [--lambda L] [--delta D] [--decimate M] [--train F]
//!     [--json]
//! imu-ar report FILE.. --column C --order P --rate HZ --out DIR [--lambda L] [--delta D]
//!     [--decimate M] [--train F] [--unit U] [--reference TABLE]
//! imu-ar noise FILE.. --column C --rate HZ [--gm-states K] [--ar-order P] [--oscillators]
//!     [--ramp] [--filter-rate HZ] [--decimate M] [--unit U] [--json] [--plot FILE.png]
//! imu-ar order FILE.. --column C --max-order P --method ls|yule-walker|burg [--no-demean] [--json]
//! imu-ar adev FILE.. --column C --rate HZ [--json]
//! imu-ar kalman FILE.. --column C --order P --rate HZ [--method ls|yule-walker|burg] [--decimate M]
//!     [--filter-rate HZ] [--json]
//! imu-ar parity
//! imu-ar simulate --a A1,A2,.. [--a-end B1,B2,..] --sigma S --n N --seed K [--rate HZ] [--burn-in B]
//! imu-ar thermal FILE.. --out DIR [--columns C,..] [--temperature-column T] [--format px4,ardupilot,json]
//!     [--device-id GYRO,ACCEL] [--px4-slot J] [--imu N] [--bin-width C] [--min-bin K] [--json]
//! ```
//!
//! Several files are read as one record, in order. Bad input exits with status 2 and one line
//! on stderr naming the file, line and problem; nothing is written to stdout. The commands
//! are the modules of the library `imu_ar_cli`; this file parses and dispatches.

use std::ffi::OsString;
use std::io::{BufWriter, Write};
use std::process::ExitCode;

use clap::{CommandFactory, Parser, Subcommand};
use imu_ar_cli::error::{Fail, clap_error, escaped};
use imu_ar_cli::output::{json_line, render};
use imu_ar_cli::{
    adev, characterise, compare, fit, kalman, noise, order, parity, report, simulate, thermal,
};

#[derive(Parser)]
#[command(
    name = "imu-ar",
    version,
    about = "AR stochastic models of MEMS sensor errors"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Fit an AR(P) model to one column.
    Fit(fit::Args),
    /// One-step prediction error of a batch LS fit on the training part against RLS and the
    /// lattice running over the whole record, on the evaluation part.
    Compare(compare::Args),
    /// The paper's comparison on one record, in PNG plots: coefficient convergence of RLS and
    /// the lattice against the batch fit, one-step prediction error over time, the fitted PSD
    /// against a Welch periodogram, and Allan deviations of the data and the model; with
    /// --prior-a, a lattice from that prior against the plain start. Prints a JSON summary.
    Report(report::Args),
    /// The Kalman filter hand-off of a batch fit: `Phi`, `Q` and the stationary covariance at
    /// the filter's rate, the Gauss-Markov form of an AR(1), and the Allan check that the model
    /// explains the data's Allan deviation.
    Kalman(kalman::Args),
    /// The composite noise model a navigation filter needs (white noise, quantisation,
    /// Gauss-Markov terms, random walk, an AR part for the short-term colouring), fitted to the
    /// Allan variance, checked at every averaging time, with its IEEE 952 readings and its
    /// `Phi`, `Q` and `P0` at the filter's rate.
    Noise(noise::Args),
    /// All six axes of a recording (CSV, ROS 1 bag, MCAP) in one streaming pass: per axis the
    /// Allan deviation, the composite noise model and its IEEE 952 readings; decomposition
    /// plots, parameter files for navigation filters, and a summary table.
    Characterise(characterise::Args),
    /// Order criteria (AIC, AICc, BIC, FPE) of orders 0..=P.
    Order(order::Args),
    /// Overlapping Allan deviation at m = 1, 2, 4, ...
    Adev(adev::Args),
    /// Checksums of the f32 and fixed-point lattices on the seeded parity sequence and of the
    /// identified noise model on a seeded Allan stream, to compare
    /// with `cargo qemu parity` (bit-identical results on host and target).
    Parity,
    /// Simulate an AR process; CSV `t_s,x` on stdout.
    Simulate(simulate::Args),
    /// The thermal calibration PX4 and ArduPilot ask for, from a warm-up record: per axis the
    /// bias against temperature (binned, a robust cubic), the TC_* and INS_TCALn_* parameters,
    /// each applied back through the autopilot's own formula, and a check on bins held out of
    /// the fit (exit status 1 when a fit does not generalise).
    Thermal(thermal::Args),
}

fn main() -> ExitCode {
    // Ended by a signal: the folder `characterise` writes into goes first (status 130); once
    // the output is in place, the run ends as it would have.
    let _ = ctrlc::set_handler(|| {
        if characterise::remove_staging() {
            std::process::exit(130);
        }
    });
    let args: Vec<OsString> = std::env::args_os().collect();
    let cli = match Cli::try_parse_from(&args) {
        Ok(cli) => cli,
        // Help and version: a closed pipe is a normal end.
        Err(e) if !e.use_stderr() => return write_stdout(&e.to_string()),
        Err(e) => return fail(&clap_error(&e, &Cli::command(), &args)),
    };
    match run(cli.command) {
        Ok((out, passed)) => match write_stdout(&out) {
            ExitCode::SUCCESS if !passed => ExitCode::FAILURE,
            code => code,
        },
        Err(Fail(msg)) => fail(&escaped(&msg)),
    }
}

/// Runs a command and returns everything it prints, so that a failure prints nothing, and
/// whether its checks passed (status 1 when not: `thermal`). (`simulate` streams its record
/// itself.)
fn run(command: Command) -> Result<(String, bool), Fail> {
    if let Command::Thermal(args) = command {
        let t = thermal::run(&args)?;
        return Ok((render(&t, args.json)?, t.generalises));
    }
    let out = match command {
        Command::Fit(args) => render(&fit::run(&args)?, args.json),
        Command::Compare(args) => render(&compare::run(&args)?, args.json),
        Command::Report(args) => json_line(&report::run(&args)?),
        Command::Kalman(args) => render(&kalman::run(&args)?, args.json),
        Command::Noise(args) => render(&noise::run(&args)?, args.json),
        Command::Characterise(args) => render(&characterise::run(&args)?, args.json),
        Command::Order(args) => render(&order::run(&args)?, args.json),
        Command::Adev(args) => render(&adev::run(&args)?, args.json),
        Command::Parity => render(&parity::run()?, false),
        Command::Simulate(args) => simulate::run(&args).map(|()| String::new()),
        Command::Thermal(_) => Ok(String::new()),
    }?;
    Ok((out, true))
}

/// Prints the one line of an error on stderr; status 2.
fn fail(msg: &str) -> ExitCode {
    eprintln!("imu-ar: {msg}");
    ExitCode::from(2)
}

/// Writes `out` to stdout; a reader that closed the pipe early (`| head`) ends the run
/// normally (status 0), any other write error is status 1.
fn write_stdout(out: &str) -> ExitCode {
    let mut stdout = BufWriter::new(std::io::stdout().lock());
    match stdout
        .write_all(out.as_bytes())
        .and_then(|_| stdout.flush())
    {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("imu-ar: cannot write to stdout: {e}");
            ExitCode::FAILURE
        }
    }
}
