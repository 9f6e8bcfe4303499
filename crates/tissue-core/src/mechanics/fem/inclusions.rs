//! Inclusions in the uniform-grid FEM (the real-time models and the same-mesh reference): each
//! element an inclusion meets gets the stiffness it contains, as a change `Delta K_e` on top of
//! the background's element matrix that the stencil applies.
//!
//! The rule for an element the inclusion's surface cuts: `Delta K_e = int_{element & sphere} B^T
//! (C_in - C_bg) B dV`. On an axis-aligned box, `B^T C B` is a polynomial of degree at most two
//! in each natural coordinate, so it equals its interpolant on the 27 nodes `{-1, 0, 1}^3` and the
//! integral is `sum_g w_g B(xi_g)^T (C_in - C_bg) B(xi_g)` with `w_g` the integral of node `g`'s
//! Lagrange polynomial over the part of the element inside the sphere. Those weights are
//! integrated exactly along x (the sphere's chord) and by a two-point Gauss rule on each of
//! [`CUT_ROWS`] strips along y and z; an element the sphere fills, or misses, comes out exact.
//! With [`CUT_ROWS`] = 64, doubling the strips changes `Delta K_e` of a cut element of the
//! paper's grid by about 1e-4 of its largest entry (the test below).

use nalgebra::Matrix6;

use super::element::{ElementStiffness, box_strain_displacement};
use crate::mechanics::grid::Grid;
use crate::mechanics::inclusion::Inclusion;
use crate::mechanics::material::Material;

/// Strips per axis (y and z) over which a cut element's Lagrange weights are integrated.
pub const CUT_ROWS: usize = 64;

/// `int_{[lo, lo + sides] & sphere} B^T dc B dV` of the box (hex8, metres) for a sphere of
/// `centre` and `radius`, `rows` strips along y and z ([`CUT_ROWS`]).
pub fn sphere_change(
    dc: &Matrix6<f64>,
    centre: [f64; 3],
    radius: f64,
    lo: [f64; 3],
    sides: [f64; 3],
    rows: usize,
) -> ElementStiffness {
    // The three Lagrange polynomials on {-1, 0, 1} and their antiderivatives.
    let lagrange = |t: f64| [0.5 * t * (t - 1.0), 1.0 - t * t, 0.5 * t * (t + 1.0)];
    let integral = |t: f64| [t * t * t / 6.0 - t * t / 4.0, t - t * t * t / 3.0, t * t * t / 6.0 + t * t / 4.0];
    let g = 1.0 / 3f64.sqrt();
    let n = rows as f64;
    // Natural coordinate and Lagrange values of each Gauss point of the strips, weight 1/n each.
    let points: Vec<(f64, [f64; 3])> = (0..rows)
        .flat_map(|i| [-g, g].map(|s| -1.0 + (2.0 * i as f64 + 1.0 + s) / n))
        .map(|t| (t, lagrange(t)))
        .collect();
    let to_x = |d: usize, t: f64| lo[d] + 0.5 * sides[d] * (t + 1.0);
    let mut w = [0.0; 27];
    for (zeta, lz) in &points {
        let dz = to_x(2, *zeta) - centre[2];
        for (eta, ly) in &points {
            let dy = to_x(1, *eta) - centre[1];
            let q = radius * radius - dy * dy - dz * dz;
            if q <= 0.0 {
                continue;
            }
            let to_xi = |x: f64| (2.0 * (x - lo[0]) / sides[0] - 1.0).clamp(-1.0, 1.0);
            let (a, b) = (to_xi(centre[0] - q.sqrt()), to_xi(centre[0] + q.sqrt()));
            if b <= a {
                continue;
            }
            let (ia, ib) = (integral(a), integral(b));
            for cz in 0..3 {
                for cy in 0..3 {
                    let yz = ly[cy] * lz[cz] / (n * n);
                    for cx in 0..3 {
                        w[cx + 3 * cy + 9 * cz] += (ib[cx] - ia[cx]) * yz;
                    }
                }
            }
        }
    }
    let det_j = 0.125 * sides[0] * sides[1] * sides[2];
    let mut ke = ElementStiffness::zeros();
    for (node, &weight) in w.iter().enumerate() {
        if weight == 0.0 {
            continue;
        }
        let xi = [node % 3, (node / 3) % 3, node / 9].map(|c| c as f64 - 1.0);
        let b = box_strain_displacement(xi, sides);
        ke += b.transpose() * (dc * b) * (weight * det_j);
    }
    (ke + ke.transpose()) * 0.5
}

/// One element of the grid an inclusion meets: its index (`i + m (j + m k)`), nodes (spec
/// order) and `Delta K_e`.
#[derive(Debug, Clone)]
pub struct PatchedElement {
    /// Element index.
    pub index: usize,
    /// Its nodes.
    pub nodes: [usize; 8],
    /// Its stiffness less the background's.
    pub delta: ElementStiffness,
}

/// The elements of `grid` that `material`'s inclusions meet, with their `Delta K_e` (empty for a
/// homogeneous material).
pub fn patch(grid: &Grid, material: &Material) -> Vec<PatchedElement> {
    let (m, h) = (grid.n() - 1, grid.h());
    let mut out = Vec::new();
    for (index, nodes) in grid.elements().enumerate() {
        let ijk = [index % m, (index / m) % m, index / (m * m)];
        let lo = ijk.map(|i| i as f64 * h);
        let hi = lo.map(|x| x + h);
        let mut delta = ElementStiffness::zeros();
        let mut met = false;
        for inclusion in &material.inclusions {
            if inclusion.meets_box(lo, hi) == Some(false) {
                continue;
            }
            met = true;
            delta += change(inclusion, &material.stiffness, lo, h);
        }
        if met {
            out.push(PatchedElement { index, nodes, delta });
        }
    }
    out
}

