//! A reader that serves recorded samples from memory: tests, emulation, host replays.

use core::convert::Infallible;

use super::{Error, FifoStats, ImuReader, RawSample, Scale, Thermometer};

/// Serves the samples of a slice in order, with the sensitivities they were recorded at.
///
/// ```
/// use imu_ar::recursive::{Channel, Config, Estimator, Lattice};
/// use imu_ar::sensor::{AccelUnit, Error, GyroUnit, ImuReader, RawSample, Replay, Scale};
///
/// let scale = Scale { gyro_counts_per_dps: 131.0, accel_counts_per_g: 16384.0 };
/// let record: Vec<RawSample> = (0..200i16)
///     .map(|i| RawSample { gyro: [i % 7, -(i % 5), 3], accel: [i % 3, 0, 16384], temperature: None })
///     .collect();
/// let mut replay = Replay::new(&record, scale);
///
/// let config = Config::new(0.99f32, 0.01).unwrap();
/// let (gyro, accel) = (Channel::new(1e-4).unwrap(), Channel::new(1e-6).unwrap());
/// let mut axes: [Lattice<f32, 2>; 6] =
///     core::array::from_fn(|i| Lattice::new(&config, if i < 3 { &gyro } else { &accel }));
/// let mut batch = [RawSample::default(); 32];
/// loop {
///     let n = replay.read_fifo(&mut batch)?;
///     if n == 0 {
///         break;
///     }
///     for s in &batch[..n] {
///         let gyro = replay.scale().gyro(s.gyro, GyroUnit::DegPerSec);
///         let accel = replay.scale().accel(s.accel, AccelUnit::G);
///         for (lattice, x) in axes.iter_mut().zip(gyro.into_iter().chain(accel)) {
///             lattice.update(&config, x);
///         }
///     }
/// }
/// assert_eq!(axes[0].health().samples, 200);
/// assert_eq!(replay.read(), Err(Error::NoData));
/// # Ok::<(), Error<core::convert::Infallible>>(())
/// ```
#[derive(Clone, Copy, Debug)]
pub struct Replay<'a> {
    samples: &'a [RawSample],
    next: usize,
    scale: Scale,
    thermometer: Option<Thermometer>,
    stats: FifoStats,
}

impl<'a> Replay<'a> {
    /// A replay of `samples` recorded at `scale`.
    pub fn new(samples: &'a [RawSample], scale: Scale) -> Self {
        Self {
            samples,
            next: 0,
            scale,
            thermometer: None,
            stats: FifoStats::default(),
        }
    }

    /// The same replay, its samples' raw temperatures read by `thermometer` (the recording
    /// chip's: [`ImuReader::die_temperature`] then gives deg C).
    pub fn with_thermometer(self, thermometer: Thermometer) -> Self {
        Self {
            thermometer: Some(thermometer),
            ..self
        }
    }

    /// Samples not yet served.
    pub fn remaining(&self) -> usize {
        self.samples.len().saturating_sub(self.next)
    }

    /// Starts again from the first sample.
    pub fn rewind(&mut self) {
        self.next = 0;
    }
}

impl ImuReader for Replay<'_> {
    type BusError = Infallible;

    fn scale(&self) -> Scale {
        self.scale
    }

    fn read(&mut self) -> Result<RawSample, Error<Infallible>> {
        let s = *self.samples.get(self.next).ok_or(Error::NoData)?;
        self.next += 1;
        Ok(s)
    }

    fn read_fifo(&mut self, out: &mut [RawSample]) -> Result<usize, Error<Infallible>> {
        let rest = self.samples.get(self.next..).unwrap_or(&[]);
        let n = rest.len().min(out.len());
        out[..n].copy_from_slice(&rest[..n]);
        self.next += n;
        self.stats.samples = self.stats.samples.saturating_add(n as u64);
        self.stats.clipped = self
            .stats
            .clipped
            .saturating_add(out[..n].iter().filter(|s| s.clipped()).count() as u64);
        Ok(n)
    }

    fn fifo_stats(&self) -> FifoStats {
        self.stats
    }

    fn thermometer(&self) -> Option<Thermometer> {
        self.thermometer
    }
}
