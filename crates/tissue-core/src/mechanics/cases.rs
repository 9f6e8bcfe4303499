//! The paper's benchmark load cases (`shared/spec/benchmark.md`): 9 clamped cases per object
//! (axis 1, 2, 3 x force 1, 5, 10 N) and 9 patch cases with an exact uniform-strain answer; and
//! [`CaseSolution`], the answer of a case, whichever model solved it.

use crate::mechanics::grid::{CUBE_SIDE_M, Grid};

/// The paper's force magnitudes, newtons.
pub const FORCES_N: [f64; 3] = [1.0, 5.0, 10.0];

/// Boundary-condition family of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Bc {
    /// Face `x_a = 0` fully fixed, equal nodal forces `F / n^2` on face `x_a = L`.
    Clamped,
    /// Roller supports removing rigid motion only, consistent nodal loads of a uniform traction.
    Patch,
}

impl Bc {
    /// The lower-case name used in case ids and files.
    pub fn name(self) -> &'static str {
        match self {
            Bc::Clamped => "clamped",
            Bc::Patch => "patch",
        }
    }
}

/// One load case: which degrees of freedom are fixed (to zero) and the nodal loads.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadCase {
    /// `{object}_{bc}_ax{a}_F{F}`.
    pub id: String,
    /// Boundary-condition family.
    pub bc: Bc,
    /// Loaded axis, 1-based (1 = x).
    pub axis: usize,
    /// Total applied force, newtons, along `+axis`.
    pub force_n: f64,
    /// Per degree of freedom (`3 node + component`): fixed to zero.
    pub fixed: Vec<bool>,
    /// Per degree of freedom: applied nodal force, newtons.
    pub load: Vec<f64>,
}

impl LoadCase {
    /// Spec case id, e.g. `A_clamped_ax2_F5`.
    pub fn make_id(object: &str, bc: Bc, axis: usize, force_n: f64) -> String {
        format!("{object}_{}_ax{axis}_F{force_n}", bc.name())
    }

    /// The clamped case: face `x_a = 0` fixed, `F / n^2` on each node of face `x_a = L`.
    pub fn clamped(grid: &Grid, object: &str, axis: usize, force_n: f64) -> Self {
        let a = axis - 1;
        let dofs = 3 * grid.num_nodes();
        let mut fixed = vec![false; dofs];
        let mut load = vec![0.0; dofs];
        for p in grid.face_nodes(a, false) {
            fixed[3 * p..3 * p + 3].fill(true);
        }
        let face = grid.face_nodes(a, true);
        let per_node = force_n / face.len() as f64;
        for p in face {
            load[3 * p + a] = per_node;
        }
        Self { id: Self::make_id(object, Bc::Clamped, axis, force_n), bc: Bc::Clamped, axis, force_n, fixed, load }
    }

    /// The viewer's scene: face z = 0 fully fixed, no loads (the touch benchmark's scene too).
    pub fn bottom_clamp(grid: &Grid, object: &str) -> Self {
        let mut c = Self::clamped(grid, object, 3, 0.0);
        c.load.fill(0.0);
        c
    }

    /// The patch case: rollers on `x_a = 0` (`u_a = 0`), node 0 also `u_b = u_c = 0`, the node at
    /// `x_b = L` on the `x_a = 0, x_c = 0` edge also `u_c = 0`, with `(a, b, c)` cyclic; the
    /// consistent nodal loads of the traction `F / L^2` on face `x_a = L`.
    pub fn patch(grid: &Grid, object: &str, axis: usize, force_n: f64) -> Self {
        let a = axis - 1;
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        let n = grid.n();
        let dofs = 3 * grid.num_nodes();
        let mut fixed = vec![false; dofs];
        let mut load = vec![0.0; dofs];
        for p in grid.face_nodes(a, false) {
            fixed[3 * p + a] = true;
        }
        fixed[b] = true;
        fixed[c] = true;
        let mut corner = [0usize; 3];
        corner[b] = n - 1;
        let q = grid.node(corner[0], corner[1], corner[2]);
        fixed[3 * q + c] = true;
        let cells = ((n - 1) * (n - 1)) as f64;
        for p in grid.face_nodes(a, true) {
            let ijk = grid.ijk(p);
            let on_edge = |d: usize| ijk[d] == 0 || ijk[d] == n - 1;
            let weight = match (on_edge(b), on_edge(c)) {
                (true, true) => 0.25,
                (true, false) | (false, true) => 0.5,
                (false, false) => 1.0,
            };
            load[3 * p + a] = force_n / cells * weight;
        }
        Self { id: Self::make_id(object, Bc::Patch, axis, force_n), bc: Bc::Patch, axis, force_n, fixed, load }
    }

