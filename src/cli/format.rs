//! Number formatting for reports.

/// `x` with `sig` significant digits, fixed-point for ordinary magnitudes and
/// scientific otherwise (like C's `%g`).
pub(crate) fn g(x: f64, sig: usize) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let e = x.abs().log10().floor() as i32;
    if (-4..6).contains(&e) {
        let decimals = (sig as i32 - 1 - e).max(0) as usize;
        let s = format!("{x:.decimals$}");
        if s.contains('.') {
            s.trim_end_matches('0').trim_end_matches('.').to_string()
        } else {
            s
        }
    } else {
        format!("{x:.prec$e}", prec = sig.saturating_sub(1))
    }
}

/// A duration in microseconds, readable.
pub(crate) fn micros(d: std::time::Duration) -> String {
    let us = d.as_secs_f64() * 1e6;
    if us < 1000.0 {
        format!("{us:.2} µs")
    } else {
        format!("{:.3} ms", us / 1000.0)
    }
}

#[cfg(test)]
mod tests {
    use super::g;

    #[test]
    fn formats_like_percent_g() {
        assert_eq!(g(72.5, 7), "72.5");
        assert_eq!(g(-4.828427124746, 7), "-4.828427");
        assert_eq!(g(1.5e-12, 3), "1.50e-12");
        assert_eq!(g(0.0115, 4), "0.0115");
    }
}
