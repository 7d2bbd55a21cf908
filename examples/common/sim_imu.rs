//! A simulated MPU-6050 on a simulated I2C bus, for the `demo` firmware.
//!
//! It answers the register protocol the `imu_ar::sensor::Mpu6050` reader uses (WHO_AM_I,
//! reset, configuration writes, the data registers, INT_STATUS, FIFO_COUNT, FIFO_R_W) at
//! address 0x68, with the default ranges (+-250 deg/s: 131 counts per deg/s; +-2 g: 16384
//! counts per g). Every read of INT_STATUS is 100 ms of sensor time: 10 new samples (100 Hz)
//! enter the FIFO; but for the one that closes a FIFO read (right after FIFO_R_W), which takes
//! no time.
//!
//! Each axis is `bias(T) + Gauss-Markov drift + white noise`, quantised to counts, and the
//! temperature ramps from 25 to 45 deg C over 120 s. The bias is a cubic in `T - 25`
//! ([`Axis::bias_at`]): over the 20 K it moves by 0.27 to 0.32 deg/s on the gyro axes and by
//! 24 to 28 mg on the accelerometer axes. The drift's sigma and correlation time follow the
//! temperature too: `sigma = sigma_25 (1 + 0.01 (T - 25))`, `T_c = T_c25 (1 - 0.01 (T - 25))`.
//! The data registers hold the temperature of the latest sample (TEMP_OUT, `raw / 340 +
//! 36.53` deg C, rounded to a count).

use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};
use imu_ar::sim::StandardNormal;
use rand_chacha::ChaCha8Rng;
use rand_core::SeedableRng;

/// Six axes: gyro x, y, z (deg/s), accel x, y, z (g).
pub const AXES: usize = 6;
const ADDRESS: u8 = 0x68;
const DT: f64 = 0.01;
const BATCH: usize = 10;
const FIFO_BYTES: usize = 1024;
const RAMP_S: f64 = 120.0;

/// One axis of the simulated sensor.
#[derive(Clone, Copy)]
struct Axis {
    /// The bias at 25 deg C.
    bias: f64,
    /// The bias's change per K, K^2 and K^3 above 25 deg C.
    thermal: [f64; 3],
    gm_sigma_25: f64,
    tc_25: f64,
    white: f64,
    counts_per_unit: f64,
    gm: f64,
}

impl Axis {
    /// The bias at `celsius`: `bias + t1 d + t2 d^2 + t3 d^3`, `d = celsius - 25`.
    fn bias_at(&self, celsius: f64) -> f64 {
        let d = celsius - 25.0;
        let [t1, t2, t3] = self.thermal;
        self.bias + d * (t1 + d * (t2 + d * t3))
    }
}

/// The truth of an axis at the current temperature.
#[derive(Clone, Copy, Debug)]
pub struct AxisTruth {
    /// Mean of the output (the bias at the temperature), in units.
    pub mean: f64,
    /// Gauss-Markov sigma, in units.
    pub gm_sigma: f64,
    /// Gauss-Markov correlation time, s.
    pub tc: f64,
    /// White noise sigma including quantisation (`q^2/12`), in units.
    pub white: f64,
}

impl AxisTruth {
    fn phi(&self) -> f64 {
        libm::exp(-DT / self.tc)
    }

    /// The best AR(P) model of the process (what a least-squares fit converges to): the
    /// Yule-Walker solution for the exact autocovariances `r(0) = sigma_gm^2 + white^2`,
    /// `r(k) = sigma_gm^2 phi^k`, and its innovation variance.
    pub fn ar_projection<const P: usize>(&self) -> Option<([f64; P], f64)> {
        let phi = self.phi();
        let g = self.gm_sigma * self.gm_sigma;
        let r: [f64; 9] = core::array::from_fn(|k| {
            let c = g * libm::pow(phi, k as f64);
            if k == 0 {
                c + self.white * self.white
            } else {
                c
            }
        });
        let fit = imu_ar::batch::levinson_durbin::<f64, P>(&r).ok()?;
        Some((fit.a, fit.error_power[P - 1]))
    }

    /// Standard deviation of an exponentially weighted mean (weights `(1 - lambda) lambda^k`)
    /// of the process.
    pub fn ew_mean_sd(&self, lambda: f64) -> f64 {
        let phi = self.phi();
        let w = (1.0 - lambda) / (1.0 + lambda);
        let gm = self.gm_sigma * self.gm_sigma * w * (1.0 + phi * lambda) / (1.0 - phi * lambda);
        libm::sqrt(gm + self.white * self.white * w)
    }
}

