//! What a scalar means: YAML 1.2's core schema, with booleans spelled
//! `true`/`false` only.
//!
//! A plain (unquoted) scalar is null (`~`, `null`, empty), a boolean
//! (`true`, `false`, in lower, title or upper case), an integer (decimal
//! without a leading zero, or `0x`/`0o`/`0b`, with single `_` between
//! digits), a float (`1.5`, `.5`, `2e-3`, `.inf`, `-.inf`, `.nan`; a
//! numeral too large for an `f64` is infinite) — or else a string. So blocks
//! named `y`, `n`, `on` or `off` stay strings, as a control engineer would
//! expect, and `0127` reads as the number 127. Quoted and block scalars are
//! always strings. The tags `!!str`, `!!null`, `!!bool`, `!!int` and
//! `!!float` ask for a type, as does `!` (a string); other tags are ignored.

use super::Kind;
use granit_parser::{ScalarStyle, Tag};

/// The core-schema tags a scalar may carry.
enum CoreTag {
    Str,
    Null,
    Bool,
    Int,
    Float,
}

fn core_tag(tag: &Tag) -> Option<CoreTag> {
    match (tag.handle(), tag.suffix()) {
        ("tag:yaml.org,2002:", "str") | ("", "!") => Some(CoreTag::Str),
        ("tag:yaml.org,2002:", "null") => Some(CoreTag::Null),
        ("tag:yaml.org,2002:", "bool") => Some(CoreTag::Bool),
        ("tag:yaml.org,2002:", "int") => Some(CoreTag::Int),
        ("tag:yaml.org,2002:", "float") => Some(CoreTag::Float),
        _ => None,
    }
}

/// The value of a scalar, or what was wrong with it (a tag that asks for
/// a type its text is not).
pub fn resolve(text: &str, style: ScalarStyle, tag: Option<&Tag>) -> Result<Kind, String> {
    let plain = style == ScalarStyle::Plain;
    match tag.and_then(core_tag) {
        Some(CoreTag::Str) => Ok(Kind::Str(text.to_string())),
        Some(CoreTag::Null) => Ok(Kind::Null),
        Some(CoreTag::Bool) => {
            boolean(text.trim()).map(Kind::Bool).ok_or_else(|| mismatch("!!bool", text, "a boolean"))
        }
        Some(CoreTag::Int) => integer(text.trim()).map(Kind::Num).ok_or_else(|| mismatch("!!int", text, "an integer")),
        Some(CoreTag::Float) => float(text.trim()).map(Kind::Num).ok_or_else(|| mismatch("!!float", text, "a number")),
        None if !plain => Ok(Kind::Str(text.to_string())),
        None => Ok(plain_scalar(text)),
    }
}

fn mismatch(tag: &str, text: &str, what: &str) -> String {
    format!("`{tag}` asks for {what}, and `{text}` is not one")
}

/// Whether a plain scalar's text is null.
pub fn is_null(text: &str) -> bool {
    matches!(text, "" | "~" | "null" | "Null" | "NULL")
}

fn plain_scalar(text: &str) -> Kind {
    if is_null(text) {
        return Kind::Null;
    }
    if let Some(b) = boolean(text) {
        return Kind::Bool(b);
    }
    match integer(text).or_else(|| float(text)) {
        Some(v) => Kind::Num(v),
        None => Kind::Str(text.to_string()),
    }
}

fn boolean(t: &str) -> Option<bool> {
    match t {
        "true" | "True" | "TRUE" => Some(true),
        "false" | "False" | "FALSE" => Some(false),
        _ => None,
    }
}

/// An integer within ±2⁶⁴ (as an `f64`); larger ones are read as floats.
fn integer(t: &str) -> Option<f64> {
    let (negative, digits) = match t.as_bytes().first() {
        Some(b'-') => (true, &t[1..]),
        Some(b'+') => (false, &t[1..]),
        _ => (false, t),
    };
    let (radix, body) = match digits.as_bytes() {
        [b'0', b'x' | b'X', ..] => (16, &digits[2..]),
        [b'0', b'o' | b'O', ..] => (8, &digits[2..]),
        [b'0', b'b' | b'B', ..] => (2, &digits[2..]),
        [b'0', _, ..] => return None, // `0127`: not an integer (it reads as a float)
        _ => (10, digits),
    };
    let magnitude = digits_value(body, radix)?;
    let value = if negative { -i128::from(magnitude) } else { i128::from(magnitude) };
    // The integers an i64 or a u64 holds.
    (i128::from(i64::MIN)..=i128::from(u64::MAX)).contains(&value).then_some(value as f64)
}

