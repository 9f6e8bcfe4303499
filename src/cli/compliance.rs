//! `tissue-sim compliance`: a material's surface compliance in its compact form, the form
//! `assets/compliance/` ships for objects A and B.

use std::path::PathBuf;
use std::time::Instant;

use clap::Args;

use super::args::ObjectArgs;
use super::output::summary;
use crate::sim::material_surface::compliance::DEFAULT_DIVISIONS;
use crate::sim::material_surface::compliance::SurfaceCompliance;
use crate::sim::material_surface::compliance::compact::STEP;
use crate::sim::material_surface::{computed, stderr_report};

/// The flags of `compliance`.
#[derive(Debug, Args)]
#[allow(missing_docs)] // flattened argument groups document their own fields
pub struct ComplianceArgs {
    #[command(flatten)]
    pub object: ObjectArgs,
    /// Output file: the compact form (`assets/compliance/A.bin` and `B.bin` are this command's
    /// for objects A and B).
    #[arg(long)]
    pub out: PathBuf,
    /// Where the full compliance is kept between runs (default: $XDG_CACHE_HOME/tissue-sim or
    /// ~/.cache/tissue-sim).
    #[arg(long)]
    pub cache: Option<PathBuf>,
}

/// Computes the compliance (never the shipped one: the cache folder's where it is kept), writes
/// its compact form and reads it back.
pub fn run(args: ComplianceArgs) -> anyhow::Result<()> {
    let material = args.object.material(None)?;
    crate::io::check_output(&args.out)?;
    let started = Instant::now();
    let dir = args.cache.clone().or_else(crate::io::cache_dir);
    let mut report = stderr_report();
    let full = computed(&material, dir.as_deref(), &mut |e| report.event(e))?;
    let bytes = full.to_compact(&material);
    let back = SurfaceCompliance::from_compact(&bytes, &material, DEFAULT_DIVISIONS)
        .map_err(|e| anyhow::anyhow!("the compact form written does not read back: it {e}"))?;
    let worst = full.largest_difference(&back);
    crate::io::write_atomic(&args.out, &bytes)?;
    summary(
        "compliance",
        &format!(
            "{}: {} written, {:.1} MB (the full compliance {:.1} MB); every entry within {:.1e} of its column's \
         largest ({:.1e} allowed), {:.1} s",
            material.name,
            args.out.display(),
            bytes.len() as f64 / 1e6,
            full.memory_bytes() as f64 / 1e6,
            worst,
            STEP / 2.0,
            started.elapsed().as_secs_f64()
        ),
    );
    Ok(())
}
