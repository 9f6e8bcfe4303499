//! A palpation map: the probe pressed at every point of a grid over one free face, the material's
//! settled force there (the viewer's contact on the material's surface compliance, inclusions
//! and all) beside the force of its background alone, and their contrast: where a hand would feel
//! what is hidden. [`plot`] draws it.

pub mod plot;

use glam::DVec3;
use serde::Serialize;

use crate::mechanics::grid::CUBE_SIDE_M;
use crate::mechanics::material::Material;
use crate::sim::material_surface::compliance::{SurfaceCompliance, SurfaceContactScratch};
use crate::sim::press;

/// The contrast a hand tells apart: forces about 7 % apart.
pub const FELT_CONTRAST: f64 = 0.07;

/// The free faces, by their names on the command line.
pub const FACES: [&str; 5] = ["+z", "+x", "-x", "+y", "-y"];

/// A free face of the cube: its normal axis and side, and the two axes across it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Face {
    /// The normal axis (0 x, 1 y, 2 z).
    pub axis: usize,
    /// `true` on the face at the side's end (`+`), `false` at 0.
    pub high: bool,
}

impl Face {
    /// The face named `name` ([`FACES`]), or why not (the clamped face `-z` among them).
    pub fn parse(name: &str) -> Result<Self, String> {
        let axis = match name.get(1..) {
            Some("x") => 0,
            Some("y") => 1,
            Some("z") => 2,
            _ => return Err(format!("unknown face {name:?}: the free faces are {}", FACES.join(", "))),
        };
        let high = match name.get(..1) {
            Some("+") => true,
            Some("-") => false,
            _ => return Err(format!("unknown face {name:?}: the free faces are {}", FACES.join(", "))),
        };
        if axis == 2 && !high {
            return Err("the face -z is clamped: the free faces are +z, +x, -x, +y, -y".into());
        }
        Ok(Self { axis, high })
    }

    /// Its name ([`FACES`]).
    pub fn name(self) -> String {
        format!("{}{}", if self.high { '+' } else { '-' }, ["x", "y", "z"][self.axis])
    }

    /// The axes across it, `(u, v)`: x and y on the top face, the other horizontal axis and z on
    /// a side.
    pub fn across(self) -> [usize; 2] {
        match self.axis {
            0 => [1, 2],
            1 => [0, 2],
            _ => [0, 1],
        }
    }

    /// The outward normal.
    pub fn normal(self) -> DVec3 {
        let mut n = DVec3::ZERO;
        n[self.axis] = if self.high { 1.0 } else { -1.0 };
        n
    }

    /// The point of the face at `(u, v)` across it, metres.
    pub fn point(self, u: f64, v: f64) -> [f64; 3] {
        let [a, b] = self.across();
        let mut p = [0.0; 3];
        p[self.axis] = if self.high { CUBE_SIDE_M } else { 0.0 };
        p[a] = u;
        p[b] = v;
        p
    }
}

/// What is pressed: the probe's radius and depth (metres) at an `grid` x `grid` lattice of points
/// over `face`, each in the middle of its cell.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Palpation {
    /// The face pressed.
    pub face: Face,
    /// Probe radius, metres.
    pub radius: f64,
    /// Depth of each press, metres.
    pub depth: f64,
    /// Points per side.
    pub grid: usize,
}

/// The most points per side.
pub const MAX_GRID: usize = 101;

impl Palpation {
    /// Checks the presses (the probe's limits at every point, [`press::check`]) and the grid.
    pub fn check(&self) -> Result<(), String> {
        if !(1..=MAX_GRID).contains(&self.grid) {
            return Err(format!("a grid of {} points per side is outside 1 to {MAX_GRID}", self.grid));
        }
        if !(self.depth.is_finite() && self.depth > 0.0) {
            return Err(format!("depth {} m: a press goes into the tissue (depth above 0)", self.depth));
        }
        let inward = (-self.face.normal()).to_array();
        for at in self.points() {
            press::check(at, inward, self.radius, self.depth, true, &|p| p[2] <= 0.0)?;
        }
        let (at, least) = self.shallowest_touching();
        if self.depth < least {
            return Err(format!(
                "depth {}: the press at {} mm touches none of the material's surface nodes; every press of the \
                 grid touches from {} deep",
                crate::io::length(self.depth),
                at.map(|c| crate::io::num(c * 1e3)).join(", "),
                crate::io::length((least * 1e6).ceil() * 1e-6)
            ));
        }
        Ok(())
    }

    /// The depth from which every press of the grid touches a node of the material's surface
    /// lattice (the contact's nodes; a shallower sphere between them reads 0 N), metres, and the
    /// point that needs it: a node `r` across from the point is touched `R - sqrt(R^2 - r^2)` deep.
    fn shallowest_touching(&self) -> ([f64; 3], f64) {
        let nodes = crate::sim::material_surface::compliance::lattice::coordinates(
            crate::sim::material_surface::compliance::DEFAULT_DIVISIONS,
        );
        let nearest = |x: f64| nodes.iter().map(|c| (c - x).abs()).fold(f64::INFINITY, f64::min);
        let r = self.radius;
        self.points()
            .into_iter()
            .map(|at| {
                let across: f64 = (0..3).filter(|&a| a != self.face.axis).map(|a| nearest(at[a]).powi(2)).sum();
                (at, r - (r * r - across.min(r * r)).sqrt())
            })
            .fold(([0.0; 3], 0.0), |a, b| if b.1 > a.1 { b } else { a })
    }

