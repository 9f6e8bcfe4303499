//! `tissue-sim simulate`: a scripted sequence of tool actions, without rendering.

use std::path::PathBuf;

use anyhow::Context as _;
use clap::Args;

use crate::io::read_json;

/// The flags of `simulate`.
#[derive(Debug, Args)]
pub struct SimulateArgs {
    /// The script (JSON), see README. Presses the contact can resolve: probe radius 5 to 50 mm,
    /// depth at most 3/4 of the radius, starting on or outside the tissue's surface, moving into
    /// it, not into a clamped face.
    #[arg(long)]
    pub script: PathBuf,
    /// Output JSON file.
    #[arg(long)]
    pub out: PathBuf,
}

/// Runs the script and writes node positions and tool forces.
pub fn run(args: SimulateArgs) -> anyhow::Result<()> {
    crate::io::check_output(&args.out)?;
    let started = std::time::Instant::now();
    let s: crate::study::script::Script = read_json(&args.script)?;
    let folder = args.script.parent().unwrap_or(std::path::Path::new(""));
    let outcome =
        crate::study::script::run_from(&s, folder).with_context(|| format!("in {}", args.script.display()))?;
    outcome.check_finite()?;
    crate::io::write_json_compact(&args.out, &outcome)?;
    if let Some(r) = &outcome.replay {
        // A replay says whether it is the recording, and where it is not.
        let first = r.mismatches.first().map_or(String::new(), |m| format!("; first: {m}"));
        eprintln!(
            "replay: {} of {} recorded samples matched, {} differ (force relative L2 {}, force_n {}){first}",
            r.matched,
            r.recorded,
            r.mismatched,
            crate::io::num(r.relative_l2),
            crate::io::num(r.force_n_relative_l2)
        );
    }
    let simulated = outcome.events.last().map_or(0.0, |e| e.time_s);
    let mut line = format!(
        "{} actions of material {} ({}) written to {}: {:.2} s simulated in {:.1} s",
        outcome.events.len(),
        outcome.object,
        outcome.model.name(),
        args.out.display(),
        simulated,
        started.elapsed().as_secs_f64()
    );
    // The probe's last sample: a path's, else a press's (the later action).
    let path = outcome.force_path.last().map(|p| (p.action, p.force_n, p.depth_m, p.contact));
    let press = outcome.force_depth.last().map(|p| (p.action, p.force_n, p.depth_m, p.contact));
    if let Some((_, force, depth, contact)) = path.into_iter().chain(press).max_by_key(|p| p.0) {
        line.push_str(&format!(
            "; the probe's last force {force:.3} N at {} ({} contact)",
            crate::io::length(depth),
            contact.name()
        ));
    }
    if !outcome.blow_ups.is_empty() {
        line.push_str(&format!("; warning: {} blow-ups caught (see blow_ups)", outcome.blow_ups.len()));
    }
    super::output::summary("simulate", &line);
    Ok(())
}