/// Digits in `radix`, each `_` between two digits; `None` if empty or overflowing.
fn digits_value(body: &str, radix: u32) -> Option<u64> {
    let bytes = body.as_bytes();
    let mut value: u64 = 0;
    let mut any = false;
    for (i, &b) in bytes.iter().enumerate() {
        if b == b'_' {
            if i == 0 || i + 1 == bytes.len() || bytes[i + 1] == b'_' {
                return None;
            }
            continue;
        }
        let d = char::from(b).to_digit(radix)?;
        value = value.checked_mul(u64::from(radix))?.checked_add(u64::from(d))?;
        any = true;
    }
    any.then_some(value)
}

/// `.inf`, `.nan` and numerals; words (`inf`, `nan`) stay strings.
fn float(t: &str) -> Option<f64> {
    let (negative, unsigned) = match t.as_bytes().first() {
        Some(b'-') => (true, &t[1..]),
        Some(b'+') => (false, &t[1..]),
        _ => (false, t),
    };
    match unsigned {
        ".nan" | ".NaN" | ".NAN" => return Some(f64::NAN),
        ".inf" | ".Inf" | ".INF" => return Some(if negative { f64::NEG_INFINITY } else { f64::INFINITY }),
        _ => {}
    }
    let v: f64 = t.parse().ok()?;
    // Rust also reads `inf`, `infinity` and `nan`; YAML keeps them strings.
    (v.is_finite() || unsigned.as_bytes().first().is_some_and(u8::is_ascii_digit)).then_some(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plain(t: &str) -> Kind {
        resolve(t, ScalarStyle::Plain, None).unwrap()
    }

    #[test]
    fn the_core_schema() {
        for t in ["", "~", "null", "NULL"] {
            assert_eq!(plain(t), Kind::Null, "{t:?}");
        }
        assert_eq!(plain("True"), Kind::Bool(true));
        for (t, v) in [
            ("0", 0.0),
            ("-12", -12.0),
            ("+7", 7.0),
            ("1_000", 1000.0),
            ("0x1F", 31.0),
            ("0o17", 15.0),
            ("0b101", 5.0),
            ("-0x10", -16.0),
            ("0127", 127.0),
            ("1.5", 1.5),
            (".5", 0.5),
            ("-2e-3", -2e-3),
            ("1e999", f64::INFINITY),
            ("-.inf", f64::NEG_INFINITY),
            ("18446744073709551616", 18446744073709551616.0),
        ] {
            assert_eq!(plain(t), Kind::Num(v), "{t:?}");
        }
        assert!(matches!(plain(".nan"), Kind::Num(v) if v.is_nan()));
        for t in ["y", "n", "on", "off", "yes", "inf", "nan", "1__0", "_1", "1_", "0x", "1e", "a1", "1.2.3", "0xG"] {
            assert_eq!(plain(t), Kind::Str(t.into()), "{t:?}");
        }
        assert_eq!(resolve("1", ScalarStyle::DoubleQuoted, None).unwrap(), Kind::Str("1".into()));
        assert_eq!(resolve("null", ScalarStyle::SingleQuoted, None).unwrap(), Kind::Str("null".into()));
    }

    #[test]
    fn tags_ask_for_a_type() {
        let core = |s: &str| Tag::new("tag:yaml.org,2002:", s);
        assert_eq!(resolve("1", ScalarStyle::Plain, Some(&core("str"))).unwrap(), Kind::Str("1".into()));
        assert_eq!(resolve("3", ScalarStyle::DoubleQuoted, Some(&core("float"))).unwrap(), Kind::Num(3.0));
        assert_eq!(resolve("x", ScalarStyle::Plain, Some(&core("null"))).unwrap(), Kind::Null);
        assert_eq!(resolve("7", ScalarStyle::Plain, Some(&Tag::new("!", "mine"))).unwrap(), Kind::Num(7.0));
        assert_eq!(resolve("7", ScalarStyle::Plain, Some(&Tag::new("", "!"))).unwrap(), Kind::Str("7".into()));
        let e = resolve("abc", ScalarStyle::Plain, Some(&core("int"))).unwrap_err();
        assert_eq!(e, "`!!int` asks for an integer, and `abc` is not one");
    }
}
