//! Spherical inclusions inside the cube: a lump of another stiffness (a nodule, a tumour) in the
//! background material. A material file lists them as `[[inclusion]]` tables (TOML) or an
//! `"inclusion"` array (JSON):
//!
//! ```toml
//! [[inclusion]]
//! centre = [0.05, 0.05, 0.082]     # metres, the cube spans 0 to 0.1 m per axis
//! radius = 0.008                   # metres
//! scale = 5.0                      # its stiffness C is 5 times the background's
//! # or, instead of `scale`, its own moduli with the keys of a material:
//! # symmetry = "orthotropic", E1 = ..., nu12 = ..., G12 = ... (in the file's `units` unless
//! # it gives its own)
//! ```
//!
//! The file's keys are read and checked in [`crate::mechanics::material::inclusion_file`].

use nalgebra::Matrix6;

/// A sphere of its own stiffness inside the cube.
#[derive(Debug, Clone, PartialEq)]
pub struct Inclusion {
    /// Centre, metres.
    pub centre: [f64; 3],
    /// Radius, metres.
    pub radius: f64,
    /// Its stiffness `C` (Pa, Voigt order).
    pub stiffness: Matrix6<f64>,
}

impl Inclusion {
    /// Whether the point `x` (metres) lies inside the sphere.
    #[inline]
    pub fn contains(&self, x: [f64; 3]) -> bool {
        (0..3).map(|a| (x[a] - self.centre[a]).powi(2)).sum::<f64>() < self.radius * self.radius
    }

    /// How the axis-aligned box `[lo, hi]` (metres) meets the sphere: `Some(true)` inside it,
    /// `Some(false)` outside it, `None` cut by its surface.
    pub fn meets_box(&self, lo: [f64; 3], hi: [f64; 3]) -> Option<bool> {
        let r2 = self.radius * self.radius;
        let nearest: f64 = (0..3).map(|a| (self.centre[a].clamp(lo[a], hi[a]) - self.centre[a]).powi(2)).sum();
        if nearest >= r2 {
            return Some(false);
        }
        let farthest: f64 =
            (0..3).map(|a| (self.centre[a] - lo[a]).abs().max((hi[a] - self.centre[a]).abs()).powi(2)).sum();
        (farthest <= r2).then_some(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sphere_knows_its_inside_and_the_boxes_it_meets() {
        let lump = Inclusion { centre: [0.05, 0.05, 0.082], radius: 0.008, stiffness: Matrix6::identity() };
        assert!(lump.contains([0.05, 0.05, 0.089]) && !lump.contains([0.05, 0.05, 0.091]));
        assert_eq!(lump.meets_box([0.048, 0.048, 0.08], [0.052, 0.052, 0.084]), Some(true));
        assert_eq!(lump.meets_box([0.0, 0.0, 0.0], [0.01, 0.01, 0.01]), Some(false));
        assert_eq!(lump.meets_box([0.05, 0.05, 0.088], [0.06, 0.06, 0.095]), None);
    }
}