fn temperature_at(t: f64) -> f64 {
    25.0 + 20.0 * (t / RAMP_S).clamp(0.0, 1.0)
}

/// The simulated sensor and its bus.
pub struct SimImu {
    axes: [Axis; AXES],
    rng: ChaCha8Rng,
    normal: StandardNormal,
    t: f64,
    n: u64,
    corrupt: bool,
    pointer: u8,
    fifo_enabled: bool,
    fifo: [u8; FIFO_BYTES],
    head: usize,
    len: usize,
    overflow: bool,
    /// The last register read was FIFO_R_W: the next INT_STATUS read closes a FIFO read.
    after_data: bool,
    latest: [u8; 14],
    /// USER_CTRL and PWR_MGMT_1 as last written (the reader reads them back to detect a chip
    /// reset).
    user_ctrl: u8,
    pwr_mgmt_1: u8,
}

impl SimImu {
    /// A sensor with a fixed seed; `corrupt` spikes every 20th sample by 2000 counts.
    pub fn new(seed: u64, corrupt: bool) -> Self {
        let gyro = |bias, thermal| Axis {
            bias,
            thermal,
            gm_sigma_25: 0.05,
            tc_25: 2.0,
            white: 0.02,
            counts_per_unit: 131.0,
            gm: 0.0,
        };
        let accel = |bias, thermal| Axis {
            bias,
            thermal,
            gm_sigma_25: 0.002,
            tc_25: 5.0,
            white: 0.003,
            counts_per_unit: 16384.0,
            gm: 0.0,
        };
        // Gyro z drifts more and is quieter: an AR(1) (a sampled Gauss-Markov process) fits it.
        let gyro_z = Axis {
            gm_sigma_25: 0.2,
            tc_25: 1.0,
            white: 0.005,
            ..gyro(0.2, [0.012, 2e-4, -6e-6])
        };
        // Over 20 K: gx +0.32, gy -0.27, gz +0.27 deg/s; ax +28, ay -24, az +28 mg.
        let mut s = Self {
            axes: [
                gyro(0.5, [0.02, -3e-4, 5e-6]),
                gyro(-0.3, [-0.01, -2.5e-4, 4e-6]),
                gyro_z,
                accel(0.01, [1.5e-3, -1e-5, 2e-7]),
                accel(-0.02, [-8e-4, -3e-5, 5e-7]),
                accel(1.0, [2e-3, -5e-5, 1e-6]),
            ],
            rng: ChaCha8Rng::seed_from_u64(seed),
            normal: StandardNormal::new(),
            t: 0.0,
            n: 0,
            corrupt,
            pointer: 0,
            fifo_enabled: false,
            fifo: [0; FIFO_BYTES],
            head: 0,
            len: 0,
            overflow: false,
            after_data: false,
            latest: [0; 14],
            user_ctrl: 0,
            // Power-on value: SLEEP set, internal oscillator.
            pwr_mgmt_1: 0x40,
        };
        // Start each drift from its stationary distribution.
        for i in 0..AXES {
            let z = s.normal.sample(&mut s.rng);
            s.axes[i].gm = s.axes[i].gm_sigma_25 * z;
        }
        s
    }

    fn temperature(&self) -> f64 {
        temperature_at(self.t)
    }

    /// The truth of every axis at time `t` (s): the parameters follow the temperature ramp.
    pub fn truth_at(&self, t: f64) -> [AxisTruth; AXES] {
        let celsius = temperature_at(t);
        let dtemp = celsius - 25.0;
        self.axes.map(|a| {
            let q = 1.0 / a.counts_per_unit;
            AxisTruth {
                mean: a.bias_at(celsius),
                gm_sigma: a.gm_sigma_25 * (1.0 + 0.01 * dtemp),
                tc: a.tc_25 * (1.0 - 0.01 * dtemp),
                white: libm::sqrt(a.white * a.white + q * q / 12.0),
            }
        })
    }

