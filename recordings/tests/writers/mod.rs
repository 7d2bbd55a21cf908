//! Writers of small PX4 ULog files and ArduPilot DataFlash logs, byte by byte after the
//! formats' specifications, with the format strings the autopilots write: the fixtures of the
//! readers' tests (`recordings/tests/autopilot_logs.rs`) and of the tool's
//! (`cli/tests/cli/thermal.rs`).
// Each test crate uses some of these.
#![allow(dead_code)]

// ------------------------------------------------------------------------------------------
// A ULog writer.

/// The real format strings of PX4 (the trailing padding as the logger writes it).
pub const SENSOR_GYRO: &str = concat!(
    "sensor_gyro:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;",
    "float x;float y;float z;float temperature;uint32_t error_count;",
    "uint8_t[3] clip_counter;uint8_t samples;uint8_t[4] _padding0;",
);
pub const SENSOR_ACCEL: &str = concat!(
    "sensor_accel:uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;",
    "float x;float y;float z;float temperature;uint32_t error_count;",
    "uint8_t[3] clip_counter;uint8_t samples;uint8_t[4] _padding0;",
);
pub const GYRO_FIFO: &str = concat!(
    "sensor_gyro_fifo:uint64_t timestamp;uint64_t timestamp_sample;",
    "uint32_t device_id;float dt;float scale;int16_t[32] x;int16_t[32] y;",
    "int16_t[32] z;uint8_t samples;uint8_t[3] _padding0;",
);
pub const ACCEL_FIFO: &str = concat!(
    "sensor_accel_fifo:uint64_t timestamp;uint64_t timestamp_sample;",
    "uint32_t device_id;float dt;float scale;int16_t[32] x;int16_t[32] y;",
    "int16_t[32] z;uint8_t samples;uint8_t[3] _padding0;",
);
/// A nested format as PX4 writes them (`esc_status` holds `esc_report[8] esc`).
pub const ESC_REPORT: &str = concat!(
    "esc_report:uint64_t timestamp;float esc_rpm;float esc_voltage;",
    "uint8_t esc_address;uint8_t[7] _padding0;",
);
pub const ESC_STATUS: &str = concat!(
    "esc_status:uint64_t timestamp;uint16_t counter;uint8_t esc_count;",
    "uint8_t[5] _padding0;esc_report[8] esc;",
);

/// A ULog file being written.
pub struct ULog {
    pub bytes: Vec<u8>,
}

impl ULog {
    /// The header (version 1, start time `start_us`) and a flag bits message of zeros.
    pub fn new(start_us: u64) -> Self {
        let mut log = ULog::bare(start_us);
        log.flags([0; 8], [0; 8], [0; 3]);
        log
    }

    /// The header only.
    pub fn bare(start_us: u64) -> Self {
        let mut bytes = vec![0x55, 0x4c, 0x6f, 0x67, 0x01, 0x12, 0x35, 1];
        bytes.extend_from_slice(&start_us.to_le_bytes());
        ULog { bytes }
    }

    pub fn msg(&mut self, ty: u8, payload: &[u8]) {
        let size = u16::try_from(payload.len()).expect("a payload under 64 KiB");
        self.bytes.extend_from_slice(&size.to_le_bytes());
        self.bytes.push(ty);
        self.bytes.extend_from_slice(payload);
    }

    pub fn flags(&mut self, compat: [u8; 8], incompat: [u8; 8], offsets: [u64; 3]) {
        let mut p = compat.to_vec();
        p.extend_from_slice(&incompat);
        for o in offsets {
            p.extend_from_slice(&o.to_le_bytes());
        }
        self.msg(b'B', &p);
    }

    pub fn format(&mut self, text: &str) {
        self.msg(b'F', text.as_bytes());
    }

    /// An 'I' or 'P' message: key "<type> <name>", then `value`.
    pub fn keyed(&mut self, ty: u8, key: &str, value: &[u8]) {
        let mut p = vec![u8::try_from(key.len()).expect("a short key")];
        p.extend_from_slice(key.as_bytes());
        p.extend_from_slice(value);
        self.msg(ty, &p);
    }

    pub fn info(&mut self, name: &str, text: &str) {
        self.keyed(
            b'I',
            &format!("char[{}] {name}", text.len()),
            text.as_bytes(),
        );
    }

    pub fn param_f32(&mut self, name: &str, v: f32) {
        self.keyed(b'P', &format!("float {name}"), &v.to_le_bytes());
    }

    pub fn param_i32(&mut self, name: &str, v: i32) {
        self.keyed(b'P', &format!("int32_t {name}"), &v.to_le_bytes());
    }

