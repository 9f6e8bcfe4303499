//! Where the surface compliance lives: the nodes of a lattice on the cube's free surface (the top
//! face and the four side faces; the clamped bottom row left out), the three families of
//! faces that share a fine FEM mesh (the top face; the two faces normal to x, mirror images; the
//! two normal to y), and which columns each family keeps.
//!
//! The cube and its orthotropic material are mirror-symmetric in x and in y, so a family keeps
//! the columns of one face's nodes, on one side of its mirror lines. Away from the face's edges
//! the compliance barely changes under a shift along the face, so only every [`STRIDE`]th node's
//! column is solved there, per axis: a node between takes its nearest solved node's column
//! shifted by the offset. Within [`EDGE_ROWS`] nodes of an edge every row along it is solved (a
//! node there shifts along the edge only; near a corner, not at all). A column holds the
//! displacements of its own face and of [`BAND_ROWS`] rows of the faces beside it (a press across
//! an edge).
//!
//! The lattice is uniform but for the first [`HALVED`] intervals from either end of every axis,
//! which are halved: across every edge the rows are twice as close (1 mm at 2 mm), where a
//! shallow press across an edge or into a corner has its whole contact. Its indices count the
//! halved rows; [`EDGE_ROWS`], [`BAND_ROWS`] and [`STRIDE`] count the lattice's intervals.

use crate::mechanics::grid::CUBE_SIDE_M;

/// Intervals at each end of an axis that are halved.
pub const HALVED: usize = 2;
/// Intervals from an edge within which every column is solved.
pub const EDGE_ROWS: usize = 4;
/// Away from the edges, one node's column in this many per axis is solved.
pub const STRIDE: usize = 3;
/// Intervals of the neighbouring faces (from the shared edge) a column holds.
pub const BAND_ROWS: usize = 8;

/// Intervals halved at each end of an axis of `divisions` intervals (fewer on a lattice too
/// coarse for them).
fn halved(divisions: usize) -> usize {
    HALVED.min((divisions / 2).saturating_sub(1))
}

/// The node coordinates along an axis of `divisions` intervals (the first and last
/// [`HALVED`] halved), metres, ascending from 0 to the side.
pub fn coordinates(divisions: usize) -> Vec<f64> {
    let (d, h) = (divisions, halved(divisions));
    let s = CUBE_SIDE_M / d as f64;
    let n = d + 2 * h;
    (0..=n)
        .map(|i| {
            if i == n {
                CUBE_SIDE_M
            } else if i <= 2 * h {
                0.5 * s * i as f64
            } else if i + 2 * h >= n {
                CUBE_SIDE_M - 0.5 * s * (n - i) as f64
            } else {
                s * (i - h) as f64
            }
        })
        .collect()
}

/// The faces of one fine mesh and the columns it keeps.
#[derive(Debug, Clone, PartialEq)]
pub struct Family {
    /// The normal axis of its faces (2: the top face; 0: x = 0 and x = L; 1: y = 0 and y = L).
    pub axis: usize,
    /// The face's in-plane axes `(u, v)`.
    pub plane: [usize; 2],
    /// The solved coordinates along `u` and along `v`.
    pub solved: [Vec<usize>; 2],
    /// For each coordinate along `u` and `v` (after mirroring), the nearest solved one.
    nearest: [Vec<usize>; 2],
    /// The lattice points a column holds (`[i, j, k]`).
    pub targets: Vec<[usize; 3]>,
    /// Lattice index `i + s (j + s k)` to target, `u32::MAX` where not held.
    table: Vec<u32>,
    /// Where the family's columns start.
    pub offset: usize,
}

/// How a surface node's column is found: its family, the mirror flips that bring it into the
/// family's kept region, the solved column, and the shift from the node to that column's node.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Source {
    /// Family index (0 top, 1 x, 2 y).
    pub family: u8,
    /// Mirrored in x, in y.
    pub flip: [bool; 2],
    /// The solved column's index within the family.
    pub column: u32,
    /// Lattice offset from the (mirrored) node to the solved column's node.
    pub shift: [i8; 3],
}

/// The surface lattice of `divisions` divisions per axis.
#[derive(Debug, Clone, PartialEq)]
pub struct Lattice {
    /// Divisions per axis (even), before halving those at the ends.
    pub divisions: usize,
    /// Node coordinates along every axis ([`coordinates`]), metres.
    pub coords: Vec<f64>,
    /// The top face's family, the x faces', the y faces'.
    pub families: [Family; 3],
    /// Values held: all families' columns.
    pub values: usize,
}

