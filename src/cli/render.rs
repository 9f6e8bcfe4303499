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
    let what = match &case {
        Some(id) => format!("{id}, the {} lattice's static answer", model.name()),
        None => "object A at rest".to_owned(),
    };
    let caption = format!("{what}; shape magnified x {}", crate::io::num(magnify));
    let colour_at = |t: f64| crate::render::gpu::ramp_srgb8(t as f32);
    let title = match colour {
        ColourMode::Displacement => Some("displacement (mm)"),
        ColourMode::Error => Some("lattice - FEM distance (mm)"),
        ColourMode::None => None,
    };
    // A map of all zeros (the cube at rest) has no scale to show.
    let bar = title.filter(|_| scene.scalar_max > 0.0).map(|t| crate::study::colour_bar::ColourBar {
        title: t.to_owned(),
        max: 1e3 * f64::from(scene.scalar_max),
        colour: &colour_at,
    });
    let bytes = crate::study::colour_bar::annotated_png(&png.rgba, (width, height), bar.as_ref(), &caption)
        .map_err(anyhow::Error::msg)?;
    write_atomic(&out, &bytes)?;
    super::output::summary(
        "render",
        &format!(
            "wrote {} ({}x{} and its colour bar and caption, adapter: {} / {:?})",
            out.display(),
            width,
            height,
            png.adapter,
            png.backend
        ),
    );
    Ok(())
}
