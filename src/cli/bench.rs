//! `tissue-sim bench`: the speed benchmark of the physics core.

use clap::Args;

use super::output::{say, say_raw};

/// The flags of `bench`.
#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Only the GPU's figures: its step alone and its 1 ms tick at 16^3, 32^3 and 64^3 against
    /// the CPU's (an error where no adapter computes).
    #[arg(long, conflicts_with = "moving")]
    pub gpu: bool,
    /// Only the viewer's 1 ms tick with the probe moving on the material's surface (pressing
    /// and sliding; the default tissue at 8^3 and 12^3, the corotational FEM at 8^3).
    #[arg(long)]
    pub moving: bool,
}

/// Runs the benchmark and prints its report.
pub fn run(args: BenchArgs) -> anyhow::Result<()> {
    if args.gpu {
        let gpu = crate::gpu::ComputeDevice::open()?;
        let material = crate::mechanics::material::Material::object_a();
        let mut said = crate::sim::material_surface::stderr_report();
        let surface = crate::sim::material_surface::MaterialSurface::load_or_compute(
            &material,
            crate::io::cache_dir().as_deref(),
            &mut |e| said.event(e),
        )?;
        let report = crate::study::bench::gpu::measure(&gpu, &surface)?;
        if args.json {
            say(&serde_json::to_string_pretty(&report)?)?
        } else {
            say_raw(&report.to_text())?
        }
        super::output::summary("bench", "the GPU step timed against the CPU (the report above)");
        return Ok(());
    }
    if args.moving {
        let ticks = crate::study::bench::moving::run()?;
        if args.json {
            say(&serde_json::to_string_pretty(&serde_json::json!({ "moving_probe_tick_s": ticks }))?)?;
        } else {
            say_raw(&crate::study::bench::moving::to_text(&ticks))?;
        }
        let worst = ticks.values().copied().fold(0.0, f64::max);
        super::output::summary(
            "bench",
            &format!("the moving probe's tick timed: the slowest {:.0} us of the 1 ms budget", worst * 1e6),
        );
        return Ok(());
    }
    let report = crate::study::bench::run()?;
    if args.json {
        say(&serde_json::to_string_pretty(&report)?)?
    } else {
        say_raw(&report.to_text())?
    }
    super::output::summary("bench", "the physics core timed (the report above; targets in docs/speed.md)");
    Ok(())
}
