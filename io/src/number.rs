//! Numbers in text: timestamps converted to integer nanoseconds exactly, from the decimal
//! digits (not through a binary float), and readings as finite `f64`.

/// `text`, a decimal number (`12`, `-0.5`, `1.4e18`, `46536.397971133`, `1540822773.2470136`),
/// times `10^scale_exp`, as the nearest integer (ties away from zero). The digits are used
/// exactly: `0.0035` s → 3 500 000 ns, with no binary rounding, so sample spacings survive the
/// conversion. `None` if `text` is not a decimal number or the result does not fit an `i64`.
pub fn parse_scaled_integer(text: &str, scale_exp: i32) -> Option<i64> {
    parse_scaled(text, scale_exp).map(|(v, _)| v)
}

/// As [`parse_scaled_integer`], also saying whether the result is exact (no digits were
/// rounded away).
pub fn parse_scaled(text: &str, scale_exp: i32) -> Option<(i64, bool)> {
    // Integer nanoseconds (the common case): up to 19 digits accumulate in a u64 without
    // overflow (the one non-digit byte that ends the loop adds at most 255).
    if scale_exp == 0 && !text.is_empty() && text.len() <= 19 {
        let mut v: u64 = 0;
        if text.bytes().all(|b| {
            v = v * 10 + u64::from(b.wrapping_sub(b'0'));
            b.is_ascii_digit()
        }) {
            return Some((i64::try_from(v).ok()?, true));
        }
    }
    let (negative, rest) = match text.as_bytes().first()? {
        b'-' => (true, &text[1..]),
        b'+' => (false, &text[1..]),
        _ => (false, text),
    };
    let (mantissa_text, exponent) = match rest.find(['e', 'E']) {
        Some(i) => (&rest[..i], rest[i + 1..].parse::<i32>().ok()?),
        None => (rest, 0),
    };
    let (int_digits, frac_digits) = mantissa_text.split_once('.').unwrap_or((mantissa_text, ""));
    if int_digits.is_empty() && frac_digits.is_empty() {
        return None;
    }
    let mut mantissa: i128 = 0;
    let mut digits = 0usize;
    for b in int_digits.bytes().chain(frac_digits.bytes()) {
        if !b.is_ascii_digit() {
            return None;
        }
        if mantissa == 0 && b == b'0' {
            continue;
        }
        digits += 1;
        if digits > 36 {
            return None;
        }
        mantissa = mantissa * 10 + i128::from(b - b'0');
    }
    let shift = i64::from(exponent) + i64::from(scale_exp) - frac_digits.len() as i64;
    let (magnitude, exact) = scale(mantissa, shift)?;
    let value = if negative { -magnitude } else { magnitude };
    Some((i64::try_from(value).ok()?, exact))
}

/// `m · 10^shift` rounded to the nearest integer (ties away from zero), and whether that is
/// exact; `None` on overflow.
fn scale(m: i128, shift: i64) -> Option<(i128, bool)> {
    if m == 0 {
        return Some((0, true));
    }
    if shift >= 0 {
        let p = 10i128.checked_pow(u32::try_from(shift).ok()?)?;
        return Some((m.checked_mul(p)?, true));
    }
    if shift < -38 {
        return Some((0, false));
    }
    let p = 10i128.pow((-shift) as u32);
    let (q, r) = (m / p, m % p);
    Some((if 2 * r >= p { q + 1 } else { q }, r == 0))
}

/// `text` as a finite `f64`, or a message saying what it is instead.
pub fn parse_finite(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("value `{text}` is not finite")),
        Err(_) => Err(format!("`{text}` is not a number")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timestamps_keep_every_digit() {
        let ns = |t: &str, e: i32| parse_scaled_integer(t, e);
        assert_eq!(
            ns("1403715273262142976", 0),
            Some(1_403_715_273_262_142_976)
        );
        assert_eq!(
            ns("1.4037152732621430e18", 0),
            Some(1_403_715_273_262_143_000)
        );
        assert_eq!(ns("46536.397971133", 9), Some(46_536_397_971_133));
        assert_eq!(ns("1540822773.2470136", 9), Some(1_540_822_773_247_013_600));
        assert_eq!(ns("0.003500", 9), Some(3_500_000));
        assert_eq!(ns("-0.5", 9), Some(-500_000_000));
        assert_eq!(ns("+12", 6), Some(12_000_000));
        assert_eq!(ns("12.", 3), Some(12_000));
        assert_eq!(ns(".25", 3), Some(250));
        assert_eq!(ns("5E-1", 0), Some(1), "ties round away from zero");
        assert_eq!(ns("0.4999999999", 0), Some(0));
        assert_eq!(ns("1.0000000005", 9), Some(1_000_000_001));
        assert_eq!(ns("0.0", 9), Some(0));
        assert_eq!(
            parse_scaled("1403715273.262142976", 0),
            Some((1_403_715_273, false))
        );
        assert_eq!(
            parse_scaled("1403715273262142976.000", 0),
            Some((1_403_715_273_262_142_976, true))
        );
        // 0.1 s spaced rows stay exactly 1e8 ns apart (a binary product would not).
        for k in 0..1000u32 {
            let t = format!("{}.{}", k / 10, k % 10);
            assert_eq!(ns(&t, 9), Some(i64::from(k) * 100_000_000), "{t}");
        }
    }

    /// The integer fast path agrees with the general path (taken with a leading `+`) at the
    /// edges of `i64` and on digit strings of every length up to 20.
    #[test]
    fn integer_fast_path_agrees_with_the_general_path() {
        let mut cases: Vec<String> = [
            "0",
            "7",
            "0000000000000000001",
            "9223372036854775807",
            "9223372036854775808",
            "9999999999999999999",
            "18446744073709551615",
            "12a",
            "1-2",
            "1.5",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        for len in 1..=20 {
            x = x
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            cases.push(x.to_string().chars().cycle().take(len).collect());
        }
        for c in &cases {
            assert_eq!(parse_scaled(c, 0), parse_scaled(&format!("+{c}"), 0), "{c}");
        }
        assert_eq!(
            parse_scaled("9223372036854775807", 0),
            Some((i64::MAX, true))
        );
        assert_eq!(parse_scaled("9223372036854775808", 0), None);
    }

    #[test]
    fn not_numbers_and_overflow() {
        for bad in [
            "", "-", ".", "1.2.3", "1e", "abc", "1,5", "nan", "inf", "1e3x", "0x10",
        ] {
            assert_eq!(parse_scaled_integer(bad, 9), None, "{bad}");
        }
        assert_eq!(parse_scaled_integer("9.3e18", 0), None);
        assert_eq!(parse_scaled_integer("1e10", 9), None);
        assert_eq!(parse_scaled_integer("1e-400", 9), Some(0));
        assert_eq!(parse_scaled_integer("1e400", 0), None);
    }

    #[test]
    fn readings_must_be_finite() {
        assert_eq!(parse_finite(" 1.5".trim()), Ok(1.5));
        assert!(parse_finite("nan").unwrap_err().contains("not finite"));
        assert!(parse_finite("1e999").unwrap_err().contains("not finite"));
        assert!(parse_finite("x").unwrap_err().contains("not a number"));
    }
}