    /// The exact patch-test displacement field `u_i = eps_ii x_i`, `eps = S sigma`, for the
    /// uniaxial stress `sigma_aa = F / L^2`. `compliance` is the material's `S`.
    pub fn patch_exact(&self, grid: &Grid, compliance: &nalgebra::Matrix6<f64>) -> Vec<[f64; 3]> {
        let a = self.axis - 1;
        let sigma = self.force_n / (CUBE_SIDE_M * CUBE_SIDE_M);
        let eps = [0, 1, 2].map(|i| compliance[(i, a)] * sigma);
        (0..grid.num_nodes())
            .map(|p| {
                let x = grid.position(p);
                [eps[0] * x[0], eps[1] * x[1], eps[2] * x[2]]
            })
            .collect()
    }

    /// Nodes whose three components are all fixed.
    pub fn fixed_nodes(&self) -> Vec<bool> {
        self.fixed.chunks_exact(3).map(|c| c.iter().all(|&f| f)).collect()
    }
}

/// The answer of one load case (FEM or mass-spring).
#[derive(Debug, Clone, PartialEq)]
pub struct CaseSolution {
    /// Spec case id.
    pub case_id: String,
    /// Loaded axis, 1-based.
    pub axis: usize,
    /// Applied force, newtons.
    pub force_n: f64,
    /// Nodal displacements, metres, row = node.
    pub displacements: Vec<[f64; 3]>,
    /// Sum of the support reactions `K u - f` over the fixed degrees of freedom, newtons.
    pub reaction_n: [f64; 3],
}

/// Parses a case id such as `A_clamped_ax1_F10` into its object label and case on `grid`.
pub fn parse_case_id(grid: &Grid, id: &str) -> Result<(String, LoadCase), String> {
    let bad = || format!("case id {id:?} is not of the form OBJECT_clamped|patch_axA_FF (e.g. A_clamped_ax1_F10)");
    let parts: Vec<&str> = id.split('_').collect();
    let [object, bc, axis, force] = parts[..] else { return Err(bad()) };
    let axis: usize =
        axis.strip_prefix("ax").and_then(|a| a.parse().ok()).filter(|a| (1..=3).contains(a)).ok_or_else(bad)?;
    let force: f64 = force
        .strip_prefix('F')
        .and_then(|f| f.parse().ok())
        .filter(|f: &f64| f.is_finite() && *f >= 0.0)
        .ok_or_else(bad)?;
    let case = match bc {
        "clamped" => LoadCase::clamped(grid, object, axis, force),
        "patch" => LoadCase::patch(grid, object, axis, force),
        _ => return Err(bad()),
    };
    Ok((object.to_owned(), case))
}

/// The 9 cases of one boundary-condition family, ordered axis 1..3, then force 1, 5, 10 N.
pub fn benchmark_cases(grid: &Grid, object: &str, bc: Bc) -> Vec<LoadCase> {
    let mut out = Vec::with_capacity(9);
    for axis in 1..=3 {
        for f in FORCES_N {
            out.push(match bc {
                Bc::Clamped => LoadCase::clamped(grid, object, axis, f),
                Bc::Patch => LoadCase::patch(grid, object, axis, f),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn case_ids_and_loads() {
        let g = Grid::paper();
        let cases = benchmark_cases(&g, "A", Bc::Clamped);
        assert_eq!(cases.len(), 9);
        assert_eq!(cases[4].id, "A_clamped_ax2_F5");
        for c in &cases {
            let total: f64 = c.load.iter().sum();
            assert!((total - c.force_n).abs() < 1e-14);
            assert_eq!(c.fixed.iter().filter(|&&f| f).count(), 3 * 64);
        }
        let patch = benchmark_cases(&g, "B", Bc::Patch);
        for c in &patch {
            let total: f64 = c.load.iter().sum();
            assert!((total - c.force_n).abs() < 1e-14);
            assert_eq!(c.fixed.iter().filter(|&&f| f).count(), 64 + 3);
        }
        assert_eq!(patch[0].id, "B_patch_ax1_F1");
        // Axis 1 patch: node 0 has u_y = u_z = 0, node 56 (x=0, y=L, z=0) has u_z = 0.
        assert!(patch[0].fixed[1] && patch[0].fixed[2] && patch[0].fixed[3 * 56 + 2]);
    }
}
