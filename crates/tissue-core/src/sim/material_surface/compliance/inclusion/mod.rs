//! What a material's inclusions change in its surface compliance: the background's compliance
//! (kept per background material) less a correction on the surface nodes near the inclusions.
//!
//! An inclusion changes the stiffness only on the elements it meets: `K = K0 + P' D P`, `D` the
//! change on the dofs `P` of those elements. By the Woodbury identity the compliance is
//! `K^-1 = K0^-1 - X (I + D G)^-1 D X'`, with `X = K0^-1 P'` (the background's answer to a unit
//! force at each of those dofs) and `G = P X`. One factorisation of the background's FEM on a mesh
//! fine around the inclusions (and [`REACH_M`] beyond them, where the surface nodes the correction
//! holds lie) and one solve per dof of the inclusions' elements give `X`; the correction on the
//! surface nodes is `X_Q (I + D G)^-1 D X_Q'`, `X_Q` the solutions read at the lattice's surface
//! nodes by the mesh's trilinear shape functions. Far from the inclusions (beyond [`REACH_M`])
//! the correction is left out: there the lump changes the force by a few parts in a thousand.
//! [`file`](mod@file): the correction kept in the cache folder.

pub mod file;

use faer::Mat;
use faer::linalg::solvers::Solve;

use super::ComplianceError;
use super::lattice::Lattice;
use crate::mechanics::fem::graded::{GradedFem, GradedMesh, graded_axis, inclusion_change};
use crate::mechanics::grid::CUBE_SIDE_M;
use crate::mechanics::material::Material;

/// Element side of the mesh around the inclusions, metres.
pub const SPACING_M: f64 = 0.0025;
/// How far beyond an inclusion's surface the mesh stays fine and the surface nodes hold the
/// correction, metres.
pub const REACH_M: f64 = 0.02;
/// Growth of the element size beyond.
const GROWTH: f64 = 1.45;
/// Most surface nodes the correction holds (3 x 3 blocks per pair: 290 MB).
pub const MAX_NODES: usize = 2800;
/// Unit loads solved in one batch.
const BATCH: usize = 128;

/// The change the inclusions make to the surface compliance, on the surface nodes near them.
#[derive(Debug, Clone, PartialEq)]
pub struct InclusionCorrection {
    /// For every surface node of the lattice, its row here, `u32::MAX` where the correction does
    /// not hold it.
    rows: Vec<u32>,
    /// Surface nodes held.
    count: usize,
    /// Per pair of rows `(q, p)`, the 3 x 3 block: per force component at `p`, per displacement
    /// component at `q`, metres per newton (the background's less the material's).
    values: Vec<f32>,
}

impl InclusionCorrection {
    /// The correction of `material`'s inclusions on `lattice`'s surface nodes; `progress` as
    /// [`super::SurfaceCompliance::compute`]'s.
    pub fn compute(
        lattice: &Lattice,
        material: &Material,
        progress: &mut dyn FnMut(f64) -> bool,
    ) -> Result<Self, ComplianceError> {
        if material.inclusions.is_empty() {
            return Ok(Self { rows: vec![u32::MAX; lattice.len()], count: 0, values: Vec::new() });
        }
        let (lo, hi, mesh) = window(material);
        // The surface nodes held: those within the fine box, each read from its box's corners.
        let mut rows = vec![u32::MAX; lattice.len()];
        let mut read = Vec::new();
        for (q, row) in rows.iter_mut().enumerate() {
            let x = lattice.point(q).map(|c| lattice.coords[c]);
            if (0..3).all(|a| (lo[a] - 1e-12..=hi[a] + 1e-12).contains(&x[a])) {
                *row = read.len() as u32;
                read.push(mesh.corners(x));
            }
        }
        if read.len() > MAX_NODES {
            return Err(ComplianceError::TooSpread(read.len()));
        }
        let (nodes, change) = inclusion_change(&mesh, material);
        let mut background = material.clone();
        background.inclusions.clear();
        if !progress(0.0) {
            return Err(ComplianceError::Cancelled);
        }
        let mut fem = GradedFem::clamped_bottom(mesh, &background)?;
        let n = fem.fixed.len();
        // The inclusions' free dofs (a clamped one moves not at all).
        let all = 3 * nodes.len();
        let free: Vec<usize> = (0..all).filter(|&l| !fem.fixed[3 * nodes[l / 3] + l % 3]).collect();
        let dof = |l: usize| 3 * nodes[free[l] / 3] + free[l] % 3;
        let m = free.len();
        let held = 3 * read.len();
        let mut g = Mat::<f64>::zeros(m, m);
        let mut xq = Mat::<f64>::zeros(held, m);
        let mut done = 0;
        while done < m {
            let cols = BATCH.min(m - done);
            let mut rhs = vec![0.0; n * cols];
            for c in 0..cols {
                rhs[c * n + dof(done + c)] = 1.0;
            }
            fem.solve_columns(&mut rhs, cols)?;
            for c in 0..cols {
                let u = &rhs[c * n..(c + 1) * n];
                for l in 0..m {
                    g[(l, done + c)] = u[dof(l)];
                }
                for (r, corners) in read.iter().enumerate() {
                    for a in 0..3 {
                        xq[(3 * r + a, done + c)] = corners.iter().map(|&(node, w)| w * u[3 * node + a]).sum();
                    }
                }
            }
            done += cols;
            if !progress(0.1 + 0.8 * done as f64 / m as f64) {
                return Err(ComplianceError::Cancelled);
            }
        }
        let d = Mat::<f64>::from_fn(m, m, |r, c| change[free[c] * all + free[r]]);
        let mut i_dg = &d * &g;
        for k in 0..m {
            i_dg[(k, k)] += 1.0;
        }
        let mut middle = i_dg.partial_piv_lu().solve(&d);
        // (I + D G)^-1 D is symmetric: made so to its rounding, so that the correction is too.
        for c in 0..m {
            for r in 0..c {
                let v = 0.5 * (middle[(r, c)] + middle[(c, r)]);
                middle[(r, c)] = v;
                middle[(c, r)] = v;
            }
        }
        let values = blocks(&(&xq * &middle), &xq);
        progress(1.0);
        Ok(Self { rows, count: read.len(), values })
    }

