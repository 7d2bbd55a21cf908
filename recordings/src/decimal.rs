//! Plain decimals (`-0.015574726745215603`, `9.536274327859523`: a sign, digits, a point and
//! at most 19 digits after it, as loggers print samples) read to the nearest `f64`, eight
//! digits at a time: the cells of a CSV record are nearly all of this form. The value is the
//! one the standard library's parser gives (the nearest, ties to even): the digits exactly in a
//! `u64`, then the Eisel-Lemire product with a 128-bit power of five (as the standard library
//! and `fast-float2` compute it). Any other text is `None`: the caller's general parser reads
//! it.

/// Digits after the point read here at most (10^19 is the largest power of ten in a `u64`).
const MOST: usize = 19;

/// `10^k` for `k` up to [`MOST`].
const POW10: [u64; MOST + 1] = {
    let mut p = [1u64; MOST + 1];
    let mut k = 1;
    while k <= MOST {
        p[k] = p[k - 1] * 10;
        k += 1;
    }
    p
};

/// `5^-k` for `k` from 1 to [`MOST`] as Eisel-Lemire takes it: `floor(2^(z + 127) / 5^k) + 1`
/// with `2^z` the least power of two above `5^k`, in `[2^127, 2^128)`, as (high, low) words.
const INVERSE_POW5: [(u64, u64); MOST + 1] = {
    let mut t = [(0u64, 0u64); MOST + 1];
    let mut k = 1;
    while k <= MOST {
        let mut p = 1u64;
        let mut i = 0;
        while i < k {
            p *= 5;
            i += 1;
        }
        let z = 64 - p.leading_zeros();
        // Long division of 2^(z + 127) by p, bit by bit (the quotient's 128 bits fit).
        let mut quotient = 0u128;
        let mut rest = 0u64;
        let mut bit = z + 127;
        loop {
            rest = rest * 2 + (bit == z + 127) as u64;
            quotient <<= 1;
            if rest >= p {
                rest -= p;
                quotient |= 1;
            }
            if bit == 0 {
                break;
            }
            bit -= 1;
        }
        // p lies strictly between 2^(z-1) and 2^z: the quotient lies in [2^127, 2^128 - 2^128/p),
        // and one more still fits.
        let c = quotient + 1;
        t[k] = ((c >> 64) as u64, c as u64);
        k += 1;
    }
    t
};

/// The value of eight ASCII digits in `word` (little-endian: the first digit in the lowest
/// byte), or `None` when a byte is no digit.
#[inline]
fn eight(word: u64) -> Option<u64> {
    // Each byte, 0x30 to 0x39: neither 0x46 more nor 0x30 less sets its high bit (the lowest
    // byte that is no digit is caught before a carry or borrow from it reaches another).
    if (word.wrapping_add(0x4646_4646_4646_4646) | word.wrapping_sub(0x3030_3030_3030_3030))
        & 0x8080_8080_8080_8080
        != 0
    {
        return None;
    }
    let v = word - 0x3030_3030_3030_3030;
    let v = v * 10 + (v >> 8);
    let v = ((v & 0x0000_00ff_0000_00ff).wrapping_mul(0x000f_4240_0000_0064))
        .wrapping_add(((v >> 16) & 0x0000_00ff_0000_00ff).wrapping_mul(0x0000_2710_0000_0001))
        >> 32;
    Some(v & 0xffff_ffff)
}

/// The value of `digits` (at most [`MOST`], all ASCII digits), or `None` when one is not a
/// digit: eight at a time, the last few from the eight bytes that end with them, zeros put in
/// place of the digits before them.
#[inline]
fn value(digits: &[u8]) -> Option<u64> {
    let n = digits.len();
    if n < 8 {
        return digits.iter().try_fold(0u64, |v, &b| {
            let d = b.wrapping_sub(b'0');
            (d < 10).then_some(v * 10 + u64::from(d))
        });
    }
    let word = |at: usize| {
        let mut w = [0u8; 8];
        w.copy_from_slice(&digits[at..at + 8]);
        u64::from_le_bytes(w)
    };
    let mut v = eight(word(0))?;
    let mut at = 8;
    if n >= 16 {
        v = v * 100_000_000 + eight(word(8))?;
        at = 16;
    }
    let r = n - at;
    if r > 0 {
        // The last r digits are the word's high bytes; leading zeros below them.
        let last = word(n - 8) & (u64::MAX << (8 * (8 - r)));
        let zeros = 0x3030_3030_3030_3030u64 >> (8 * r);
        v = v * POW10[r] + eight(last | zeros)?;
    }
    Some(v)
}