impl Lattice {
    /// The lattice of `divisions` (even, at least 2) divisions per axis.
    pub fn new(divisions: usize) -> Self {
        let coords = coordinates(divisions);
        let extra = halved(divisions);
        let d = coords.len() - 1;
        let h = d / 2;
        let edge = EDGE_ROWS + extra;
        // The side faces' nodes: below the top face's row; those on a vertical edge are the x faces'.
        let (mirrored, height) = (solved_along(0, h, false, d, edge), solved_along(1, d - 1, true, d, edge));
        let inner = solved_along(1, h, false, d, edge);
        let mut offset = 0;
        let families = [
            (2, [0, 1], [mirrored.clone(), mirrored.clone()]),
            (0, [1, 2], [mirrored, height.clone()]),
            (1, [0, 2], [inner, height]),
        ]
        .map(|(axis, plane, solved): (usize, [usize; 2], [Vec<usize>; 2])| {
            let band = d.saturating_sub(BAND_ROWS + extra);
            let targets: Vec<[usize; 3]> = all_surface(d).filter(|q| q[axis] >= band && q[axis] >= 1).collect();
            let side = d + 1;
            let mut table = vec![u32::MAX; side * side * side];
            for (t, q) in targets.iter().enumerate() {
                table[q[0] + side * (q[1] + side * q[2])] = t as u32;
            }
            let nearest = [0, 1].map(|a| nearest_of(&solved[a], d));
            let f = Family { axis, plane, solved, nearest, targets, table, offset };
            offset += f.columns() * 9 * f.targets.len();
            f
        });
        Self { divisions, coords, families, values: offset }
    }

    /// The last index along an axis (intervals per axis, the halved ones counted).
    pub fn last(&self) -> usize {
        self.coords.len() - 1
    }

    /// Lattice nodes per axis.
    pub fn side(&self) -> usize {
        self.coords.len()
    }

    /// Surface nodes: the top face, the faces x = 0 and x = L without their top and bottom rows,
    /// the faces y = 0 and y = L without those and without their vertical edges.
    pub fn len(&self) -> usize {
        let (s, m) = (self.side(), self.last() - 1);
        s * s + 2 * s * m + 2 * m * m
    }

    /// Whether the lattice has no surface node (never).
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The surface node at lattice point `q`, if it is one.
    pub fn index(&self, q: [usize; 3]) -> Option<usize> {
        let (d, s) = (self.last(), self.side());
        let m = d - 1;
        let [i, j, k] = q;
        if i > d || j > d || k > d || k == 0 {
            return None;
        }
        if k == d {
            return Some(i + s * j);
        }
        let top = s * s;
        if i == 0 || i == d {
            return Some(top + usize::from(i == d) * s * m + j + s * (k - 1));
        }
        if j == 0 || j == d {
            return Some(top + 2 * s * m + usize::from(j == d) * m * m + (i - 1) + m * (k - 1));
        }
        None
    }

    /// The lattice point of surface node `q`.
    pub fn point(&self, q: usize) -> [usize; 3] {
        let (d, s) = (self.last(), self.side());
        let m = d - 1;
        if q < s * s {
            return [q % s, q / s, d];
        }
        let r = q - s * s;
        if r < 2 * s * m {
            let (face, r) = (r / (s * m), r % (s * m));
            return [face * d, r % s, 1 + r / s];
        }
        let r = r - 2 * s * m;
        let (face, r) = (r / (m * m), r % (m * m));
        [1 + r % m, face * d, 1 + r / m]
    }

    /// How surface node `p`'s column is found.
    pub fn source(&self, p: [usize; 3]) -> Source {
        let (d, h) = (self.last(), self.last() / 2);
        let (family, flip) = if p[2] == d {
            (0, [p[0] > h, p[1] > h])
        } else if p[0] == 0 || p[0] == d {
            (1, [p[0] == 0, p[1] > h])
        } else {
            (2, [p[0] > h, p[1] == 0])
        };
        let f = &self.families[family];
        let m = mirror(p, flip, d);
        let mut shift = [0i8; 3];
        let mut at = [0usize; 2];
        for (a, &axis) in f.plane.iter().enumerate() {
            let n = f.nearest[a][m[axis]];
            shift[axis] = (n as i64 - m[axis] as i64) as i8;
            at[a] = f.solved[a].binary_search(&n).unwrap_or(0);
        }
        let column = (at[0] + f.solved[0].len() * at[1]) as u32;
        Source { family: family as u8, flip, column, shift }
    }

