//! Numbers as text for the CSV outputs: the shortest decimal digits that read back to the same f64
//! (from `zmij`, several times faster than `core::fmt`'s Grisu/Dragon), laid out byte for byte as
//! `core::fmt` lays them out with `{}` (`Display`) and `{:e}` (`LowerExp`). Both find the shortest
//! digits that round-trip and, of those, the closest to the value; they differ only where two are
//! equally close (a tie: `core::fmt` takes the larger magnitude, zmij the even last digit, e.g.
//! 2⁻²⁵ = 2.98023223876953125e-8). A tie needs a value whose exact decimal expansion has at most 18
//! significant digits ([`exact_is_short`]); those few go to `core::fmt`. The tests compare the
//! bytes with `format!` on millions of values (random bit patterns, subnormals, powers of two and
//! ten, integers, short decimals, the neighbours of every threshold).

use std::io::Write;

/// The shortest round-trip digits of a finite, nonzero |v|: v = ±0.d₁d₂…dₙ × 10^`exp`, d₁ ≠ 0,
/// dₙ ≠ 0.
struct Digits {
    negative: bool,
    digits: [u8; 24],
    len: usize,
    exp: i32,
}

impl Digits {
    /// From zmij's text, which lays the same digits out its own way ("1.234e-7", "0.001234",
    /// "12340000000.0").
    fn of(text: &[u8]) -> Digits {
        let negative = text.first() == Some(&b'-');
        let text = &text[usize::from(negative)..];
        let (mantissa, exponent) = match exponent_at(text) {
            Some(at) => (&text[..at], parse_exponent(&text[at + 1..])),
            None => (text, 0),
        };
        let mut d = Digits { negative, digits: [0; 24], len: 0, exp: exponent };
        let mut before_point = true;
        for &b in mantissa {
            match b {
                b'.' => before_point = false,
                b'0' if d.len == 0 => d.exp -= i32::from(!before_point),
                _ => {
                    d.digits[d.len] = b;
                    d.len += 1;
                    d.exp += i32::from(before_point);
                }
            }
        }
        while d.len > 1 && d.digits[d.len - 1] == b'0' {
            d.len -= 1;
        }
        d
    }

    fn digits(&self) -> &[u8] {
        &self.digits[..self.len]
    }
}

/// Where zmij's text has its 'e': among the last five bytes ("e-324", "e+20", "e-7"), if anywhere.
fn exponent_at(text: &[u8]) -> Option<usize> {
    let from = text.len().saturating_sub(5);
    text[from..].iter().position(|&b| b == b'e').map(|at| from + at)
}

/// "+12", "-7" or "12" as an integer (zmij writes the exponent's sign).
fn parse_exponent(text: &[u8]) -> i32 {
    let (sign, digits) = match text.first() {
        Some(b'-') => (-1, &text[1..]),
        Some(b'+') => (1, &text[1..]),
        _ => (1, text),
    };
    sign * digits.iter().fold(0i32, |acc, &b| acc * 10 + i32::from(b - b'0'))
}

/// NaN, ±∞ and ±0 as `core::fmt` writes them, or `None` for a finite nonzero value.
fn special(v: f64, exp_form: bool) -> Option<&'static [u8]> {
    if v.is_nan() {
        Some(b"NaN")
    } else if v.is_infinite() {
        Some(if v > 0.0 { b"inf" } else { b"-inf" })
    } else if v == 0.0 {
        Some(match (v.is_sign_negative(), exp_form) {
            (false, false) => b"0",
            (true, false) => b"-0",
            (false, true) => b"0e0",
            (true, true) => b"-0e0",
        })
    } else {
        None
    }
}

