//! Printing: standard output that tolerates a closed pipe, and progress bars on a terminal.

/// Writes `text` and a newline to standard output ([`say_raw`]).
pub fn say(text: &str) -> anyhow::Result<()> {
    say_raw(&format!("{text}\n"))
}

/// Writes `text` to standard output; a reader that has gone away (a closed pipe, as with
/// `| head`) ends the output quietly instead of failing.
pub fn say_raw(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut stdout = std::io::stdout().lock();
    match stdout.write_all(text.as_bytes()).and_then(|()| stdout.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// A progress bar on a terminal (hidden otherwise) counting `len` `unit`.
pub fn progress_bar(len: u64, unit: &str) -> indicatif::ProgressBar {
    if !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template(&format!(
            "{{spinner}} {{bar:40}} {{pos}}/{{len}} {unit}, {{msg}} [{{elapsed}}]"
        ))
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}