/// `text` as the nearest `f64` when it is a plain decimal read here: an optional sign, at
/// least one digit, a point and 1 to [`MOST`] digits whose value with the digits before the
/// point fits a `u64`; `None` for anything else (which may still be a number).
#[inline]
pub(crate) fn plain(text: &[u8]) -> Option<f64> {
    // The sign without a branch: it is as often there as not.
    let negative = text.first() == Some(&b'-');
    let s = &text[usize::from(negative)..];
    let s = match s {
        [b'+', rest @ ..] if !negative => rest,
        _ => s,
    };
    let point = s.iter().position(|&b| b == b'.')?;
    let (whole, fraction) = (&s[..point], &s[point + 1..]);
    if whole.is_empty() || whole.len() > MOST || fraction.is_empty() || fraction.len() > MOST {
        return None;
    }
    let f = fraction.len();
    let w = value(whole)?
        .checked_mul(POW10[f])?
        .checked_add(value(fraction)?)?;
    // The product serves every w (Clinger's exact division too would, below 2^53, but a branch
    // between the two goes wrong as often as right).
    let magnitude = if w == 0 { 0.0 } else { eisel_lemire(w, f)? };
    Some(f64::from_bits(
        magnitude.to_bits() | u64::from(negative) << 63,
    ))
}