    /// Where surface node `q`'s displacement under `source`'s column is held: the family's target,
    /// with `q` mirrored and shifted as the source is (along the axes on which `q` is not on a face
    /// of the cube: a node on a neighbouring face stays on it). `None` where the column does not
    /// hold it.
    #[inline]
    pub fn target(&self, source: &Source, q: [usize; 3]) -> Option<usize> {
        let d = self.last();
        let f = &self.families[source.family as usize];
        let mut m = mirror(q, source.flip, d);
        for c in 0..3 {
            let s = source.shift[c];
            if s != 0 && m[c] != 0 && m[c] != d {
                m[c] = (m[c] as i64 + i64::from(s)).clamp(0, d as i64) as usize;
            }
        }
        let side = d + 1;
        let t = f.table[m[0] + side * (m[1] + side * m[2])];
        (t != u32::MAX).then_some(t as usize)
    }
}

impl Family {
    /// The target at lattice point `q` (every index at most `last`), if the family's columns hold it.
    pub fn target_at(&self, q: [usize; 3], last: usize) -> Option<usize> {
        let side = last + 1;
        let t = *self.table.get(q[0] + side * (q[1] + side * q[2]))?;
        (t != u32::MAX).then_some(t as usize)
    }

    /// Columns' nodes solved.
    pub fn columns(&self) -> usize {
        self.solved[0].len() * self.solved[1].len()
    }

    /// The lattice point of solved column `c` (on the face `axis = L`, of index `last`).
    pub fn column_point(&self, c: usize, last: usize) -> [usize; 3] {
        let n = self.solved[0].len();
        let mut p = [0; 3];
        p[self.axis] = last;
        p[self.plane[0]] = self.solved[0][c % n];
        p[self.plane[1]] = self.solved[1][c / n];
        p
    }
}

/// `q` mirrored in x and y as `flip` says.
#[inline]
fn mirror(q: [usize; 3], flip: [bool; 2], d: usize) -> [usize; 3] {
    [if flip[0] { d - q[0] } else { q[0] }, if flip[1] { d - q[1] } else { q[1] }, q[2]]
}

/// The solved indices on `[lo, hi]`: every one within `edge` of an edge (at 0, and at `d` where
/// `far_edge`), every [`STRIDE`]th between, and `hi`.
fn solved_along(lo: usize, hi: usize, far_edge: bool, d: usize, edge: usize) -> Vec<usize> {
    (lo..=hi)
        .filter(|&c| c <= edge || (far_edge && c + edge >= d) || (c - edge).is_multiple_of(STRIDE) || c == hi)
        .collect()
}

/// For every coordinate on `[0, d]`, the nearest of `solved` (the lower on a tie).
fn nearest_of(solved: &[usize], d: usize) -> Vec<usize> {
    (0..=d).map(|c| *solved.iter().min_by_key(|&&s| (s.abs_diff(c), s)).unwrap_or(&c)).collect()
}

/// Every lattice point on the free surface (`k > 0`), in no particular order.
fn all_surface(d: usize) -> impl Iterator<Item = [usize; 3]> {
    (1..=d).flat_map(move |k| {
        (0..=d).flat_map(move |j| {
            (0..=d).filter_map(move |i| (k == d || i == 0 || i == d || j == 0 || j == d).then_some([i, j, k]))
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_surface_node_has_one_index_and_a_column_near_it() {
        for d in [2, 10, 50] {
            let l = Lattice::new(d);
            let x = &l.coords;
            assert!(x.windows(2).all(|w| w[1] > w[0]) && x[0] == 0.0 && x[l.last()] == CUBE_SIDE_M);
            assert!((0..=l.last()).all(|i| (x[i] + x[l.last() - i] - CUBE_SIDE_M).abs() < 1e-15), "{x:?}");
            for q in 0..l.len() {
                let p = l.point(q);
                assert_eq!(l.index(p), Some(q), "{d} {p:?}");
                let s = l.source(p);
                assert!(s.shift.iter().all(|v| v.abs() <= 1), "{p:?} {s:?}");
                assert!(l.target(&s, p).is_some(), "{d}: the node itself {p:?}");
            }
            assert_eq!(all_surface(l.last()).count(), l.len());
        }
        let l = Lattice::new(50);
        // 1 mm rows across the edges, 2 mm between.
        assert_eq!(l.last(), 54);
        assert!((l.coords[4] - 0.004).abs() < 1e-15 && (l.coords[5] - 0.006).abs() < 1e-15, "{:?}", l.coords);
        // Near a corner every column is solved, near an edge it shifts along the edge only; a
        // twentieth or so in all.
        assert_eq!(l.source([2, 52, 54]).shift, [0, 0, 0]);
        assert_eq!(l.source([2, 30, 54]).shift[0], 0);
        assert_eq!(l.source([54, 30, 53]).shift[2], 0);
        let solved: usize = l.families.iter().map(Family::columns).sum();
        assert!(solved < l.len() / 16, "{solved}");
    }
}
