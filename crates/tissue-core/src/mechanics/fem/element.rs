//! The trilinear 8-node hexahedron (hex8 / Q1) on an axis-aligned cube, full 2x2x2 Gauss rule.

use nalgebra::{Matrix6, SMatrix};

/// A 24 x 24 element stiffness matrix; dof `3 a + c` is component `c` of local node `a`.
pub type ElementStiffness = SMatrix<f64, 24, 24>;

/// Natural coordinates of the 8 nodes, in the spec's element node order.
pub const NODE_SIGNS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];

/// The side of each node (spec order) along each axis: 1 on the high side (`NODE_SIGNS` +1), 0
/// on the low; also the node's lattice offset from its element's lowest node.
pub const NODE_SIDES: [[usize; 3]; 8] = {
    let mut sides = [[0; 3]; 8];
    let mut a = 0;
    while a < 8 {
        let mut c = 0;
        while c < 3 {
            sides[a][c] = (NODE_SIGNS[a][c] > 0.0) as usize;
            c += 1;
        }
        a += 1;
    }
    sides
};

/// Strain-displacement matrix `B` (Voigt order 11, 22, 33, 23, 13, 12, engineering shear) at
/// natural point `xi` of a cube of side `h`.
pub fn strain_displacement(xi: [f64; 3], h: f64) -> SMatrix<f64, 6, 24> {
    box_strain_displacement(xi, [h; 3])
}

/// [`strain_displacement`] of an axis-aligned box of sides `sides` (x, y, z).
pub fn box_strain_displacement(xi: [f64; 3], sides: [f64; 3]) -> SMatrix<f64, 6, 24> {
    let mut b = SMatrix::<f64, 6, 24>::zeros();
    // x = x0 + h/2 (xi + 1): d/dx = (2/h) d/dxi.
    let scale = sides.map(|h| 2.0 / h);
    for (a, s) in NODE_SIGNS.iter().enumerate() {
        let f = |d: usize| 1.0 + s[d] * xi[d];
        let dx = scale[0] * 0.125 * s[0] * f(1) * f(2);
        let dy = scale[1] * 0.125 * s[1] * f(0) * f(2);
        let dz = scale[2] * 0.125 * s[2] * f(0) * f(1);
        let (cx, cy, cz) = (3 * a, 3 * a + 1, 3 * a + 2);
        b[(0, cx)] = dx;
        b[(1, cy)] = dy;
        b[(2, cz)] = dz;
        b[(3, cy)] = dz; // gamma_23 = du_y/dz + du_z/dy
        b[(3, cz)] = dy;
        b[(4, cx)] = dz; // gamma_13 = du_x/dz + du_z/dx
        b[(4, cz)] = dx;
        b[(5, cx)] = dy; // gamma_12 = du_x/dy + du_y/dx
        b[(5, cy)] = dx;
    }
    b
}

/// Element stiffness `K_e = sum_g B^T C B det(J) w_g` of a cube of side `h` with material
/// stiffness `c`, 2x2x2 Gauss points at `+-1/sqrt(3)` (exact for this element shape).
pub fn hex8_stiffness(c: &Matrix6<f64>, h: f64) -> ElementStiffness {
    hex8_box_stiffness(c, [h; 3])
}

/// [`hex8_stiffness`] of an axis-aligned box of sides `sides` (x, y, z), metres: the same rule,
/// exact for this shape too.
pub fn hex8_box_stiffness(c: &Matrix6<f64>, sides: [f64; 3]) -> ElementStiffness {
    let g = 1.0 / 3f64.sqrt();
    let det_j = 0.125 * sides[0] * sides[1] * sides[2];
    let mut ke = ElementStiffness::zeros();
    for &sx in &[-g, g] {
        for &sy in &[-g, g] {
            for &sz in &[-g, g] {
                let b = box_strain_displacement([sx, sy, sz], sides);
                ke += b.transpose() * (c * b) * det_j;
            }
        }
    }
    (ke + ke.transpose()) * 0.5
}

