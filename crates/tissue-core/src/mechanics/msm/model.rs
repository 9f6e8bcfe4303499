//! The mass-spring model: parameters, spring families and masses.

use crate::mechanics::grid::{Grid, SpringFamily, axis_families, body_diagonal_families, face_diagonal_families};
use glam::DVec3;

/// Errors in MSM parameters.
#[derive(Debug, thiserror::Error)]
pub enum ParamError {
    /// A parameter is NaN, infinite or out of its range.
    #[error("MSM parameter {name} = {} is invalid: {why}", crate::io::num(*value))]
    Invalid {
        /// Parameter name, e.g. `k1`.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What is required.
        why: &'static str,
    },
    /// A parameter the topology needs is missing.
    #[error("MSM parameter {name} is missing: {why}")]
    Missing {
        /// Parameter name, e.g. `c23`.
        name: &'static str,
        /// What is required.
        why: &'static str,
    },
}

/// Which springs the lattice has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Topology {
    /// The paper's model: axis-aligned structural springs only (no shear stiffness).
    Axis,
    /// Axis springs plus both diagonals of every lattice square, one stiffness per plane.
    Shear,
    /// The springs of every hex element: its 12 edges, 12 face diagonals and 4 body diagonals,
    /// one stiffness per family group (`k1..k3`, `c12..c23`, `b`). A spring shared by several
    /// elements gets each element's share, so springs on the surface are softer than inside
    /// (an edge spring on a face has half, on a cube edge a quarter of an interior one's
    /// stiffness). Calibrated, it is the most accurate lattice here: see the `reproduce` report.
    Hex,
}

impl Topology {
    /// The lower-case name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Topology::Axis => "axis",
            Topology::Shear => "shear",
            Topology::Hex => "hex",
        }
    }
}

/// MSM parameters: spring stiffness per family (N/m) and nodal damping (N s/m).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MsmParams {
    /// Stiffness of springs along axis 1 (x), N/m.
    pub k1: f64,
    /// Stiffness of springs along axis 2 (y), N/m.
    pub k2: f64,
    /// Stiffness of springs along axis 3 (z), N/m.
    pub k3: f64,
    /// Nodal damping: force `-d v` on every node, N s/m.
    pub d: f64,
    /// Face-diagonal stiffness in the 1-2 plane (shear topology), N/m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c12: Option<f64>,
    /// Face-diagonal stiffness in the 1-3 plane (shear topology), N/m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c13: Option<f64>,
    /// Face-diagonal stiffness in the 2-3 plane (shear topology), N/m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub c23: Option<f64>,
    /// Body-diagonal stiffness (hex topology, which also needs `c12..c23`), N/m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub b: Option<f64>,
}

impl MsmParams {
    /// The paper's axis-spring parameters.
    pub fn axis(k1: f64, k2: f64, k3: f64, d: f64) -> Self {
        Self { k1, k2, k3, d, c12: None, c13: None, c23: None, b: None }
    }

    /// Every stiffness of `topology` at 1 N/m, no damping.
    pub fn unit(topology: Topology) -> Self {
        let one = Some(1.0);
        let axis = Self::axis(1.0, 1.0, 1.0, 0.0);
        match topology {
            Topology::Axis => axis,
            Topology::Shear => Self { c12: one, c13: one, c23: one, ..axis },
            Topology::Hex => Self { c12: one, c13: one, c23: one, b: one, ..axis },
        }
    }

    /// The topology these parameters describe: hex when a body-diagonal stiffness is set, shear
    /// when any face-diagonal stiffness is, axis otherwise.
    pub fn topology(&self) -> Topology {
        if self.b.is_some() {
            Topology::Hex
        } else if self.c12.is_some() || self.c13.is_some() || self.c23.is_some() {
            Topology::Shear
        } else {
            Topology::Axis
        }
    }