    pub fn subscribe(&mut self, multi_id: u8, msg_id: u16, name: &str) {
        let mut p = vec![multi_id];
        p.extend_from_slice(&msg_id.to_le_bytes());
        p.extend_from_slice(name.as_bytes());
        self.msg(b'A', &p);
    }

    pub fn data(&mut self, msg_id: u16, payload: &[u8]) {
        let mut p = msg_id.to_le_bytes().to_vec();
        p.extend_from_slice(payload);
        self.msg(b'D', &p);
    }

    pub fn log_string(&mut self, timestamp: u64, text: &str) {
        let mut p = vec![b'6'];
        p.extend_from_slice(&timestamp.to_le_bytes());
        p.extend_from_slice(text.as_bytes());
        self.msg(b'L', &p);
    }

    pub fn sync(&mut self) {
        self.msg(b'S', &[0x2f, 0x73, 0x13, 0x20, 0x25, 0x0c, 0xbb, 0x12]);
    }

    pub fn dropout(&mut self, ms: u16) {
        self.msg(b'O', &ms.to_le_bytes());
    }
}

/// A `sensor_gyro`/`sensor_accel` payload, its trailing padding omitted as PX4 does.
pub fn sensor(
    timestamp: u64,
    sample: u64,
    device: u32,
    xyz: [f32; 3],
    temperature: f32,
) -> Vec<u8> {
    let mut p = timestamp.to_le_bytes().to_vec();
    p.extend_from_slice(&sample.to_le_bytes());
    p.extend_from_slice(&device.to_le_bytes());
    for v in xyz {
        p.extend_from_slice(&v.to_le_bytes());
    }
    p.extend_from_slice(&temperature.to_le_bytes());
    p.extend_from_slice(&0u32.to_le_bytes());
    p.extend_from_slice(&[0, 0, 0, 1]);
    p
}

/// A FIFO payload of `n` samples (its arrays filled with `xyz`), its padding omitted.
pub fn fifo(sample: u64, device: u32, dt: f32, scale: f32, n: u8, xyz: &[[i16; 32]; 3]) -> Vec<u8> {
    let mut p = (sample + 40).to_le_bytes().to_vec();
    p.extend_from_slice(&sample.to_le_bytes());
    p.extend_from_slice(&device.to_le_bytes());
    p.extend_from_slice(&dt.to_le_bytes());
    p.extend_from_slice(&scale.to_le_bytes());
    for axis in xyz {
        for v in axis {
            p.extend_from_slice(&v.to_le_bytes());
        }
    }
    p.push(n);
    p
}

// ------------------------------------------------------------------------------------------
// A DataFlash writer.

/// Message types as ArduPilot numbers some of them; the rest free.
pub const PARM: u8 = 64;
pub const UNIT: u8 = 177;
pub const MULT: u8 = 178;
pub const FMTU: u8 = 179;
pub const IMU: u8 = 150;
pub const ISBH: u8 = 151;
pub const ISBD: u8 = 152;
pub const EVERY: u8 = 200;

/// A DataFlash log being written.
pub struct Df {
    pub bytes: Vec<u8>,
}

/// The size of a format character.
pub fn df_size(c: char) -> usize {
    match c {
        'b' | 'B' | 'M' => 1,
        'h' | 'H' | 'c' | 'C' | 'g' => 2,
        'i' | 'I' | 'f' | 'e' | 'E' | 'L' | 'n' => 4,
        'd' | 'q' | 'Q' => 8,
        'N' => 16,
        'a' | 'Z' => 64,
        _ => panic!("format character {c}"),
    }
}

/// `text` in `len` bytes, padded with NULs.
pub fn fixed(text: &str, len: usize) -> Vec<u8> {
    let mut b = text.as_bytes().to_vec();
    b.resize(len, 0);
    b
}