/// Whether the exact decimal value of a finite, nonzero v has at most 18 significant digits, the
/// only values where two shortest candidates can be equally close (a tie at L ≤ 17 digits is a
/// value of exactly L + 1 digits, the last a 5). v = odd·2^e: for e < 0 its digits are those of
/// odd·5^(−e); for e ≥ 0 it is an integer, and below 2⁵³ one whose neighbours are at most 1 away,
/// so no two candidates can tie (the whole range from 2⁵³ up is counted as short).
fn exact_is_short(v: f64) -> bool {
    let bits = v.to_bits();
    let (biased, fraction) = ((bits >> 52) & 0x7ff, bits & ((1 << 52) - 1));
    let (mantissa, exp) = if biased == 0 { (fraction, -1074) } else { (fraction | 1 << 52, biased as i32 - 1075) };
    let zeros = mantissa.trailing_zeros();
    let (odd, e) = (mantissa >> zeros, exp + zeros as i32);
    if e >= 0 {
        return v.abs() >= 9_007_199_254_740_992.0;
    }
    // 5^25 < 10^18 ≤ 5^26: from e = −26 on odd·5^(−e) has more than 18 digits.
    e >= -25 && u128::from(odd) * 5u128.pow(e.unsigned_abs()) < 10u128.pow(18)
}

/// zmij's text of a finite, nonzero `v` that needs no tie-break; NaN, ±∞, ±0 and the values
/// [`exact_is_short`] are written whole instead (`None`).
fn start<'b>(out: &mut Vec<u8>, v: f64, exp_form: bool, buffer: &'b mut zmij::Buffer) -> Option<&'b [u8]> {
    if let Some(text) = special(v, exp_form) {
        out.extend_from_slice(text);
        return None;
    }
    if exact_is_short(v) {
        let written = if exp_form { write!(out, "{v:e}") } else { write!(out, "{v}") };
        written.expect("writing to a Vec cannot fail");
        return None;
    }
    Some(buffer.format_finite(v).as_bytes())
}

/// Appends `v` as `format!("{}", v)` writes it: plain decimal, no exponent, no ".0".
pub fn push_display(out: &mut Vec<u8>, v: f64, buffer: &mut zmij::Buffer) {
    let Some(text) = start(out, v, false, buffer) else { return };
    // zmij writes 1e-5 ≤ |v| < 1e16 in plain decimal ("0.001234", "12.34", "1230.0"): the same
    // text but for the ".0" of an integer (shortest digits never end in 0).
    if exponent_at(text).is_none() {
        return out.extend_from_slice(text.strip_suffix(b".0").unwrap_or(text));
    }
    let d = Digits::of(text);
    if d.negative {
        out.push(b'-');
    }
    let (digits, exp) = (d.digits(), d.exp);
    if exp <= 0 {
        out.extend_from_slice(b"0.");
        out.resize(out.len() + exp.unsigned_abs() as usize, b'0');
        out.extend_from_slice(digits);
    } else if (exp as usize) < digits.len() {
        let (int, frac) = digits.split_at(exp as usize);
        out.extend_from_slice(int);
        out.push(b'.');
        out.extend_from_slice(frac);
    } else {
        out.extend_from_slice(digits);
        out.resize(out.len() + exp as usize - digits.len(), b'0');
    }
}