    /// Checks ranges: axis stiffness positive, diagonal stiffness and damping non-negative, all finite.
    pub fn validate(&self) -> Result<(), ParamError> {
        let bad = |name, value, why| Err(ParamError::Invalid { name, value, why });
        let in_range = |v: f64| (STIFFNESS_RANGE.0..=STIFFNESS_RANGE.1).contains(&v);
        for (name, v) in [("k1", self.k1), ("k2", self.k2), ("k3", self.k3)] {
            if !in_range(v) {
                return bad(name, v, "a spring stiffness must be a finite number from 1e-6 to 1e10 N/m");
            }
        }
        if !self.d.is_finite() || self.d < 0.0 || self.d > 1e10 {
            return bad("d", self.d, "damping must be a finite number from 0 to 1e10 N s/m");
        }
        for (name, v) in [("c12", self.c12), ("c13", self.c13), ("c23", self.c23), ("b", self.b)] {
            if let Some(v) = v
                && v != 0.0
                && !in_range(v)
            {
                return bad(name, v, "a diagonal stiffness must be 0 or a finite number from 1e-6 to 1e10 N/m");
            }
        }
        let diagonals = [("c12", self.c12), ("c13", self.c13), ("c23", self.c23)];
        if diagonals.iter().any(|(_, v)| v.is_some())
            && let Some((name, _)) = diagonals.iter().find(|(_, v)| v.is_none())
        {
            return Err(ParamError::Missing {
                name,
                why: "the shear and hex lattices (face diagonals) need all of c12, c13 and c23",
            });
        }
        if let Some(b) = self.b
            && (self.c12.is_none() || self.c13.is_none() || self.c23.is_none())
        {
            return bad("b", b, "the hex topology (body diagonals) also needs c12, c13 and c23");
        }
        Ok(())
    }

    /// These parameters with the ties of a transversely isotropic material imposed (`k3 = k2`,
    /// `c13 = c12` where face diagonals are set); unchanged for an orthotropic one.
    pub fn with_ties(mut self, transversely_isotropic: bool) -> Self {
        if transversely_isotropic {
            self.k3 = self.k2;
            if self.c12.is_some() {
                self.c13 = self.c12;
            }
        }
        self
    }

    /// The ties of a transversely isotropic material (axis 1 distinct): `k3 = k2` and, where
    /// face diagonals are set, `c13 = c12`. Orthotropic materials have no ties.
    pub fn check_ties(&self, transversely_isotropic: bool) -> Result<(), ParamError> {
        if !transversely_isotropic {
            return Ok(());
        }
        if self.k3 != self.k2 {
            return Err(ParamError::Invalid {
                name: "k3",
                value: self.k3,
                why: "the material is transversely isotropic (axis 1 distinct): k3 must equal k2",
            });
        }
        if self.c13 != self.c12 {
            return Err(ParamError::Invalid {
                name: "c13",
                value: self.c13.unwrap_or(f64::NAN),
                why: "the material is transversely isotropic (axis 1 distinct): c13 must equal c12",
            });
        }
        Ok(())
    }
}

/// The range of a spring stiffness, N/m: below it forces of a newton give displacements beyond
/// floating point, above it no soft tissue (and no stable step) lies.
pub const STIFFNESS_RANGE: (f64, f64) = (1e-6, 1e10);

/// Element-lumped node masses: `density h^3 / 8` from each element at each of its nodes.
pub fn lumped_masses(grid: &Grid, density: f64) -> Vec<f64> {
    let mut m = vec![0.0; grid.num_nodes()];
    let m_e = density * grid.h().powi(3) / 8.0;
    for nodes in grid.elements() {
        for p in nodes {
            m[p] += m_e;
        }
    }
    m
}

