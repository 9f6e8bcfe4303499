//! `tissue-sim palpate`: a palpation map of one face (map.json, map.csv, map.png).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::bail;
use clap::Args;

use super::args::ObjectArgs;
use super::output::{progress_bar, say};
use crate::io::OutputDir;
use crate::sim::material_surface::{stderr_report, with_background};
use crate::sim::press::DEFAULT_RADIUS_M;
use crate::study::palpate::{FACES, Face, Palpation, PalpationMap, plot};

/// The flags of `palpate`.
#[derive(Debug, Args)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub struct PalpateArgs {
    #[command(flatten)]
    pub object: ObjectArgs,
    /// The face pressed: +z (the top), +x, -x, +y or -y (-z is clamped).
    #[arg(long, default_value = "+z", value_parser = FACES, allow_hyphen_values = true)]
    pub face: String,
    /// Probe radius, metres.
    #[arg(long, default_value_t = DEFAULT_RADIUS_M, allow_hyphen_values = true)]
    pub radius: f64,
    /// How deep each press goes, metres.
    #[arg(long, default_value_t = 0.004, allow_hyphen_values = true)]
    pub depth: f64,
    /// Points per side of the grid pressed (each in the middle of its cell).
    #[arg(long, default_value_t = 21, allow_hyphen_values = true)]
    pub grid: usize,
    /// Where map.json, map.csv and map.png are written.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Where the material's surface compliance is kept (default: $XDG_CACHE_HOME/tissue-sim, else
    /// ~/.cache/tissue-sim).
    #[arg(long, value_name = "DIR")]
    pub cache: Option<PathBuf>,
}

/// Runs `palpate`.
pub fn run(args: PalpateArgs) -> anyhow::Result<()> {
    let material = args.object.material_with_inclusions(None)?;
    let face = Face::parse(&args.face).map_err(anyhow::Error::msg)?;
    let palpation = Palpation { face, radius: args.radius, depth: args.depth, grid: args.grid };
    if let Err(why) = palpation.check() {
        bail!("{why}");
    }
    OutputDir::check_names(&args.out, &["map.json", "map.csv", "map.png"])?;
    let started = Instant::now();
    let dir = args.cache.clone().or_else(crate::io::cache_dir);
    let mut report = stderr_report();
    let (background, compliance) = with_background(&material, dir.as_deref(), &mut |e| report.event(e))?;
    let prepared = started.elapsed().as_secs_f64();
    let presses = palpation.grid * palpation.grid;
    let bar = progress_bar(2 * presses as u64, "presses");
    let pressing = Instant::now();
    let forces = palpation.forces(&compliance, &mut || bar.inc(1)).map_err(anyhow::Error::msg)?;
    let background_forces = if material.inclusions.is_empty() {
        bar.inc(presses as u64);
        forces.clone()
    } else {
        palpation.forces(&background, &mut || bar.inc(1)).map_err(anyhow::Error::msg)?
    };
    bar.finish_and_clear();
    let pressed = pressing.elapsed().as_secs_f64();
    let map = PalpationMap::new(&material, &palpation, forces, background_forces);
    let mut out = OutputDir::default();
    out.add("map.json", serde_json::to_vec_pretty(&map)?);
    out.add("map.csv", map.csv()?);
    out.add("map.png", plot::png(&map).map_err(anyhow::Error::msg)?);
    out.commit(&args.out)?;
    let range = |v: &[f64]| v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &f| (a.min(f), b.max(f)));
    let (low, high) = range(&map.forces);
    say(&format!(
        "{}: {n} x {n} presses on face {}, probe {} pressed {}: force {low:.3} to {high:.3} N",
        map.material,
        map.face,
        crate::io::length(args.radius),
        crate::io::length(args.depth),
        n = palpation.grid
    ))?;
    if let Some((peak, at)) = map.peak().filter(|_| !material.inclusions.is_empty()) {
        say(&format!(
            "contrast against the material without its inclusions: largest {:+.2} % at ({:.1}, {:.1}, {:.1}) mm; \
             beyond {:.0} % either way (felt) at {} of {presses} points",
            100.0 * peak,
            at[0] * 1e3,
            at[1] * 1e3,
            at[2] * 1e3,
            100.0 * map.felt_contrast,
            map.felt()
        ))?;
    }
    super::output::summary(
        "palpate",
        &format!(
            "surface compliance ready in {prepared:.1} s, presses {pressed:.2} s; wrote {}/map.json, map.csv, map.png",
            args.out.display()
        ),
    );
    Ok(())
}
