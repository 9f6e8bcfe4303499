//! Rendering of the tissue cube: the surface mesh and camera (CPU, no GPU types), the wgpu
//! renderer shared by the window and the offscreen path, and headless rendering to PNG.

pub mod camera;
pub mod gpu;
pub mod mesh;
pub mod offscreen;

use crate::grid::Grid;
use gpu::LineVertex;

/// Line segments outlining the nodes marked `fixed` (each grid edge between two fixed nodes).
pub fn fixed_outline(grid: &Grid, x: &[[f32; 3]], fixed: &[bool], colour: [f32; 4], out: &mut Vec<LineVertex>) {
    for fam in crate::grid::axis_families() {
        for (a, b) in grid.springs(fam) {
            if fixed[a] && fixed[b] {
                out.push(LineVertex { position: x[a], colour });
                out.push(LineVertex { position: x[b], colour });
            }
        }
    }
}

/// Normalises `values` to [0, 1] by `max` (or their own maximum when `max` is `None`); returns the
/// scale used.
pub fn normalise(values: &mut [f32], max: Option<f32>) -> f32 {
    let m = max.unwrap_or_else(|| values.iter().copied().fold(0.0, f32::max)).max(f32::MIN_POSITIVE);
    for v in values.iter_mut() {
        *v /= m;
    }
    m
}
