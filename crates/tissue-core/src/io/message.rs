//! Numbers and messages as the user reads them: short numbers, one brief line.

/// A number as a message shows it, short: exactly as typed when it has at most six significant
/// digits, otherwise rounded to four (`4.9` for 4.9000000001, `11.3` for 11.29999); plain when
/// moderate (1e-4 to 1e7), else in exponent form (`1e-300` rather than three hundred zeros,
/// `4.156e-4`).
pub fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let shortest = format!("{v:e}");
    let digits = shortest.split('e').next().unwrap_or("").chars().filter(char::is_ascii_digit).count();
    let shown = if digits > 6 { format!("{v:.3e}").parse().unwrap_or(v) } else { v };
    if (1e-4..1e7).contains(&shown.abs()) { format!("{shown}") } else { format!("{shown:e}") }
}

/// A length in metres as a person reads it: millimetres (`4.9 mm`, `11.3 mm`) from 0.1 mm up,
/// micrometres below (`1 um`, `12 um`), four significant digits at most ([`num`]).
///
/// ```
/// assert_eq!(tissue_core::io::length(0.0049), "4.9 mm");
/// assert_eq!(tissue_core::io::length(1e-6), "1 um");
/// ```
pub fn length(m: f64) -> String {
    if m != 0.0 && m.abs() < 1e-4 && m.is_finite() {
        format!("{} um", num(round4(m * 1e6)))
    } else {
        format!("{} mm", num(round4(m * 1e3)))
    }
}

/// `v` to four significant digits (as is where not finite or zero).
fn round4(v: f64) -> f64 {
    if v == 0.0 || !v.is_finite() {
        return v;
    }
    format!("{v:.3e}").parse().unwrap_or(v)
}

/// Longest quoted text a message repeats, characters.
const MAX_QUOTED_CHARS: usize = 60;
/// Longest message line, characters.
const MAX_LINE_CHARS: usize = 400;

/// A word that is a long numeral (`1000...0`, `-0.000...1`, with trailing punctuation) in short
/// form ([`num`]); any other word as it is.
fn short_numeral(word: &str) -> String {
    let body = word.trim_end_matches([',', ';', ':', ')', '.']);
    let (number, tail) = word.split_at(body.len());
    match number.parse::<f64>() {
        Ok(v) if number.len() > 16 && number.bytes().all(|b| b.is_ascii_digit() || b"+-.eE".contains(&b)) => {
            format!("{}{tail}", num(v))
        }
        _ => word.to_owned(),
    }
}

/// A message as one brief line: line breaks and runs of blanks become single spaces; any text
/// quoted between `"` or backquotes (an escaped `\"` does not close it) longer than 60 characters
/// is cut, saying how long it was; and the line itself is cut at 400 characters. A
/// 100,000-character input comes back as a short error.
pub fn brief_line(message: &str) -> String {
    let words: Vec<String> = message.split_whitespace().map(short_numeral).collect();
    let line = words.join(" ");
    let mut out = String::with_capacity(line.len().min(4 * MAX_LINE_CHARS));
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        out.push(c);
        if c != '"' && c != '`' {
            continue;
        }
        let mut quoted = String::new();
        let mut closed = false;
        while let Some(q) = chars.next() {
            if q == '\\' {
                quoted.push(q);
                if let Some(next) = chars.next() {
                    quoted.push(next);
                }
                continue;
            }
            if q == c {
                closed = true;
                break;
            }
            quoted.push(q);
        }
        let count = quoted.chars().count();
        if count > MAX_QUOTED_CHARS {
            out.extend(quoted.chars().take(MAX_QUOTED_CHARS / 2));
            out.push_str(&format!("... ({count} characters)"));
        } else {
            out.push_str(&quoted);
        }
        if closed {
            out.push(c);
        }
    }
    let count = out.chars().count();
    if count > MAX_LINE_CHARS {
        let mut cut: String = out.chars().take(MAX_LINE_CHARS - 40).collect();
        cut.push_str(&format!("... ({count} characters in all)"));
        return cut;
    }
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
        assert_eq!(num(0.0004155926674608283), "0.0004156");
        assert_eq!(num(0.00004155926674608283), "4.156e-5");
        assert_eq!(num(-123456.789), "-123500");
        assert_eq!(num(4.9000000001), "4.9");
        assert_eq!(num(11.299999999), "11.3");
        assert_eq!(num(1.23456789e-7), "1.235e-7");
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
        // Apostrophes far apart are prose, not a quotation.
        let prose = format!("the paper's lattice {}keeps the paper's d", "word ".repeat(20));
        assert_eq!(brief_line(&prose), prose);
        // An escaped quote does not end a quotation; an unclosed one is still cut; so is the line.
        let escaped = brief_line(&format!("object \"a\\\"{long}\": no"));
        assert!(escaped.len() < 200 && escaped.ends_with("characters)\": no"), "{escaped}");
        assert!(brief_line(&format!("x \"{long}")).len() < 200);
        assert!(brief_line(&"ab ".repeat(50_000)).chars().count() <= 400);
        assert_eq!(brief_line("é \"ü\" ß"), "é \"ü\" ß");
        // Long numerals, wherever they come from, in short form.
        let huge = format!("got {}, and {}.", 1e308, -1e-300);
        assert_eq!(brief_line(&huge), "got 1e308, and -1e-300.");
        assert_eq!(brief_line("at 0.0001 s, 12345 nodes"), "at 0.0001 s, 12345 nodes");
    }
}

/// Whether progress and summaries on standard error are silenced (the command line's `--quiet`).
static QUIET: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Silences (or not) the progress lines and summaries this process writes on standard error
/// ([`progress`]); warnings and errors are written all the same.
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, std::sync::atomic::Ordering::Relaxed);
}

/// Whether [`set_quiet`] silenced progress and summaries.
pub fn quiet() -> bool {
    QUIET.load(std::sync::atomic::Ordering::Relaxed)
}

/// Writes a line of progress (or a summary) on standard error, unless [`set_quiet`].
pub fn progress(line: &str) {
    if !quiet() {
        eprintln!("{line}");
    }
}
