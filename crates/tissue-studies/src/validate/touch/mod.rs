//! The touch benchmark: how a model answers where the viewer's user touches the cube.
//!
//! The scene is the viewer's: face z = 0 clamped. Its cases are (a) a 1 N point load at a
//! surface node along x, y or z, over top-face, side-face, edge and corner nodes; (b) a uniform
//! 1 N shear of the top face along x and along y; (c) the viewer's probe, a 15 mm sphere, pressed
//! into the top face at a node, between two nodes and at a cell's centre, 2, 4 and 6 mm deep,
//! with the viewer's node contact; and (d) the lowest six natural frequencies with each model's
//! lumped masses. Point and probe cases come in a training set and a validation set that share
//! no node. Every model is scored in its small-displacement (rest-tangent) response against the
//! project's hex8 FEM on the same mesh, computed once per material and resolution
//! (`touch_score::Reference`).
//!
//! The response layer's `linear` holds the stiffness, the solves and the contact, and its
//! `modes` the frequencies; the sibling `touch_score` holds the reference answers and the scores;
//! the calibration's `fit` the touch cost, its gradient and the load-free stiffness fit.
//!
//! [`score`]: the same-mesh FEM's answers and a model's scores against them.

pub mod score;

use crate::mechanics::grid::Grid;

/// Radius of the viewer's probe sphere, metres.
pub const PROBE_RADIUS_M: f64 = crate::sim::press::DEFAULT_RADIUS_M;
/// Probe depths, metres.
pub const PROBE_DEPTHS_M: [f64; 3] = [0.002, 0.004, 0.006];
/// Number of natural frequencies compared.
pub const MODES: usize = 6;

/// What a case does to the tissue.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// A 1 N force at one surface node.
    Point,
    /// A uniform 1 N shear traction on the top face.
    Shear,
    /// The probe sphere pressed into the top face.
    Probe,
}

/// Which set a case belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Set {
    /// Cases a calibration may fit to.
    Training,
    /// Cases no calibration sees: the scores a user relies on.
    Validation,
}

/// The load of a case.
#[derive(Debug, Clone, PartialEq)]
pub enum Load {
    /// Nodal forces over all dofs, newtons.
    Forces(Vec<f64>),
    /// The probe sphere held at `centre`, metres.
    Probe {
        /// Centre, metres.
        centre: [f64; 3],
    },
}

/// One touch case.
#[derive(Debug, Clone, PartialEq)]
pub struct TouchCase {
    /// e.g. `point_top_2_3_7_z`, `shear_top_x`, `probe_node_2_3_d4`.
    pub id: String,
    /// What it does.
    pub kind: Kind,
    /// Training or validation.
    pub set: Set,
    /// Its load.
    pub load: Load,
}

/// Surface nodes of the point loads on the 8^3 grid (`i, j, k`, k = 7 the top), with the
/// region named in their id; other resolutions scale these positions. The scene is symmetric
/// under the mirrors `i -> 7 - i` and `j -> 7 - j` (an orthotropic material aligned with the
/// grid), so no node of one set is a mirror image of a node (or probe contact) of the other.
const POINT_NODES: [(Set, &str, [usize; 3]); 13] = [
    (Set::Training, "top", [2, 3, 7]),
    (Set::Training, "top", [1, 1, 7]),
    (Set::Training, "edge", [3, 0, 7]),
    (Set::Training, "side", [0, 3, 4]),
    (Set::Training, "side", [5, 7, 3]),
    (Set::Training, "edge", [0, 7, 4]),
    (Set::Validation, "top", [4, 3, 7]),
    (Set::Validation, "top", [2, 2, 7]),
    (Set::Validation, "corner", [7, 7, 7]),
    (Set::Validation, "edge", [7, 2, 7]),
    (Set::Validation, "side", [7, 2, 5]),
    (Set::Validation, "side", [4, 0, 2]),
    (Set::Validation, "edge", [7, 0, 2]),
];