fn change(inclusion: &Inclusion, background: &Matrix6<f64>, lo: [f64; 3], h: f64) -> ElementStiffness {
    let dc = inclusion.stiffness - background;
    if inclusion.meets_box(lo, lo.map(|x| x + h)) == Some(true) {
        return super::element::hex8_box_stiffness(&dc, [h; 3]);
    }
    sphere_change(&dc, inclusion.centre, inclusion.radius, lo, [h; 3], CUT_ROWS)
}

/// `out += Delta K u` over the patched elements (interleaved dofs). Allocates nothing.
pub fn add_product(patch: &[PatchedElement], u: &[f64], out: &mut [f64]) {
    for e in patch {
        let ue: [f64; 24] = std::array::from_fn(|l| u[3 * e.nodes[l / 3] + l % 3]);
        for (a, &p) in e.nodes.iter().enumerate() {
            for c in 0..3 {
                let row = 3 * a + c;
                out[3 * p + c] += (0..24).map(|l| e.delta[(row, l)] * ue[l]).sum::<f64>();
            }
        }
    }
}

/// [`add_product`] on component-wise arrays (`u[c][node]`). Allocates nothing.
pub fn add_product_components(patch: &[PatchedElement], u: &[Vec<f64>; 3], out: &mut [Vec<f64>; 3]) {
    for e in patch {
        let ue: [f64; 24] = std::array::from_fn(|l| u[l % 3][e.nodes[l / 3]]);
        for (a, &p) in e.nodes.iter().enumerate() {
            for c in 0..3 {
                let row = 3 * a + c;
                out[c][p] += (0..24).map(|l| e.delta[(row, l)] * ue[l]).sum::<f64>();
            }
        }
    }
}

/// [`add_product_components`] on `f32` arrays, each element's product summed in `f64`.
/// Allocates nothing.
pub fn add_product_components_f32(patch: &[PatchedElement], u: &[Vec<f32>; 3], out: &mut [Vec<f32>; 3]) {
    for e in patch {
        let ue: [f64; 24] = std::array::from_fn(|l| f64::from(u[l % 3][e.nodes[l / 3]]));
        for (a, &p) in e.nodes.iter().enumerate() {
            for c in 0..3 {
                let row = 3 * a + c;
                out[c][p] += (0..24).map(|l| e.delta[(row, l)] * ue[l]).sum::<f64>() as f32;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::fem::element::{hex8_box_stiffness, hex8_box_stiffness_varying};

    #[test]
    fn a_sphere_that_fills_or_misses_the_element_is_exact_and_a_cut_converges() {
        let c = Material::object_a().stiffness;
        let dc = c * 4.0;
        let (lo, sides) = ([0.02, 0.03, 0.04], [0.1 / 7.0; 3]);
        let whole = hex8_box_stiffness(&dc, sides);
        let filled = sphere_change(&dc, [0.027, 0.037, 0.047], 0.05, lo, sides, 8);
        assert!((filled - whole).abs().max() < 1e-12 * whole.abs().max());
        assert_eq!(sphere_change(&dc, [0.08, 0.08, 0.08], 0.005, lo, sides, 8).abs().max(), 0.0);
        // A sphere cutting the element: converged in the strips, and the sub-cell rule agrees.
        let (centre, radius) = ([0.025, 0.031, 0.05], 0.008);
        let cut = sphere_change(&dc, centre, radius, lo, sides, CUT_ROWS);
        let finer = sphere_change(&dc, centre, radius, lo, sides, 4 * CUT_ROWS);
        assert!((cut - finer).abs().max() < 3e-4 * cut.abs().max(), "{}", (cut - finer).abs().max() / cut.abs().max());
        let c_in = c * 5.0;
        let inside = |x: [f64; 3]| (0..3).map(|a| (x[a] - centre[a]).powi(2)).sum::<f64>() < radius * radius;
        let sub = hex8_box_stiffness_varying(|x| if inside(x) { &c_in } else { &c }, lo, sides, 24)
            - hex8_box_stiffness(&c, sides);
        assert!((cut - sub).abs().max() < 0.02 * cut.abs().max(), "{}", (cut - sub).abs().max() / cut.abs().max());
    }

    #[test]
    fn the_patch_product_is_the_assembled_change() {
        let grid = Grid::new(5).unwrap();
        let mut material = Material::object_b();
        material.inclusions.push(Inclusion {
            centre: [0.05, 0.06, 0.07],
            radius: 0.012,
            stiffness: material.stiffness * 3.0,
        });
        let patch = patch(&grid, &material);
        assert!(!patch.is_empty() && patch.len() < 27);
        let dofs = 3 * grid.num_nodes();
        let u: Vec<f64> = (0..dofs).map(|d| ((d * 37 % 11) as f64 - 5.0) * 1e-4).collect();
        let mut out = vec![0.0; dofs];
        add_product(&patch, &u, &mut out);
        let split =
            |v: &[f64]| -> [Vec<f64>; 3] { std::array::from_fn(|c| v.iter().skip(c).step_by(3).copied().collect()) };
        let mut by_components = split(&vec![0.0; dofs]);
        add_product_components(&patch, &split(&u), &mut by_components);
        for d in 0..dofs {
            assert!((by_components[d % 3][d / 3] - out[d]).abs() <= 1e-12 * out[d].abs().max(1e-9));
        }
        // The lump is stiffer: positive energy.
        let energy: f64 = u.iter().zip(&out).map(|(a, b)| a * b).sum();
        assert!(energy > 0.0);
    }
}