/// One spring family laid out for the force loop: pairs `(lo + p, lo + p + s)` for `p` in
/// `0..stiffness.len()`, with `stiffness[p] = 0` where the lattice partner is outside the grid.
#[derive(Debug, Clone)]
pub struct FamilyLayout {
    /// The lattice family.
    pub family: SpringFamily,
    /// Linear index offset between the two nodes of a pair.
    pub offset: usize,
    /// First node of the first pair.
    pub lo: usize,
    /// Stiffness of each pair (N/m), zero for pairs that are not springs.
    pub stiffness: Vec<f64>,
    /// Whether each pair is a spring (its lattice partner lies in the grid).
    pub valid: Vec<bool>,
    /// Rest length, metres.
    pub rest_length: f64,
}

/// A spring listed explicitly: nodes, stiffness (N/m), rest length (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    /// First node (also the pair index within its family).
    pub a: usize,
    /// Second node.
    pub b: usize,
    /// Index of its family in [`MsmModel::families`].
    pub family: usize,
    /// Stiffness, N/m.
    pub k: f64,
    /// Rest length, m.
    pub rest: f64,
}

/// A mass-spring model of the cube: lattice springs, lumped masses, nodal damping.
#[derive(Debug, Clone)]
pub struct MsmModel {
    /// The grid.
    pub grid: Grid,
    /// The parameters.
    pub params: MsmParams,
    /// The mean node mass, kg: the cube's mass over the nodes (every node's mass in the paper's
    /// axis lattice and the shear lattice).
    pub node_mass: f64,
    /// Mass of each node, kg: the cube's mass shared equally, except for the hex lattice, which
    /// is assembled from elements and so inclusions each element's mass onto its eight nodes (a
    /// surface node carries less, as in the FEM's lumped masses).
    pub masses: Vec<f64>,
    /// The spring families with non-zero stiffness.
    pub families: Vec<FamilyLayout>,
    /// Damping coefficient of each node, N s/m (force `-c_p v_p`): the paper's nodal `d` on every
    /// node as built, or mass-proportional `alpha m_p` after [`MsmModel::set_mass_damping`].
    pub damping: Vec<f64>,
    /// The rule of the material's inclusions its springs take ([`super::inclusions`]), if any.
    pub inclusions: Option<super::inclusions::SpringRule>,
}

impl MsmModel {
    /// Builds the model; `density` in kg/m^3 gives the node mass `density L^3 / n^3`.
    pub fn new(grid: Grid, params: MsmParams, density: f64) -> Result<Self, ParamError> {
        params.validate()?;
        let mut stiff: Vec<(SpringFamily, f64)> =
            axis_families().into_iter().zip([params.k1, params.k2, params.k3]).collect();
        let diag = face_diagonal_families();
        for (plane, c) in [params.c12, params.c13, params.c23].into_iter().enumerate() {
            // Kept even at zero stiffness, so that the spring pattern depends on the topology only.
            if let Some(c) = c {
                stiff.extend(diag[plane].iter().map(|f| (*f, c)));
            }
        }
        let hex = params.topology() == Topology::Hex;
        if let Some(b) = params.b {
            stiff.extend(body_diagonal_families().into_iter().map(|f| (f, b)));
        }
        let families = stiff
            .into_iter()
            .map(|(family, k)| {
                let (lo, _, valid) = grid.family_pairs(family);
                FamilyLayout {
                    family,
                    offset: grid.linear_offset(family),
                    lo,
                    stiffness: valid
                        .iter()
                        .enumerate()
                        .map(|(p, &v)| match (v, hex) {
                            (false, _) => 0.0,
                            (true, false) => k,
                            (true, true) => k * grid.element_share(family, lo + p),
                        })
                        .collect(),
                    valid,
                    rest_length: family.length_in_h() * grid.h(),
                }
            })
            .collect();
        let side = crate::mechanics::grid::CUBE_SIDE_M;
        let node_mass = density * side * side * side / grid.num_nodes() as f64;
        let masses = if hex { lumped_masses(&grid, density) } else { vec![node_mass; grid.num_nodes()] };
        let damping = vec![params.d; grid.num_nodes()];
        Ok(Self { grid, params, node_mass, masses, families, damping, inclusions: None })
    }

