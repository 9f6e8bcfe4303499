//! Layer 7, rendering of the tissue cube: the surface mesh and camera (CPU, no GPU types), the
//! wgpu renderer shared by the window and the offscreen path, headless rendering to PNG, and what
//! a static scene draws ([`scene`]). May use: gpu (the adapter a compute step shares), sim, mechanics, io.
//!
//! [`mesh`]: the surface mesh; [`camera`]: the orbit camera; [`gpu`]: the wgpu renderer;
//! [`offscreen`]: rendering to PNG.

pub mod camera;
pub mod gpu;
pub mod mesh;
pub mod offscreen;
pub mod scene;

use crate::mechanics::grid::Grid;
use gpu::LineVertex;

/// The grid's edges (pairs of lattice neighbours), for line overlays; build once per grid.
pub fn lattice_edges(grid: &Grid) -> Vec<(usize, usize)> {
    crate::mechanics::grid::axis_families().iter().flat_map(|f| grid.springs(*f)).collect()
}

/// Appends the `edges` for which `keep(a, b)` holds as line segments, while `out` has capacity.
pub fn push_edges(
    edges: &[(usize, usize)],
    x: &[[f32; 3]],
    colour: [f32; 4],
    keep: impl Fn(usize, usize) -> bool,
    out: &mut Vec<LineVertex>,
) {
    for &(a, b) in edges {
        if out.len() + 2 > out.capacity() {
            break;
        }
        if keep(a, b) {
            out.push(LineVertex { position: x[a], colour });
            out.push(LineVertex { position: x[b], colour });
        }
    }
}

/// Line segments outlining the nodes marked `fixed` (each edge between two fixed nodes).
pub fn fixed_outline(
    edges: &[(usize, usize)],
    x: &[[f32; 3]],
    fixed: &[bool],
    colour: [f32; 4],
    out: &mut Vec<LineVertex>,
) {
    push_edges(edges, x, colour, |a, b| fixed[a] && fixed[b], out);
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