impl Df {
    /// The FMT of FMT, then the formats of PARM, UNIT, MULT, FMTU, IMU, ISBH and ISBD with
    /// ArduPilot's strings, and the units and multipliers.
    pub fn new() -> Self {
        let mut df = Df { bytes: Vec::new() };
        df.fmt(128, "FMT", "BBnNZ", "Type,Length,Name,Format,Columns");
        df.fmt(PARM, "PARM", "QNff", "TimeUS,Name,Value,Default");
        df.fmt(UNIT, "UNIT", "QbZ", "TimeUS,Id,Label");
        df.fmt(MULT, "MULT", "Qbd", "TimeUS,Id,Mult");
        df.fmt(FMTU, "FMTU", "QBNN", "TimeUS,FmtType,UnitIds,MultIds");
        for (id, label) in [
            ('E', "rad/s"),
            ('o', "m/s/s"),
            ('O', "degC"),
            ('s', "s"),
            ('#', "instance"),
            ('-', ""),
            ('z', "Hz"),
        ] {
            let mut p = 0u64.to_le_bytes().to_vec();
            p.push(id as u8);
            p.extend_from_slice(&fixed(label, 64));
            df.msg(UNIT, &p);
        }
        for (id, mult) in [('F', 1e-6), ('0', 1.0), ('-', 0.0), ('?', 1.0)] {
            let mut p = 0u64.to_le_bytes().to_vec();
            p.push(id as u8);
            p.extend_from_slice(&f64::to_le_bytes(mult));
            df.msg(MULT, &p);
        }
        df.fmt(
            IMU,
            "IMU",
            "QBffffffIIfBBHH",
            "TimeUS,I,GyrX,GyrY,GyrZ,AccX,AccY,AccZ,EG,EA,T,GH,AH,GHz,AHz",
        );
        df.fmtu(IMU, "s#EEEooo--O--zz", "F-000000-----00");
        df.fmt(
            ISBH,
            "ISBH",
            "QHBBHHQf",
            "TimeUS,N,type,instance,mul,smp_cnt,SampleUS,smp_rate",
        );
        df.fmt(ISBD, "ISBD", "QHHaaa", "TimeUS,N,seqno,x,y,z");
        df
    }

    pub fn msg(&mut self, ty: u8, payload: &[u8]) {
        self.bytes.extend_from_slice(&[0xa3, 0x95, ty]);
        self.bytes.extend_from_slice(payload);
    }

    pub fn fmt(&mut self, ty: u8, name: &str, format: &str, columns: &str) {
        let len = 3 + format.chars().map(df_size).sum::<usize>();
        let mut p = vec![ty, u8::try_from(len).expect("a message under 256 bytes")];
        p.extend_from_slice(&fixed(name, 4));
        p.extend_from_slice(&fixed(format, 16));
        p.extend_from_slice(&fixed(columns, 64));
        self.msg(128, &p);
    }

    pub fn fmtu(&mut self, ty: u8, units: &str, mults: &str) {
        let mut p = 0u64.to_le_bytes().to_vec();
        p.push(ty);
        p.extend_from_slice(&fixed(units, 16));
        p.extend_from_slice(&fixed(mults, 16));
        self.msg(FMTU, &p);
    }

    pub fn parm(&mut self, time: u64, name: &str, value: f32) {
        let mut p = time.to_le_bytes().to_vec();
        p.extend_from_slice(&fixed(name, 16));
        p.extend_from_slice(&value.to_le_bytes());
        p.extend_from_slice(&0f32.to_le_bytes());
        self.msg(PARM, &p);
    }

    pub fn imu(&mut self, time: u64, instance: u8, gyro: [f32; 3], accel: [f32; 3], t: f32) {
        let mut p = time.to_le_bytes().to_vec();
        p.push(instance);
        for v in gyro.iter().chain(&accel) {
            p.extend_from_slice(&v.to_le_bytes());
        }
        p.extend_from_slice(&[0; 8]);
        p.extend_from_slice(&t.to_le_bytes());
        p.extend_from_slice(&[1, 1]);
        p.extend_from_slice(&1000u16.to_le_bytes());
        p.extend_from_slice(&1000u16.to_le_bytes());
        self.msg(IMU, &p);
    }

    #[allow(clippy::too_many_arguments)]
    pub fn isbh(
        &mut self,
        time: u64,
        n: u16,
        ty: u8,
        instance: u8,
        mul: u16,
        count: u16,
        sample_us: u64,
        rate: f32,
    ) {
        let mut p = time.to_le_bytes().to_vec();
        p.extend_from_slice(&n.to_le_bytes());
        p.extend_from_slice(&[ty, instance]);
        p.extend_from_slice(&mul.to_le_bytes());
        p.extend_from_slice(&count.to_le_bytes());
        p.extend_from_slice(&sample_us.to_le_bytes());
        p.extend_from_slice(&rate.to_le_bytes());
        self.msg(ISBH, &p);
    }

    pub fn isbd(&mut self, time: u64, n: u16, seqno: u16, xyz: &[[i16; 32]; 3]) {
        let mut p = time.to_le_bytes().to_vec();
        p.extend_from_slice(&n.to_le_bytes());
        p.extend_from_slice(&seqno.to_le_bytes());
        for axis in xyz {
            for v in axis {
                p.extend_from_slice(&v.to_le_bytes());
            }
        }
        self.msg(ISBD, &p);
    }
}