/// Probe points on the top face in lattice units of the 8^3 grid: at a node, between two nodes,
/// at a cell's centre (the validation cell is the face's centre).
const PROBE_POINTS: [(Set, &str, [f64; 2]); 6] = [
    (Set::Training, "node", [2.0, 3.0]),
    (Set::Training, "edge", [1.0, 1.5]),
    (Set::Training, "cell", [2.5, 0.5]),
    (Set::Validation, "node", [3.0, 5.0]),
    (Set::Validation, "edge", [0.5, 3.0]),
    (Set::Validation, "cell", [3.5, 3.5]),
];

/// The touch cases on `grid` (at least 4 nodes per axis). A node of the 8^3 layout that lands on
/// a node already used at a coarser resolution is dropped, so the sets never share a node.
pub fn touch_cases(grid: &Grid) -> Vec<TouchCase> {
    let n = grid.n();
    let scale = (n - 1) as f64 / 7.0;
    let dofs = 3 * grid.num_nodes();
    let mut cases = Vec::new();
    let mut used: Vec<usize> = Vec::new();
    for (set, region, ijk) in POINT_NODES {
        let [i, j, k] = ijk.map(|c| ((c as f64 * scale).round() as usize).min(n - 1));
        let node = grid.node(i, j, k);
        if used.contains(&node) {
            continue;
        }
        used.push(node);
        for (axis, name) in ["x", "y", "z"].iter().enumerate() {
            let mut f = vec![0.0; dofs];
            f[3 * node + axis] = 1.0;
            cases.push(TouchCase {
                id: format!("point_{region}_{i}_{j}_{k}_{name}"),
                kind: Kind::Point,
                set,
                load: Load::Forces(f),
            });
        }
    }
    for (axis, name) in ["x", "y"].iter().enumerate() {
        cases.push(TouchCase {
            id: format!("shear_top_{name}"),
            kind: Kind::Shear,
            set: Set::Training,
            load: Load::Forces(top_traction(grid, axis, 1.0)),
        });
    }
    let top = crate::mechanics::grid::CUBE_SIDE_M;
    for (set, where_, uv) in PROBE_POINTS {
        let [x, y] = uv.map(|c| c * scale * grid.h());
        for depth in PROBE_DEPTHS_M {
            cases.push(TouchCase {
                id: format!("probe_{where_}_{}_{}_d{}", uv[0], uv[1], depth * 1e3),
                kind: Kind::Probe,
                set,
                load: Load::Probe { centre: [x, y, top + PROBE_RADIUS_M - depth] },
            });
        }
    }
    cases
}

/// Consistent nodal loads of a uniform traction of total `force_n` along `axis` on the top face.
pub fn top_traction(grid: &Grid, axis: usize, force_n: f64) -> Vec<f64> {
    let n = grid.n();
    let cells = ((n - 1) * (n - 1)) as f64;
    let mut f = vec![0.0; 3 * grid.num_nodes()];
    for p in grid.face_nodes(2, true) {
        let [i, j, _] = grid.ijk(p);
        let edge = |c: usize| c == 0 || c == n - 1;
        let weight = match (edge(i), edge(j)) {
            (true, true) => 0.25,
            (true, false) | (false, true) => 0.5,
            (false, false) => 1.0,
        };
        f[3 * p + axis] = force_n / cells * weight;
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cases_cover_the_surface_and_sets_are_disjoint() {
        let grid = Grid::paper();
        let cases = touch_cases(&grid);
        let points = cases.iter().filter(|c| c.kind == Kind::Point).count();
        assert_eq!(points, 39);
        assert_eq!(cases.iter().filter(|c| c.kind == Kind::Probe).count(), 18);
        let total: f64 = top_traction(&grid, 0, 1.0).iter().sum();
        assert!((total - 1.0).abs() < 1e-14);
        // Coarser grids keep the sets apart too.
        for n in [4, 5, 6, 12] {
            let g = Grid::new(n).unwrap();
            let mut seen = std::collections::HashMap::new();
            for c in touch_cases(&g).iter().filter(|c| c.kind == Kind::Point) {
                let Load::Forces(f) = &c.load else { unreachable!() };
                let node = f.iter().position(|v| *v != 0.0).unwrap() / 3;
                assert_eq!(*seen.entry(node).or_insert(c.set), c.set, "node {node} in both sets at n = {n}");
            }
        }
    }
}
