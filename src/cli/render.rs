//! `tissue-sim render`: the cube drawn offscreen to a PNG.

use std::path::PathBuf;

use clap::Args;

use crate::io::write_atomic;
use crate::mechanics::msm::Topology;
use crate::render::scene::{self, ColourMode, StaticScene};

/// The flags of `render`.
#[derive(Debug, Args)]
pub struct RenderArgs {
    /// Output PNG file.
    #[arg(long)]
    pub out: PathBuf,
    /// Image width, pixels.
    #[arg(long, default_value_t = 1280, allow_hyphen_values = true)]
    pub width: u32,
    /// Image height, pixels.
    #[arg(long, default_value_t = 720, allow_hyphen_values = true)]
    pub height: u32,
    /// A benchmark case to show in static equilibrium, e.g. A_clamped_ax1_F10 (default: object A at rest).
    #[arg(long)]
    pub case: Option<String>,
    /// Colour map: none, displacement magnitude, or MSM-vs-FEM error.
    #[arg(long, value_parser = crate::cli::values::parser::<ColourMode>(), default_value = "displacement")]
    pub colour: ColourMode,
    /// MSM: the default hex-element tissue, the shear-spring lattice or the paper's axis springs.
    #[arg(long, value_parser = crate::cli::values::parser::<Topology>(), default_value = "hex")]
    pub model: Topology,
    /// Displacement magnification of the drawn shape.
    #[arg(long, default_value_t = 1.0, allow_hyphen_values = true)]
    pub magnify: f64,
}

/// Renders the scene and writes the PNG.
pub fn run(args: RenderArgs) -> anyhow::Result<()> {
    let RenderArgs { out, width, height, case, colour, model, magnify } = args;
    crate::io::check_output(&out)?;
    scene::check_magnify(magnify)?;
    scene::check_image_size(width, height)?;
    let scene = StaticScene::new(case.as_deref(), model, colour, magnify)?;
    let png = scene.render_png(width, height)?;
    write_atomic(&out, &png.bytes)?;
    super::output::summary(
        "render",
        &format!("wrote {} ({}x{}, adapter: {} / {:?})", out.display(), width, height, png.adapter, png.backend),
    );
    Ok(())
}
