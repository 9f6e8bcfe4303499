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
}

/// Opens the viewer.
pub fn run(args: ViewArgs) -> anyhow::Result<()> {
    crate::app::run(args.frames, args.screenshot)
}
