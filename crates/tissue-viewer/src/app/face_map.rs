//! The palpation map over a free face in the viewer: the probe's settled force at a grid of
//! points (`tissue-sim palpate`'s map, [`crate::study::palpate`]), read at the model's nodes on
//! that face for the colour overlay.

use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::study::palpate::{Face, PalpationMap};

/// Points per side of the viewer's map.
pub const GRID: usize = 21;
/// Depth of each press, metres.
pub const DEPTH_M: f64 = 0.004;

/// A palpation map of a face and its force at the model's nodes.
#[derive(Debug, Clone)]
pub struct FaceMap {
    /// The map.
    pub map: PalpationMap,
    /// Its force at each node of the model on the face (bilinear between the map's points,
    /// held beyond the outermost), `NaN` elsewhere, newtons.
    pub per_node: Vec<f32>,
    /// The force's range over the map, newtons.
    pub range: [f32; 2],
    /// Its contrast (against the material without its inclusions) at the same nodes.
    pub contrast_per_node: Vec<f32>,
    /// The contrast's range over the map.
    pub contrast_range: [f32; 2],
}

impl FaceMap {
    /// `map` (of a face, its points row by row) read at `grid`'s nodes on that face.
    pub fn new(map: PalpationMap, grid: &Grid) -> Self {
        let face = Face::parse(&map.face).unwrap_or(Face { axis: 2, high: true });
        let per_node = at_nodes(&map.forces, map.grid, grid, face);
        let contrast_per_node = at_nodes(&map.contrast, map.grid, grid, face);
        let range = |v: &[f64]| {
            let low = v.iter().copied().fold(f64::INFINITY, f64::min) as f32;
            [low, v.iter().copied().fold(f64::NEG_INFINITY, f64::max) as f32]
        };
        Self { range: range(&map.forces), contrast_range: range(&map.contrast), map, per_node, contrast_per_node }
    }
}

/// `values` at the `n` x `n` map's points of `face` read at `grid`'s nodes on it (`NaN`
/// elsewhere).
fn at_nodes(values: &[f64], n: usize, grid: &Grid, face: Face) -> Vec<f32> {
    let at = |i: usize, j: usize| values[i.min(n - 1) + n * j.min(n - 1)];
    // The map's points lie in the middle of the cells of an n x n division of the face.
    let cell = |x: f64| {
        let u = (x / CUBE_SIDE_M * n as f64 - 0.5).clamp(0.0, (n - 1) as f64);
        let i = (u.floor() as usize).min(n.saturating_sub(2));
        (i, u - i as f64)
    };
    let (level, [u, v]) = (if face.high { grid.n() - 1 } else { 0 }, face.across());
    grid.positions()
        .iter()
        .enumerate()
        .map(|(node, p)| {
            if grid.ijk(node)[face.axis] != level {
                return f32::NAN;
            }
            let ((i, a), (j, b)) = (cell(p[u]), cell(p[v]));
            let f = (1.0 - a) * (1.0 - b) * at(i, j)
                + a * (1.0 - b) * at(i + 1, j)
                + (1.0 - a) * b * at(i, j + 1)
                + a * b * at(i + 1, j + 1);
            f as f32
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::material::Material;
    use crate::study::palpate::{Face, Palpation};

    #[test]
    fn the_map_is_read_at_its_faces_nodes_only() {
        let palpation = Palpation { face: Face::parse("+z").expect("the top"), radius: 0.015, depth: DEPTH_M, grid: 3 };
        // A force rising along x: 1, 2, 3 N at x = 1/6, 1/2, 5/6 of the side.
        let forces: Vec<f64> = (0..9).map(|k| 1.0 + (k % 3) as f64).collect();
        let map = PalpationMap::new(&Material::object_a(), &palpation, forces.clone(), forces.clone());
        let grid = Grid::new(4).expect("a grid");
        let face = FaceMap::new(map, &grid);
        assert_eq!(face.range, [1.0, 3.0]);
        let top: Vec<f32> = (0..4).map(|i| face.per_node[grid.node(i, 2, 3)]).collect();
        // x = 0 and 1/3 of the side: held at 1 N, then 1 + (1/3 - 1/6) / (1/3) = 1.5 N; 2.5 N, 3 N.
        for (a, b) in top.iter().zip([1.0, 1.5, 2.5, 3.0]) {
            assert!((a - b).abs() < 1e-5, "{top:?}");
        }
        assert!(face.per_node[grid.node(1, 1, 2)].is_nan());
        // The -y face: across it x (inner) and z (outer), read at its nodes only.
        let palpation = Palpation { face: Face::parse("-y").expect("a side"), radius: 0.015, depth: DEPTH_M, grid: 3 };
        let map = PalpationMap::new(&Material::object_a(), &palpation, forces.clone(), forces);
        let side = FaceMap::new(map, &grid);
        let row: Vec<f32> = (0..4).map(|i| side.per_node[grid.node(i, 0, 1)]).collect();
        for (a, b) in row.iter().zip([1.0, 1.5, 2.5, 3.0]) {
            assert!((a - b).abs() < 1e-5, "{row:?}");
        }
        assert!(side.per_node[grid.node(1, 3, 1)].is_nan() && side.per_node[grid.node(1, 1, 3)].is_nan());
    }
}
