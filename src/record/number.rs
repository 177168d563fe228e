//! Numbers as ctlgraph's CSV files show them: the shortest decimal text
//! that reads back to the same f64, so values survive the round trip —
//! plain from 1e-4 up to 1e15 in magnitude (Rust's `{}`), in exponent
//! form outside that (`{:e}`), `NaN`, `inf` and `-inf` as Rust spells them.
//!
//! The text is the standard library's, to the byte (tested over millions
//! of numbers below), but not made by it: the shortest digits come from
//! `ryu` (Adams, "Ryū: fast float-to-string conversion", PLDI 2018), which
//! finds the same shortest, closest digits as the standard library's
//! Grisu/Dragon4 — except where two are equally close, which ryu breaks to
//! the even digit and the standard library upwards ([`upper_tie`]) — and
//! are laid out here. Through `fmt`, a 20 000-row run's
//! CSV took longer to write than the run took to simulate (most of
//! `ctlgraph run --out`'s wall time); this path is several times faster.

/// An f64 in the CSV form of the module's doc, for `format!` and friends.
pub struct Number(pub f64);

impl std::fmt::Display for Number {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut text = Vec::with_capacity(MAX_LEN);
        push_number(&mut text, self.0);
        // Only ASCII is written.
        f.write_str(std::str::from_utf8(&text).map_err(|_| std::fmt::Error)?)
    }
}

/// The longest text [`push_number`] writes: a sign, 17 significant digits
/// and, at most, "0.000" before them or a point and "e-324" around them.
pub(super) const MAX_LEN: usize = 25;

/// Appends `v`'s text (the module's doc) to `out`.
pub(super) fn push_number(out: &mut Vec<u8>, v: f64) {
    if v == 0.0 || !v.is_finite() {
        // Rust's spellings: "0", "-0", "NaN", "inf", "-inf".
        let text = match v {
            f64::INFINITY => "inf",
            f64::NEG_INFINITY => "-inf",
            _ if v.is_nan() => "NaN",
            _ if v.is_sign_negative() => "-0",
            _ => "0",
        };
        out.extend_from_slice(text.as_bytes());
        return;
    }
    let mut ryu = ryu::Buffer::new();
    let (mut digits, mut exponent) = shortest_digits(ryu.format_finite(v.abs()).as_bytes());
    if upper_tie(v.abs(), &digits, exponent) {
        exponent += digits.round_up();
    }
    if v < 0.0 {
        out.push(b'-');
    }
    if (1e-4..1e15).contains(&v.abs()) {
        plain(out, &digits, exponent);
    } else {
        scientific(out, &digits, exponent);
    }
}

/// Up to 17 significant digits (ASCII, no leading or trailing zeros) and
/// the power of ten of the first one.
struct Digits {
    bytes: [u8; 17],
    len: usize,
}

impl std::ops::Deref for Digits {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        &self.bytes[..self.len]
    }
}

impl Digits {
    /// The next number of as many digits (…129 → …13, 999 → 1); returns 1
    /// when the first digit's power of ten went up.
    fn round_up(&mut self) -> i32 {
        let mut k = self.len;
        while k > 0 && self.bytes[k - 1] == b'9' {
            k -= 1;
        }
        if k == 0 {
            (self.bytes[0], self.len) = (b'1', 1);
            return 1;
        }
        self.bytes[k - 1] += 1;
        self.len = k;
        0
    }
}

/// Whether `v` (positive, finite) lies exactly halfway between `digits`
/// (first digit at 10^`exponent`) and the next number of as many digits.
/// Both then read back to `v`; ryu writes the even one, the standard
/// library the upper one.
///
/// With v = m·2^q, m odd, and the halfway point M·10^p = M·5^p·2^p, where
/// M = 10·digits + 5 is odd, the two are equal only if q = p and
/// m = M·5^p (p ≥ 0) or m·5^−p = M (p < 0); M < 10^18 < 2^60 bounds
/// |p| by 25, so most numbers are ruled out by their exponent alone.
fn upper_tie(v: f64, digits: &[u8], exponent: i32) -> bool {
    let bits = v.to_bits();
    let (fraction, biased) = (bits & ((1 << 52) - 1), (bits >> 52) as i32);
    let (mut m, mut q) = if biased == 0 { (fraction, -1074) } else { (fraction | 1 << 52, biased - 1075) };
    let zeros = m.trailing_zeros();
    (m, q) = (m >> zeros, q + zeros as i32);
    let p = exponent - digits.len() as i32;
    if q != p || !(-25..=25).contains(&p) {
        return false;
    }
    let halfway = digits.iter().fold(0u128, |n, &c| n * 10 + u128::from(c - b'0')) * 10 + 5;
    let fives = 5u128.pow(p.unsigned_abs());
    if p >= 0 { u128::from(m) == halfway * fives } else { u128::from(m) * fives == halfway }
}

