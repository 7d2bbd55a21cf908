//! `imu-ar adev`: the overlapping Allan deviation at `m = 1, 2, 4, ...` samples.

use imu_ar::allan::overlapping_avar;
use serde::Serialize;

use crate::error::Fail;
use crate::input::{Input, check_rate, check_span};
use crate::output::Output;

/// The arguments of `imu-ar adev`.
#[derive(clap::Args)]
pub struct Args {
    /// The column.
    #[command(flatten)]
    input: Input,
    /// Sample rate in Hz [default: from the timestamps].
    #[arg(long, allow_negative_numbers = true)]
    rate: Option<f64>,
    /// Print one JSON object.
    #[arg(long)]
    pub json: bool,
}

/// The Allan variance and deviation at `tau = m / rate` while `2m <= n`.
#[derive(Serialize)]
pub struct AdevResult {
    /// Sample rate in Hz.
    pub rate_hz: f64,
    /// Averaging times in s.
    pub tau_s: Vec<f64>,
    /// Overlapping Allan variance at each `tau`.
    pub avar: Vec<f64>,
    /// Its square root.
    pub adev: Vec<f64>,
    /// Samples in the record.
    pub n: usize,
}

impl Output for AdevResult {
    fn text(&self) -> String {
        let mut s = format!(
            "# n = {}, rate = {} Hz\n# tau_s avar adev\n",
            self.n, self.rate_hz
        );
        for ((t, v), d) in self.tau_s.iter().zip(&self.avar).zip(&self.adev) {
            s += &format!("{t} {v:e} {d:e}\n");
        }
        s
    }
}

/// Checks the rate, reads the record and computes its Allan deviation.
pub fn run(args: &Args) -> Result<AdevResult, Fail> {
    if let Some(r) = args.rate {
        check_rate(r)?;
    }
    let series = args.input.series(args.rate.is_none())?;
    let x = &series.x;
    if x.len() < 2 {
        let e = format!("{} sample(s), at least 2 needed", x.len());
        return Err(args.input.fail(e));
    }
    let rate = series.rate(args.rate, &args.input)?;
    check_span("--rate", rate, x.len())?;
    let (mut tau, mut avar) = (Vec::new(), Vec::new());
    let mut m = 1usize;
    while x.len() / 2 >= m {
        tau.push(m as f64 / rate);
        let v = overlapping_avar(x, m)?;
        if !v.is_finite() {
            return Err(args.input.fail(format!(
                "the Allan variance at m = {m} overflows: the samples' differences are too large \
                 for f64 (scale the data, --unit)"
            )));
        }
        avar.push(v);
        m *= 2;
    }
    Ok(AdevResult {
        rate_hz: rate,
        tau_s: tau,
        adev: avar.iter().map(|v| v.sqrt()).collect(),
        avar,
        n: x.len(),
    })
}