    /// The points pressed, row by row (`v` outer, `u` inner), metres.
    pub fn points(&self) -> Vec<[f64; 3]> {
        let n = self.grid;
        let at = |i: usize| CUBE_SIDE_M * (i as f64 + 0.5) / n as f64;
        (0..n).flat_map(|j| (0..n).map(move |i| self.face.point(at(i), at(j)))).collect()
    }

    /// The settled force along the press at each point, newtons, on `compliance`; `each` is
    /// called after every press.
    pub fn forces(&self, compliance: &SurfaceCompliance, each: &mut dyn FnMut()) -> Result<Vec<f64>, String> {
        let n = self.face.normal();
        let mut scratch = SurfaceContactScratch::default();
        self.points()
            .into_iter()
            .map(|at| {
                scratch.clear();
                let centre = press::centre(at, -n, self.radius, self.depth);
                let f = compliance.press(centre, self.radius, &mut scratch).map_err(|e| format!("at {at:?}: {e}"))?;
                each();
                Ok(DVec3::from(f).dot(n))
            })
            .collect()
    }
}

/// An inclusion as the map shows it.
#[derive(Debug, Clone, Serialize)]
pub struct MapInclusion {
    /// Centre, metres.
    pub centre: [f64; 3],
    /// Radius, metres.
    pub radius: f64,
    /// Depth of its top under the face pressed, metres.
    pub depth_under_face: f64,
}

/// A palpation map (`map.json`).
#[derive(Debug, Clone, Serialize)]
pub struct PalpationMap {
    /// The material's name.
    pub material: String,
    /// The face pressed ([`FACES`]).
    pub face: String,
    /// Probe radius, metres.
    pub radius_m: f64,
    /// Depth of each press, metres.
    pub depth_m: f64,
    /// Points per side.
    pub grid: usize,
    /// The points pressed, metres, row by row (the face's second axis outer, its first inner:
    /// x then y on the top face; y then z on an x face; x then z on a y face).
    pub points: Vec<[f64; 3]>,
    /// The material's settled force along the press at each point, newtons.
    pub forces: Vec<f64>,
    /// The background's (the material without its inclusions), newtons.
    pub background_forces: Vec<f64>,
    /// `forces / background_forces - 1` at each point.
    pub contrast: Vec<f64>,
    /// The contrast a hand tells apart ([`FELT_CONTRAST`]).
    pub felt_contrast: f64,
    /// The material's inclusions.
    pub inclusions: Vec<MapInclusion>,
}

impl PalpationMap {
    /// The map of `palpation` on `material` from its compliance and its background's.
    pub fn new(material: &Material, palpation: &Palpation, forces: Vec<f64>, background_forces: Vec<f64>) -> Self {
        let face = palpation.face;
        let contrast = forces.iter().zip(&background_forces).map(|(f, b)| f / b - 1.0).collect();
        let inclusions = material
            .inclusions
            .iter()
            .map(|i| {
                let surface = if face.high { CUBE_SIDE_M } else { 0.0 };
                let depth = (surface - i.centre[face.axis]).abs() - i.radius;
                MapInclusion { centre: i.centre, radius: i.radius, depth_under_face: depth }
            })
            .collect();
        Self {
            material: material.name.clone(),
            face: face.name(),
            radius_m: palpation.radius,
            depth_m: palpation.depth,
            grid: palpation.grid,
            points: palpation.points(),
            forces,
            background_forces,
            contrast,
            felt_contrast: FELT_CONTRAST,
            inclusions,
        }
    }

    /// The largest contrast either way, and where.
    pub fn peak(&self) -> Option<(f64, [f64; 3])> {
        self.contrast.iter().zip(&self.points).map(|(&c, &p)| (c, p)).max_by(|a, b| a.0.abs().total_cmp(&b.0.abs()))
    }

    /// Points where the contrast passes [`FELT_CONTRAST`] either way (a lump stiffer or softer
    /// than the tissue).
    pub fn felt(&self) -> usize {
        self.contrast.iter().filter(|&&c| c.abs() > FELT_CONTRAST).count()
    }

    /// `map.csv`: one row per point.
    pub fn csv(&self) -> Result<Vec<u8>, csv::Error> {
        let mut w = csv::Writer::from_writer(Vec::new());
        w.write_record(["x_m", "y_m", "z_m", "force_n", "background_force_n", "contrast"])?;
        for (k, p) in self.points.iter().enumerate() {
            let row = [p[0], p[1], p[2], self.forces[k], self.background_forces[k], self.contrast[k]];
            w.write_record(row.map(|v| format!("{v}")))?;
        }
        w.into_inner().map_err(|e| csv::Error::from(e.into_error()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn faces_read_their_names_and_refuse_the_clamped_one() {
        for name in FACES {
            assert_eq!(Face::parse(name).map(Face::name).as_deref(), Ok(name));
        }
        assert!(Face::parse("-z").unwrap_err().contains("clamped"));
        assert!(Face::parse("z").is_err() && Face::parse("+w").is_err());
        let p = Palpation { face: Face::parse("-y").unwrap(), radius: 0.015, depth: 0.004, grid: 2 };
        let expected = [[0.025, 0.0, 0.025], [0.075, 0.0, 0.025], [0.025, 0.0, 0.075], [0.075, 0.0, 0.075]];
        for (a, b) in p.points().iter().zip(&expected) {
            assert!((0..3).all(|c| (a[c] - b[c]).abs() < 1e-15), "{a:?} {b:?}");
        }
        assert!(p.check().is_ok());
        assert!(Palpation { grid: 0, ..p }.check().is_err());
        assert!(Palpation { depth: 0.02, ..p }.check().is_err());
    }
}
