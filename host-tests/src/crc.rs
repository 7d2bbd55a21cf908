//! CRC-32 (IEEE) one bit at a time, independent of the library's nibble table: the tests'
//! reference for the persisted records' checksums.

/// CRC-32 (IEEE, reflected, `0xEDB88320`) of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 == 1 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// Writes the CRC of `record[..len - 4]` into its last four bytes: an intact record of
/// whatever the bytes say.
///
/// # Panics
///
/// If `record` is shorter than four bytes.
pub fn reseal(record: &mut [u8]) {
    let n = record.len() - 4;
    let crc = crc32(&record[..n]);
    record[n..].copy_from_slice(&crc.to_le_bytes());
}