/// Appends `v` as `format!("{:e}", v)` writes it: "d.ddde-N", "de20".
pub fn push_exp(out: &mut Vec<u8>, v: f64, buffer: &mut zmij::Buffer) {
    let Some(text) = start(out, v, true, buffer) else { return };
    // zmij's scientific form ("1.234e-7", "5e+20") differs only by the exponent's "+".
    if let Some(at) = exponent_at(text) {
        let (mantissa, exponent) = text.split_at(at + 1);
        out.extend_from_slice(mantissa);
        return out.extend_from_slice(exponent.strip_prefix(b"+").unwrap_or(exponent));
    }
    let d = Digits::of(text);
    if d.negative {
        out.push(b'-');
    }
    let digits = d.digits();
    out.push(digits[0]);
    if digits.len() > 1 {
        out.push(b'.');
        out.extend_from_slice(&digits[1..]);
    }
    write!(out, "e{}", d.exp - 1).expect("writing to a Vec cannot fail");
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both layouts of `v` against `core::fmt`'s.
    fn check(v: f64, buffer: &mut zmij::Buffer, out: &mut Vec<u8>) {
        out.clear();
        push_display(out, v, buffer);
        assert_eq!(std::str::from_utf8(out).unwrap(), format!("{v}"), "Display of {v:e} (bits {:#x})", v.to_bits());
        out.clear();
        push_exp(out, v, buffer);
        assert_eq!(std::str::from_utf8(out).unwrap(), format!("{v:e}"), "LowerExp of {v:e} (bits {:#x})", v.to_bits());
    }

    /// SplitMix64: a reproducible stream of bit patterns.
    fn bits(seed: u64) -> impl Iterator<Item = u64> {
        let mut state = seed;
        std::iter::repeat_with(move || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        })
    }

    #[test]
    fn special_values_and_thresholds_match_core_fmt() {
        let (mut buffer, mut out) = (zmij::Buffer::new(), Vec::new());
        let mut values = vec![
            0.0,
            -0.0,
            f64::NAN,
            -f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            f64::EPSILON,
            5e-324,
            -5e-324,
            f64::from_bits(0x000f_ffff_ffff_ffff), // the largest subnormal
            0.1,
            0.2,
            0.3,
            1.0 / 3.0,
            2.0 / 3.0,
            9007199254740993.0,
            123456789012345680.0,
        ];
        // Powers of two and ten over the whole range, and their neighbours (the ends of the
        // rounding intervals, where a shortest-digits algorithm errs first).
        let powers =
            (-1074..=1023).map(|k| 2f64.powi(k)).chain((-323..=308).map(|k| format!("1e{k}").parse().unwrap()));
        // The thresholds of the plain and scientific forms of signals.csv (1e-4, 1e15) and zmij's own.
        let thresholds = [1e-4, 1e15, 1e-5, 1e-6, 1e16, 1e12, 1e13];
        for v in powers.chain(thresholds) {
            let (up, down) = (f64::from_bits(v.to_bits() + 1), f64::from_bits(v.to_bits() - 1));
            values.extend([v, up, down, -v, -up, -down]);
        }
        for v in values {
            check(v, &mut buffer, &mut out);
        }
    }

    #[test]
    fn integers_decimals_and_subnormals_match_core_fmt() {
        let (mut buffer, mut out) = (zmij::Buffer::new(), Vec::new());
        for k in 0..100_000u64 {
            check(k as f64, &mut buffer, &mut out);
            check(k as f64 / 10.0, &mut buffer, &mut out);
            check(k as f64 * 1e-3, &mut buffer, &mut out);
            check((1u64 << 53) as f64 - k as f64, &mut buffer, &mut out);
            // Short exact decimals (ties of the shortest digits): k/4, k/1024, k·2⁻²⁵.
            check(k as f64 / 4.0, &mut buffer, &mut out);
            check(k as f64 / 1024.0, &mut buffer, &mut out);
            check(k as f64 * 2f64.powi(-25), &mut buffer, &mut out);
        }
        // Subnormals: random mantissas with a zero exponent field, and the smallest ones in turn.
        for (b, k) in bits(7).zip(0..200_000u64) {
            check(f64::from_bits(b & 0x800f_ffff_ffff_ffff), &mut buffer, &mut out);
            check(f64::from_bits(k + 1), &mut buffer, &mut out);
        }
    }

    /// `patterns` random bit patterns (exponents over the whole range), then `sized` values of the
    /// size signals.csv holds (|v| between 1e-12 and 1e12, 17 significant digits, either sign),
    /// each against `core::fmt`.
    fn check_random(seed: u64, patterns: usize, sized: usize) {
        let (mut buffer, mut out) = (zmij::Buffer::new(), Vec::new());
        for b in bits(seed).take(patterns) {
            check(f64::from_bits(b), &mut buffer, &mut out);
        }
        for (b, e) in bits(seed + 1).zip(bits(seed + 2)).take(sized) {
            let v = (b >> 11) as f64 / (1u64 << 53) as f64 * 10f64.powi((e % 25) as i32 - 12);
            check(if e & 1 == 0 { v } else { -v }, &mut buffer, &mut out);
        }
    }

    #[test]
    fn random_values_match_core_fmt() {
        check_random(1, 300_000, 1_000_000);
    }

    #[test]
    #[ignore = "about two minutes: 20 million random bit patterns and 20 million values of signal size"]
    fn many_more_random_values_match_core_fmt() {
        check_random(11, 20_000_000, 20_000_000);
    }
}
