//! Printing: standard output that tolerates a closed pipe, progress bars on a terminal, and the
//! process set up before any command.

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

/// The command's closing line on standard error: what it wrote, the figure that matters and any
/// warning (`fem: ...`); nothing with `--quiet`.
pub fn summary(command: &str, text: &str) {
    crate::io::progress(&format!("{command}: {text}"));
}

/// The summary of a command that wrote a displacement file: `what` ("9 clamped cases of material
/// A"), where, the largest displacement of any case and the time since `started`.
pub fn cases_summary(
    command: &str,
    what: &str,
    file: &crate::mechanics::displacement_file::DisplacementFile,
    out: &std::path::Path,
    started: std::time::Instant,
) {
    let largest = file
        .cases
        .iter()
        .flat_map(|c| &c.displacements)
        .map(|u| (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]).sqrt())
        .fold(0.0, f64::max);
    summary(
        command,
        &format!(
            "{what} at {}^3 written to {}; largest displacement {}, {:.1} s",
            file.nodes_per_axis,
            out.display(),
            crate::io::length(largest),
            started.elapsed().as_secs_f64()
        ),
    );
}

/// A progress bar on a terminal (hidden otherwise, and with `--quiet`) counting `len` `unit`.
pub fn progress_bar(len: u64, unit: &str) -> indicatif::ProgressBar {
    if crate::io::quiet() || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
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

/// Sets the process up before any command runs (while it is the only thread):
/// - where `XDG_RUNTIME_DIR` is unset, points it at the temporary directory, so that the
///   Wayland probe of the Vulkan and GL drivers finds no display quietly instead of printing
///   "XDG_RUNTIME_DIR is invalid or not set" on every render;
/// - SIGINT and SIGTERM remove the temporary outputs still being written
///   ([`crate::io::remove_pending`]) and exit with status 130, unless the running command takes the
///   first one itself ([`crate::io::on_interrupt`]: the viewer writes its recording and closes).
pub fn prepare_process() {
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        // SAFETY: called first thing in `main`, before any other thread exists (the signal
        // handler's is started just below), so nothing reads the environment concurrently.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", std::env::temp_dir()) };
    }
    let _ = ctrlc::set_handler(|| {
        if !crate::io::interrupt() {
            crate::io::remove_pending();
            std::process::exit(130);
        }
    });
}