    /// `n_q . dW(q <- p) n_p`: the change of surface node `q`'s displacement along `n_q` under a
    /// unit force along `n_p` at surface node `p`, metres per newton (0 where not held).
    #[inline(always)]
    pub fn normal(&self, p: usize, n_p: [f64; 3], q: usize, n_q: [f64; 3]) -> f64 {
        let (rp, rq) = (self.rows[p], self.rows[q]);
        if rp == u32::MAX || rq == u32::MAX {
            return 0.0;
        }
        let at = 9 * (rq as usize * self.count + rp as usize);
        let block = &self.values[at..at + 9];
        (0..3).map(|c| n_p[c] * (0..3).map(|a| block[3 * c + a] as f64 * n_q[a]).sum::<f64>()).sum()
    }

    /// Surface nodes held.
    pub fn nodes(&self) -> usize {
        self.count
    }

    /// Bytes held.
    pub fn memory_bytes(&self) -> usize {
        4 * self.values.len() + 4 * self.rows.len()
    }
}

/// The box the correction holds (the inclusions and [`REACH_M`] around them, within the cube)
/// and the mesh fine inside it, metres.
fn window(material: &Material) -> ([f64; 3], [f64; 3], GradedMesh) {
    let reach: Vec<([f64; 3], [f64; 3])> = material
        .inclusions
        .iter()
        .map(|i| (i.centre.map(|c| c - i.radius - REACH_M), i.centre.map(|c| c + i.radius + REACH_M)))
        .collect();
    let lo: [f64; 3] = std::array::from_fn(|a| reach.iter().map(|r| r.0[a]).fold(f64::INFINITY, f64::min).max(0.0));
    let hi: [f64; 3] =
        std::array::from_fn(|a| reach.iter().map(|r| r.1[a]).fold(f64::NEG_INFINITY, f64::max).min(CUBE_SIDE_M));
    let mesh = GradedMesh {
        axes: std::array::from_fn(|a| {
            graded_axis(CUBE_SIDE_M, 0.5 * (lo[a] + hi[a]), SPACING_M, 0.5 * (hi[a] - lo[a]), GROWTH)
        }),
    };
    (lo, hi, mesh)
}

/// The correction `A X_Q'` (`a = X_Q (I + D G)^-1 D`, `xq = X_Q`: a row per displacement
/// component of a held node) as 3 x 3 blocks per pair of nodes, computed a band of rows at a
/// time (the whole would be `(3 count)^2` doubles).
fn blocks(a: &Mat<f64>, xq: &Mat<f64>) -> Vec<f32> {
    const BAND: usize = 64;
    let count = xq.nrows() / 3;
    let mut values = vec![0.0f32; 9 * count * count];
    let mut q0 = 0;
    while q0 < count {
        let band = BAND.min(count - q0);
        let w = a.as_ref().subrows(3 * q0, 3 * band) * xq.transpose();
        for q in 0..band {
            for p in 0..count {
                let block = &mut values[9 * ((q0 + q) * count + p)..9 * ((q0 + q) * count + p + 1)];
                for c in 0..3 {
                    for r in 0..3 {
                        block[3 * c + r] = w[(3 * q + r, 3 * p + c)] as f32;
                    }
                }
            }
        }
        q0 += band;
    }
    values
}