/// `w / 10^f` (`w` above 0, `f` from 1 to [`MOST`]) to the nearest `f64`, by the Eisel-Lemire
/// product of `w` and `5^-f` (exact enough for every such `w` and `f`: its doubtful case, a
/// product's low word all ones, decides only for `f` beyond 27).
#[inline]
fn eisel_lemire(w: u64, f: usize) -> Option<f64> {
    const EXPLICIT: i32 = 52;
    const MINIMUM_EXPONENT: i32 = -1023;
    let q = -(f as i32);
    let lz = w.leading_zeros();
    let w = w << lz;
    let (high5, low5) = *INVERSE_POW5.get(f)?;
    let full = |a: u64, b: u64| {
        let r = u128::from(a) * u128::from(b);
        (r as u64, (r >> 64) as u64)
    };
    // The product's high 128 bits, the second word only where the first leaves the 55 bits
    // needed in doubt.
    let (mut lo, mut hi) = full(w, high5);
    let precision_mask = u64::MAX >> (EXPLICIT + 3);
    if hi & precision_mask == precision_mask {
        let (_, second) = full(w, low5);
        lo = lo.wrapping_add(second);
        if second > lo {
            hi += 1;
        }
    }
    let upper = (hi >> 63) as i32;
    let shift = upper + 64 - EXPLICIT - 3;
    let mut mantissa = hi >> shift;
    let mut power2 =
        ((q.wrapping_mul(152_170 + 65_536) >> 16) + 63) + upper - lz as i32 - MINIMUM_EXPONENT;
    if power2 <= 0 {
        // Subnormal: never for a whole number above 0 over at most 10^19.
        return None;
    }
    // Exactly halfway (possible only for q from -4 up): ties go to the even mantissa.
    if lo <= 1 && q >= -4 && mantissa & 3 == 1 && (mantissa << shift) == hi {
        mantissa &= !1;
    }
    mantissa += mantissa & 1;
    mantissa >>= 1;
    if mantissa >= 2 << EXPLICIT {
        mantissa = 1 << EXPLICIT;
        power2 += 1;
    }
    mantissa &= !(1 << EXPLICIT);
    if power2 >= 0x7ff {
        return None;
    }
    Some(f64::from_bits(mantissa | (power2 as u64) << EXPLICIT))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The table's entries are those of the published Eisel-Lemire tables (`fast-float2`'s,
    /// the standard library's).
    #[test]
    fn inverse_powers_of_five_are_the_published_ones() {
        assert_eq!(
            INVERSE_POW5[1],
            (0xcccc_cccc_cccc_cccc, 0xcccc_cccc_cccc_cccd)
        );
        assert_eq!(
            INVERSE_POW5[2],
            (0xa3d7_0a3d_70a3_d70a, 0x3d70_a3d7_0a3d_70a4)
        );
        assert_eq!(
            INVERSE_POW5[10],
            (0xdbe6_fece_bded_d5be, 0xb573_440e_5a88_4d1c)
        );
        assert_eq!(
            INVERSE_POW5[19],
            (0xec1e_4a7d_b695_61a5, 0x2b31_e9e3_d06c_32e6)
        );
    }

    /// `plain` against the standard library: the same bits where it answers.
    fn agrees(text: &str) -> bool {
        let got = plain(text.as_bytes());
        if let Some(v) = got {
            assert_eq!(
                Some(v.to_bits()),
                text.parse::<f64>().ok().map(f64::to_bits),
                "{text}"
            );
        }
        got.is_some()
    }

    /// Whether the digits of a plain decimal fit what is read here: at most 19 after the point,
    /// and all of them, as one integer, a `u64`.
    fn fits(text: &str) -> bool {
        let digits: String = text.chars().filter(char::is_ascii_digit).collect();
        let places = text.split_once('.').map_or(99, |(_, f)| f.len());
        places <= MOST
            && digits
                .parse::<u128>()
                .is_ok_and(|v| v <= u128::from(u64::MAX))
    }

    /// Random plain decimals of every length read here and beyond (leading zeros, signs,
    /// values past a u64), and texts that are almost plain decimals: the same values as the
    /// standard library's parser wherever they are read here, and those that are read are most.
    #[test]
    fn plain_decimals_read_as_the_standard_library_reads_them() {
        let mut next = crate::xorshift(0x9e37_79b9_7f4a_7c15);
        let mut text = String::new();
        let mut read = 0;
        let cases = 1_000_000;
        for _ in 0..cases {
            text.clear();
            match next() % 4 {
                0 => text.push('-'),
                1 if next().is_multiple_of(4) => text.push('+'),
                _ => {}
            }
            let whole = 1 + next() % 21;
            let fraction = next() % 23;
            // Leading zeros often, as in 0.0155...
            let zeros = if next().is_multiple_of(2) {
                next() % (whole + 1)
            } else {
                0
            };
            for i in 0..whole {
                let d = if i < zeros { 0 } else { next() % 10 };
                text.push(char::from(b'0' + d as u8));
            }
            if fraction > 0 || next().is_multiple_of(8) {
                text.push('.');
            }
            for _ in 0..fraction {
                text.push(char::from(b'0' + (next() % 10) as u8));
            }
            // Now and then a character that is no digit, anywhere.
            if next().is_multiple_of(16) {
                let at = (next() % (text.len() as u64 + 1)) as usize;
                let junk = b"e.-+ x/:\x7f"[(next() % 9) as usize];
                text.insert(at, char::from(junk));
            }
            read += usize::from(agrees(&text));
        }
        assert!(read > cases / 3, "only {read} read here");
    }

    /// The shortest decimals of random doubles from 1e-7 to 1e9, as loggers print them (each
    /// read here whenever its digits fit).
    #[test]
    fn printed_doubles_come_back() {
        let mut next = crate::xorshift(0x0123_4567_89ab_cdef);
        for _ in 0..1_000_000 {
            let unit = (next() >> 11) as f64 / (1u64 << 53) as f64;
            let v =
                10f64.powf(-7.0 + 16.0 * unit) * if next().is_multiple_of(2) { 1.0 } else { -1.0 };
            let text = format!("{v}");
            let text = if text.contains('.') {
                text
            } else {
                text + ".0"
            };
            assert_eq!(agrees(&text), fits(&text), "{text}");
            assert!(agrees(&format!("{v:.17}")) || v.abs() >= 10.0);
        }
    }

    /// Decimals exactly halfway between two doubles (ties to the even one) and a unit in
    /// the last digit either side, above 2^49: where the product's rounding is decided.
    #[test]
    fn halfway_decimals_round_to_even() {
        let mut next = crate::xorshift(0x5555_aaaa_3333_cccc);
        for _ in 0..200_000 {
            // A double's spacing in [2^(52-s), 2^(53-s)) is 2^-s; halfway is 2^-(s+1) past it.
            let s = next() % 4;
            let k = next() % (1 << (52 - s));
            let base = (1u64 << (52 - s)) + k;
            // base + 2^-(s+1) in decimal: s + 1 places.
            let places = (s + 1) as usize;
            let half = 5u64.pow(s as u32 + 1);
            let tail = |d: i64| format!("{:0places$}", (half as i64 + d) as u64);
            for d in [-1i64, 0, 1] {
                for extra in ["", "0", "00"] {
                    let text = format!("{base}.{}{extra}", tail(d));
                    assert_eq!(agrees(&text), fits(&text), "{text}");
                }
            }
            // And the odd integers above 2^53, halfway between even neighbours.
            let odd = (1u64 << 53) + 2 * (next() % (1 << 40)) + 1;
            assert!(agrees(&format!("{odd}.0")));
            assert!(agrees(&format!("-{odd}.00")));
        }
    }
}