/// The significant digits of ryu's text of a positive finite number
/// ("123.45", "0.001", "1.0", "1e-7", "1.5e300") and the power of ten of
/// the first.
fn shortest_digits(text: &[u8]) -> (Digits, i32) {
    let (mantissa, power) = match text.iter().position(|&c| c == b'e') {
        Some(e) => (&text[..e], parse_exponent(&text[e + 1..])),
        None => (text, 0),
    };
    let point = mantissa.iter().position(|&c| c == b'.').unwrap_or(mantissa.len());
    let mut digits = Digits { bytes: [0; 17], len: 0 };
    let mut first = None;
    for (i, &c) in mantissa.iter().enumerate() {
        if c == b'.' || (digits.len == 0 && c == b'0') || digits.len == digits.bytes.len() {
            continue;
        }
        // The power of ten of the digit at i: ones just before the point.
        first.get_or_insert(if i < point { point as i32 - i as i32 - 1 } else { point as i32 - i as i32 });
        digits.bytes[digits.len] = c;
        digits.len += 1;
    }
    while digits.len > 1 && digits.bytes[digits.len - 1] == b'0' {
        digits.len -= 1;
    }
    (digits, first.unwrap_or(0) + power)
}

fn parse_exponent(text: &[u8]) -> i32 {
    let (negative, digits) = match text.split_first() {
        Some((b'-', rest)) => (true, rest),
        _ => (false, text),
    };
    let magnitude = digits.iter().fold(0i32, |n, &c| n * 10 + i32::from(c - b'0'));
    if negative { -magnitude } else { magnitude }
}

/// `{}`'s form: 1234.5, 0.00012, 100000.
fn plain(out: &mut Vec<u8>, digits: &[u8], exponent: i32) {
    if exponent < 0 {
        out.extend_from_slice(b"0.");
        out.extend(std::iter::repeat_n(b'0', (-exponent - 1) as usize));
        out.extend_from_slice(digits);
        return;
    }
    let whole = exponent as usize + 1;
    if digits.len() <= whole {
        out.extend_from_slice(digits);
        out.extend(std::iter::repeat_n(b'0', whole - digits.len()));
    } else {
        out.extend_from_slice(&digits[..whole]);
        out.push(b'.');
        out.extend_from_slice(&digits[whole..]);
    }
}

/// `{:e}`'s form: 1e-5, 1.25e20.
fn scientific(out: &mut Vec<u8>, digits: &[u8], exponent: i32) {
    out.push(digits[0]);
    if digits.len() > 1 {
        out.push(b'.');
        out.extend_from_slice(&digits[1..]);
    }
    out.push(b'e');
    if exponent < 0 {
        out.push(b'-');
    }
    let mut text = [0u8; 3];
    let mut n = exponent.unsigned_abs();
    let mut len = 0;
    loop {
        text[2 - len] = b'0' + (n % 10) as u8;
        len += 1;
        n /= 10;
        if n == 0 {
            break;
        }
    }
    out.extend_from_slice(&text[3 - len..]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The text the CSV files had before this module: the standard library's.
    fn by_fmt(v: f64) -> String {
        if v == 0.0 || (1e-4..1e15).contains(&v.abs()) || !v.is_finite() { format!("{v}") } else { format!("{v:e}") }
    }

    fn ours(v: f64) -> String {
        let mut text = Vec::new();
        push_number(&mut text, v);
        assert!(text.len() <= MAX_LEN, "{v:e}: {} bytes", text.len());
        String::from_utf8(text).expect("ASCII")
    }

    #[test]
    fn the_edges_read_as_the_standard_library_writes_them() {
        let edges = [
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
            f64::MAX,
            -f64::MAX,
            f64::EPSILON,
            5e-324,
            -5e-324,
            1e-4,
            1e15,
            1.0,
            0.1,
            0.30000000000000004,
            123456789012345.6,
            999999999999999.9,
            1e-5,
            -2.5e-300,
            1.7976931348623157e308,
        ];
        for v in edges {
            for w in [v, v.next_up(), v.next_down()] {
                assert_eq!(ours(w), by_fmt(w), "bits {:#x}", w.to_bits());
                if w.is_finite() {
                    assert_eq!(ours(w).parse::<f64>().expect("reads back").to_bits(), w.to_bits());
                }
            }
        }
        // 1 308 548 795 726 862.25 exactly, halfway between two shortest
        // candidates: the upper one.
        assert_eq!(Number(f64::from_bits(0x4312_9879_088f_f039)).to_string(), "1.3085487957268623e15");
        assert_eq!(Number(-1.5e-7).to_string(), "-1.5e-7");
        assert_eq!(Number(100000.0).to_string(), "100000");
        assert_eq!(Number(0.00012).to_string(), "0.00012");
    }

    /// Two million bit patterns (every exponent, subnormals included) and a
    /// million decimals of a few digits — the values a run records, such
    /// as 0.0001 steps — from a fixed seed (splitmix64).
    #[test]
    fn millions_of_numbers_read_as_the_standard_library_writes_them() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            z ^ (z >> 31)
        };
        for _ in 0..2_000_000 {
            let v = f64::from_bits(next());
            assert_eq!(ours(v), by_fmt(v), "bits {:#x}", v.to_bits());
        }
        for _ in 0..1_000_000 {
            let (mantissa, power) = ((next() % 100_000) as f64, (next() % 40) as i32 - 20);
            let v = mantissa * 10f64.powi(power);
            assert_eq!(ours(v), by_fmt(v), "bits {:#x}", v.to_bits());
        }
        // Where ties are: few binary digits after the point (m·2^q with
        // q near 0), at every power of ten the two forms meet.
        for _ in 0..1_000_000 {
            let (m, q) = (next() >> (11 + next() % 40), (next() % 51) as i32 - 25);
            let v = m as f64 * 2f64.powi(q);
            assert_eq!(ours(v), by_fmt(v), "bits {:#x}", v.to_bits());
        }
    }
}
