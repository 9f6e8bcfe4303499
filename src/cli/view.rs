//! `tissue-sim view`: the interactive viewer.

use std::path::PathBuf;

use clap::Args;

/// The flags of `view`.
#[derive(Debug, Args)]
pub struct ViewArgs {
    /// Close after this many frames.
    #[arg(long)]
    pub frames: Option<u64>,
    /// After closing, save the final 3D view (offscreen, 960x540) as PNG.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// Start with this model: hex (the default tissue), shear, axis, fem-linear or
    /// fem-corotational.
    #[arg(long, value_parser = parse_model)]
    pub model: Option<crate::sim::Model>,
    /// Where the model's steps are computed.
    #[arg(long, value_parser = crate::cli::values::parser::<crate::gpu::Compute>(), default_value = "cpu")]
    pub compute: crate::gpu::Compute,
    /// Start with the probe pressed DEPTH into the top face at (X, Y), metres (for a
    /// screenshot): X and Y in 0..0.1, DEPTH in 0..0.02.
    #[arg(long, value_name = "X,Y,DEPTH", value_parser = parse_press)]
    pub press: Option<[f64; 3]>,
    /// Record what is done and write it to FILE as a `simulate` script that replays it, with the
    /// force samples shown under "recorded": when the viewer closes, on SIGINT or SIGTERM, and
    /// from the panel's "Save recording".
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// Start with this material file (TOML, or JSON by extension; inclusions and all) instead of
    /// object A: the lattice of its background's shipped tissue where there is one.
    #[arg(long, value_name = "FILE")]
    pub material: Option<PathBuf>,
}

fn parse_press(s: &str) -> Result<[f64; 3], String> {
    let v: Vec<f64> =
        s.split(',').map(|w| w.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|e| format!("{e}"))?;
    let [x, y, depth] = v[..] else {
        return Err(format!("expected X,Y,DEPTH (three numbers), got {} numbers", v.len()));
    };
    let side = crate::mechanics::grid::CUBE_SIDE_M;
    if !((0.0..=side).contains(&x) && (0.0..=side).contains(&y)) {
        return Err(format!("the point ({x}, {y}) is off the top face (0 to {side} m)"));
    }
    if !(depth > 0.0 && depth <= 0.02) {
        return Err(format!("depth {depth} m is out of range (0 to 0.02 m)"));
    }
    Ok([x, y, depth])
}

fn parse_model(s: &str) -> Result<crate::sim::Model, String> {
    crate::sim::Model::try_from(s.to_owned())
}

/// Opens the viewer.
pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    if let Some(path) = &args.record {
        crate::io::check_output(path)?;
    }
    // Read and checked before the window opens: bad input is a one-line error.
    if let Some(path) = &args.material {
        crate::mechanics::material::Material::from_file(path)?;
    }
    crate::app::run(crate::app::ViewOptions {
        frames: args.frames,
        screenshot: args.screenshot,
        model: args.model,
        compute: args.compute,
        press: args.press,
        record: args.record,
        material: args.material,
    })?;
    if crate::io::interrupted() {
        // Closed by SIGINT or SIGTERM, the recording written.
        std::process::exit(130);
    }
    Ok(())
}