/// [`hex8_box_stiffness`] of a box (lowest corner `lo`, sides `sides`, metres) whose stiffness
/// varies inside it, `c_at(x)` at the point `x`: each of `sub`^3 equal sub-boxes integrated by a
/// 2x2x2 Gauss rule of its own on the whole box's shape functions (sub-cell quadrature), so that
/// a stiffness that jumps inside the box (an inclusion's surface) is integrated where it is.
/// `sub = 1` is [`hex8_box_stiffness`].
pub fn hex8_box_stiffness_varying<'a>(
    c_at: impl Fn([f64; 3]) -> &'a Matrix6<f64>,
    lo: [f64; 3],
    sides: [f64; 3],
    sub: usize,
) -> ElementStiffness {
    let g = 1.0 / 3f64.sqrt();
    let n = sub as f64;
    let det_j = 0.125 * sides[0] * sides[1] * sides[2] / (n * n * n);
    let mut ke = ElementStiffness::zeros();
    for cell in 0..sub * sub * sub {
        let idx = [cell % sub, (cell / sub) % sub, cell / (sub * sub)];
        for point in 0..8 {
            let s = [point & 1, (point >> 1) & 1, point >> 2].map(|b| if b == 1 { g } else { -g });
            let xi: [f64; 3] = std::array::from_fn(|d| -1.0 + (2.0 * idx[d] as f64 + 1.0 + s[d]) / n);
            let x: [f64; 3] = std::array::from_fn(|d| lo[d] + 0.5 * sides[d] * (xi[d] + 1.0));
            let b = box_strain_displacement(xi, sides);
            ke += b.transpose() * (c_at(x) * b) * det_j;
        }
    }
    (ke + ke.transpose()) * 0.5
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::material::Material;

    #[test]
    fn sub_cells_of_one_material_are_the_whole_box() {
        let c = Material::object_a().stiffness;
        let sides = [0.002, 0.003, 0.005];
        let whole = hex8_box_stiffness(&c, sides);
        for sub in [1, 3] {
            let split = hex8_box_stiffness_varying(|_| &c, [0.01, 0.02, 0.03], sides, sub);
            assert!((split - whole).abs().max() < 1e-12 * whole.abs().max(), "{sub}");
        }
    }

    #[test]
    fn rigid_modes_have_no_energy() {
        let m = Material::object_a();
        let h = 0.1 / 7.0;
        let ke = hex8_stiffness(&m.stiffness, h);
        let scale = ke.abs().max();
        // Translations and an infinitesimal rotation about z: u = (-y, x, 0).
        for mode in 0..4 {
            let mut u = SMatrix::<f64, 24, 1>::zeros();
            for (a, s) in NODE_SIGNS.iter().enumerate() {
                let p = s.map(|v| 0.5 * h * (v + 1.0));
                match mode {
                    0..=2 => u[3 * a + mode] = 1.0,
                    _ => {
                        u[3 * a] = -p[1];
                        u[3 * a + 1] = p[0];
                    }
                }
            }
            let r = (ke * u).abs().max();
            assert!(r < 1e-12 * scale, "mode {mode}: {r}");
        }
    }

    #[test]
    fn uniform_strain_energy_is_exact() {
        // For u = eps . x, the element energy is V/2 eps^T C eps exactly, on a cube and a box.
        let m = Material::object_b();
        for sides in [[0.02; 3], [0.02, 0.005, 0.013]] {
            let ke = hex8_box_stiffness(&m.stiffness, sides);
            let eps = nalgebra::Vector6::new(1e-3, -2e-4, 5e-4, 3e-4, -1e-4, 2e-4);
            let mut u = SMatrix::<f64, 24, 1>::zeros();
            for (a, s) in NODE_SIGNS.iter().enumerate() {
                let p = [0, 1, 2].map(|d| 0.5 * sides[d] * (s[d] + 1.0));
                // Displacement gradient with symmetric shear (gamma = 2 eps_ij).
                u[3 * a] = eps[0] * p[0] + 0.5 * eps[5] * p[1] + 0.5 * eps[4] * p[2];
                u[3 * a + 1] = 0.5 * eps[5] * p[0] + eps[1] * p[1] + 0.5 * eps[3] * p[2];
                u[3 * a + 2] = 0.5 * eps[4] * p[0] + 0.5 * eps[3] * p[1] + eps[2] * p[2];
            }
            let e_fem = 0.5 * (u.transpose() * ke * u)[(0, 0)];
            let volume = sides[0] * sides[1] * sides[2];
            let e_exact = 0.5 * volume * (eps.transpose() * m.stiffness * eps)[(0, 0)];
            assert!((e_fem - e_exact).abs() < 1e-12 * e_exact, "{e_fem} vs {e_exact}");
        }
    }
}
