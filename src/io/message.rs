//! Numbers and messages as the user reads them: short numbers, one brief line.

/// A number as a message shows it, short: exactly as typed when it has at most six significant
/// digits (plain when moderate, `1e-300` in exponent form rather than three hundred zeros),
/// otherwise rounded to four significant digits in exponent form (`4.156e-4`).
pub fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let shortest = format!("{v:e}");
    let digits = shortest.split('e').next().unwrap_or("").chars().filter(char::is_ascii_digit).count();
    if digits > 6 {
        format!("{v:.3e}")
    } else if (1e-4..1e7).contains(&v.abs()) {
        format!("{v}")
    } else {
        shortest
    }
}

/// Longest quoted text a message repeats, characters.
const MAX_QUOTED_CHARS: usize = 60;

/// A message as one brief line: line breaks and runs of blanks become single spaces, and any
/// quoted text (between `"`, `'` or backquotes) longer than 60 characters is cut, saying
/// how long it was, so that a 100,000-character input comes back as a short error.
pub fn brief_line(message: &str) -> String {
    let mut words = String::with_capacity(message.len().min(4096));
    for w in message.split_whitespace() {
        if !words.is_empty() {
            words.push(' ');
        }
        words.push_str(w);
    }
    let mut out = String::with_capacity(words.len().min(4096));
    let mut rest = words.as_str();
    while let Some(start) = rest.find(['"', '\'', '`']) {
        let quote = rest[start..].chars().next().unwrap_or('"');
        let body = &rest[start + 1..];
        let Some(len) = body.find(quote) else { break };
        out.push_str(&rest[..=start]);
        let quoted = &body[..len];
        let chars = quoted.chars().count();
        if chars > MAX_QUOTED_CHARS {
            out.extend(quoted.chars().take(MAX_QUOTED_CHARS / 2));
            out.push_str(&format!("... ({chars} characters)"));
        } else {
            out.push_str(quoted);
        }
        out.push(quote);
        rest = &body[len + 1..];
    }
    out.push_str(rest);
    out
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    #[test]
    fn numbers_print_short() {
        assert_eq!(num(0.001), "0.001");
        assert_eq!(num(1e-4), "0.0001");
        assert_eq!(num(2.5), "2.5");
        assert_eq!(num(1e308), "1e308");
        assert_eq!(num(1e-300), "1e-300");
        assert_eq!(num(0.0004155926674608283), "4.156e-4");
        assert_eq!(num(-123456.789), "-1.235e5");
        assert_eq!(num(f64::NAN), "NaN");
        for v in [1e308, -1e-300, 1.0 / 3.0, 6.02e23, 5e-324] {
            assert!(num(v).len() <= 10, "{v}: {}", num(v));
        }
    }

    #[test]
    fn messages_are_brief_lines() {
        let long = "x".repeat(100_000);
        let m = brief_line(&format!("unknown object \"{long}\":\n  the presets   are A and B"));
        assert!(m.len() < 200, "{m}");
        assert!(m.starts_with("unknown object \"xxx") && m.ends_with("characters)\": the presets are A and B"), "{m}");
        assert_eq!(brief_line("a `b` 'c' \"d\" e"), "a `b` 'c' \"d\" e");
        assert_eq!(brief_line("it's \"open"), "it's \"open");
    }
}
