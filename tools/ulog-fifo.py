#!/usr/bin/env python3
"""A PX4 ULog file of a static six-axis IMU: sensor_gyro_fifo and sensor_accel_fifo at RATE Hz
(32 samples per message, int16 counts times their scale), and sensor_gyro / sensor_accel at 10 Hz
for the temperature, as PX4's logger writes them with SDLOG_PROFILE's raw FIFO bits.

    tools/ulog-fifo.py OUT SECONDS RATE SEED
"""
import struct
import sys

import numpy as np

out, seconds, rate, seed = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), int(sys.argv[4])
rng = np.random.default_rng(seed)
n = int(seconds * rate) // 32 * 32
dt_us = 1e6 / rate
gyro_scale, accel_scale = 1e-4, 1e-3  # rad/s and m/s^2 per count
gyro = rng.normal(0.0, 0.02, (n, 3)) + 0.001 * np.cumsum(rng.normal(0, 1e-3, (n, 3)), axis=0)
accel = rng.normal(0.0, 0.2, (n, 3)) + np.array([0.0, 0.0, 9.81])
counts = [np.clip(np.round(gyro / gyro_scale), -32768, 32767).astype('<i2'),
          np.clip(np.round(accel / accel_scale), -32768, 32767).astype('<i2')]

def msg(kind, payload):
    return struct.pack('<HB', len(payload), ord(kind)) + payload

fifo_fmt = ('uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float dt;'
            'float scale;int16_t[32] x;int16_t[32] y;int16_t[32] z;uint8_t samples;'
            'uint8_t[3] _padding0;')
sensor_fmt = ('uint64_t timestamp;uint64_t timestamp_sample;uint32_t device_id;float x;float y;'
              'float z;float temperature;uint32_t error_count;uint8_t[3] clip_counter;'
              'uint8_t samples;uint8_t[4] _padding0;')
with open(out, 'wb') as f:
    f.write(b'ULog\x01\x12\x35\x01' + struct.pack('<Q', 0))
    f.write(msg('B', bytes(40)))
    for name, fmt in [('sensor_gyro_fifo', fifo_fmt), ('sensor_accel_fifo', fifo_fmt),
                      ('sensor_gyro', sensor_fmt), ('sensor_accel', sensor_fmt)]:
        f.write(msg('F', f'{name}:{fmt}'.encode()))
    for msg_id, name in enumerate(['sensor_gyro_fifo', 'sensor_accel_fifo', 'sensor_gyro',
                                   'sensor_accel']):
        f.write(msg('A', struct.pack('<BH', 0, msg_id) + name.encode()))
    every = max(1, int(rate / 10 / 32))
    devices = (2359330, 2359331)
    chunks = []
    for k in range(n // 32):
        t = int(1e6 + (k * 32 + 31) * dt_us)
        for s, (scale, c) in enumerate(zip((gyro_scale, accel_scale), counts)):
            block = c[k * 32:(k + 1) * 32]
            payload = struct.pack('<QQIff', t + 50, t, devices[s], dt_us, scale)
            payload += block[:, 0].tobytes() + block[:, 1].tobytes() + block[:, 2].tobytes()
            payload += bytes([32])
            chunks.append(msg('D', struct.pack('<H', s) + payload))
        if k % every == 0:
            temperature = 30.0 + 10.0 * k / (n // 32)
            for s in range(2):
                payload = struct.pack('<QQIffff', t + 60, t, devices[s], 0.0, 0.0, 0.0,
                                      temperature) + struct.pack('<I', 0) + bytes([0, 0, 0, 32])
                chunks.append(msg('D', struct.pack('<H', 2 + s) + payload))
        if len(chunks) > 10000:
            f.write(b''.join(chunks))
            chunks = []
    f.write(b''.join(chunks))