    /// The model with `material`'s inclusions taken by its springs ([`super::inclusions`]): each
    /// spring crossing one is scaled by the rule. Unchanged for a homogeneous material.
    pub fn with_inclusions(self, material: &crate::mechanics::material::Material) -> Self {
        let rule = super::inclusions::SpringRule::new(self.grid, material);
        self.with_rule(rule)
    }

    /// The model with its springs scaled by `rule` (none: unchanged).
    pub fn with_rule(mut self, rule: Option<super::inclusions::SpringRule>) -> Self {
        debug_assert!(self.inclusions.is_none(), "the springs take a rule once");
        debug_assert!(rule.as_ref().is_none_or(|r| r.grid() == self.grid), "a rule of the model's grid");
        self.inclusions = rule;
        self.apply_inclusions();
        self
    }

    /// The model of `params` on the same grid, density and inclusions.
    pub fn with_params(&self, params: MsmParams, density: f64) -> Result<Self, ParamError> {
        Ok(Self::new(self.grid, params, density)?.with_rule(self.inclusions.clone()))
    }

    fn apply_inclusions(&mut self) {
        let Some(rule) = &self.inclusions else { return };
        for f in &mut self.families {
            for (p, k) in f.stiffness.iter_mut().enumerate() {
                if *k != 0.0 {
                    *k *= rule.factor(f.lo + p, f.lo + p + f.offset);
                }
            }
        }
    }

    /// Mass-proportional damping `C = alpha M` (1/s) instead of the nodal `d`: the Rayleigh
    /// scheme that a damping ratio at the fundamental sets. A running [`super::Dynamics`] picks it up at its next
    /// [`super::Dynamics::set_model`].
    pub fn set_mass_damping(&mut self, alpha: f64) {
        for (c, m) in self.damping.iter_mut().zip(&self.masses) {
            *c = alpha * m;
        }
    }

    /// All springs as an explicit list (for assembly of tangent matrices).
    pub fn springs(&self) -> Vec<Spring> {
        let mut out = Vec::new();
        for (family, f) in self.families.iter().enumerate() {
            for (p, &k) in f.stiffness.iter().enumerate() {
                if f.valid[p] {
                    out.push(Spring { a: f.lo + p, b: f.lo + p + f.offset, family, k, rest: f.rest_length });
                }
            }
        }
        out
    }

    /// Number of springs.
    pub fn num_springs(&self) -> usize {
        self.families.iter().map(|f| f.valid.iter().filter(|&&v| v).count()).sum()
    }

    /// Elastic energy `sum 1/2 k (l - l0)^2` at positions `x` (structure of arrays).
    pub fn elastic_energy(&self, x: &[Vec<f64>; 3]) -> f64 {
        let mut e = 0.0;
        for f in &self.families {
            for (p, &k) in f.stiffness.iter().enumerate() {
                let (i, j) = (f.lo + p, f.lo + p + f.offset);
                let d = [x[0][j] - x[0][i], x[1][j] - x[1][i], x[2][j] - x[2][i]];
                let l = DVec3::from(d).length();
                e += 0.5 * k * (l - f.rest_length).powi(2);
            }
        }
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hex_lattice_lumps_element_masses_the_others_share_equally() {
        let grid = Grid::new(4).unwrap();
        let hex = MsmModel::new(grid, MsmParams::unit(Topology::Hex), 1000.0).unwrap();
        let total: f64 = hex.masses.iter().sum();
        assert!((total - 1000.0 * 1e-3).abs() < 1e-12, "{total}");
        let m_e = 1000.0 * grid.h().powi(3) / 8.0;
        assert!((hex.masses[grid.node(0, 0, 0)] - m_e).abs() < 1e-15);
        assert!((hex.masses[grid.node(1, 1, 1)] - 8.0 * m_e).abs() < 1e-15);
        let shear = MsmModel::new(grid, MsmParams::unit(Topology::Shear), 1000.0).unwrap();
        assert!(shear.masses.iter().all(|&m| m == shear.node_mass));
    }
}