    /// Draws the next sample into the data registers and, when enabled, the FIFO.
    fn step(&mut self) {
        let celsius = self.temperature();
        let dtemp = celsius - 25.0;
        let mut counts = [0i16; AXES];
        for (i, c) in counts.iter_mut().enumerate() {
            let a = self.axes[i];
            let sigma = a.gm_sigma_25 * (1.0 + 0.01 * dtemp);
            let phi = libm::exp(-DT / (a.tc_25 * (1.0 - 0.01 * dtemp)));
            let drive = sigma * libm::sqrt(1.0 - phi * phi) * self.normal.sample(&mut self.rng);
            let gm = phi * a.gm + drive;
            self.axes[i].gm = gm;
            let white = a.white * self.normal.sample(&mut self.rng);
            let mut v = libm::round((a.bias_at(celsius) + gm + white) * a.counts_per_unit);
            if self.corrupt && self.n % 20 == 19 {
                v += 2000.0;
            }
            *c = v.clamp(-32768.0, 32767.0) as i16;
        }
        self.t += DT;
        self.n += 1;
        // Data registers 59-72: accel, temperature, gyro (big-endian).
        let temp_raw = libm::round((celsius - 36.53) * 340.0) as i16;
        let words = [
            counts[3], counts[4], counts[5], temp_raw, counts[0], counts[1], counts[2],
        ];
        for (k, w) in words.iter().enumerate() {
            self.latest[2 * k..2 * k + 2].copy_from_slice(&w.to_be_bytes());
        }
        if self.fifo_enabled {
            // FIFO packet: accel then gyro, as FIFO_EN = XG | YG | ZG | ACCEL orders them.
            let mut packet = [0u8; 12];
            packet[..6].copy_from_slice(&self.latest[..6]);
            packet[6..].copy_from_slice(&self.latest[8..]);
            if self.len + packet.len() > FIFO_BYTES {
                self.overflow = true;
            } else {
                for b in packet {
                    self.fifo[(self.head + self.len) % FIFO_BYTES] = b;
                    self.len += 1;
                }
            }
        }
    }

    fn read_reg(&mut self, reg: u8) -> u8 {
        match reg {
            0x3A => {
                // INT_STATUS: 100 ms pass (but for the check that closes a FIFO read, and the
                // one inside a FIFO reset, with the FIFO off), then report (and clear) an
                // overflow.
                if !core::mem::take(&mut self.after_data) && self.fifo_enabled {
                    for _ in 0..BATCH {
                        self.step();
                    }
                }
                let status = if self.overflow { 0x11 } else { 0x01 };
                self.overflow = false;
                status
            }
            0x3B..=0x48 => self.latest[usize::from(reg - 0x3B)],
            0x72 => (self.len >> 8) as u8,
            0x73 => self.len as u8,
            0x74 => {
                self.after_data = true;
                if self.len == 0 {
                    return 0;
                }
                let b = self.fifo[self.head];
                self.head = (self.head + 1) % FIFO_BYTES;
                self.len -= 1;
                b
            }
            0x6A => self.user_ctrl,
            0x6B => self.pwr_mgmt_1,
            0x75 => 0x68,
            _ => 0,
        }
    }

    fn write_reg(&mut self, reg: u8, value: u8) {
        match reg {
            0x6A => {
                if value & 0x04 != 0 {
                    self.head = 0;
                    self.len = 0;
                }
                self.fifo_enabled = value & 0x40 != 0;
                // FIFO_RESET clears itself.
                self.user_ctrl = value & !0x04;
            }
            // DEVICE_RESET puts the registers at their power-on values (asleep).
            0x6B if value & 0x80 != 0 => {
                self.pwr_mgmt_1 = 0x40;
                self.user_ctrl = 0;
                self.fifo_enabled = false;
            }
            0x6B => self.pwr_mgmt_1 = value,
            _ => {}
        }
    }
}

impl ErrorType for SimImu {
    type Error = ErrorKind;
}

impl I2c for SimImu {
    fn transaction(&mut self, address: u8, ops: &mut [Operation<'_>]) -> Result<(), ErrorKind> {
        if address != ADDRESS {
            return Err(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address));
        }
        for op in ops {
            match op {
                Operation::Write(bytes) => {
                    if let Some((&reg, data)) = bytes.split_first() {
                        self.pointer = reg;
                        for &v in data {
                            self.write_reg(self.pointer, v);
                            self.pointer = self.pointer.wrapping_add(1);
                        }
                    }
                }
                Operation::Read(buf) => {
                    for b in buf.iter_mut() {
                        *b = self.read_reg(self.pointer);
                        if self.pointer != 0x74 {
                            self.pointer = self.pointer.wrapping_add(1);
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
