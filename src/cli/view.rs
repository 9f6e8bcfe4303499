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
    #[arg(long, value_enum, default_value = "cpu")]
    pub compute: crate::gpu::Compute,
}

fn parse_model(s: &str) -> Result<crate::sim::Model, String> {
    crate::sim::Model::try_from(s.to_owned())
}

/// Opens the viewer.
pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    crate::app::run(crate::app::ViewOptions {
        frames: args.frames,
        screenshot: args.screenshot,
        model: args.model,
        compute: args.compute,
    })
}
