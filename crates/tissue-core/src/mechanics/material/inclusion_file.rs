//! The keys of a material file's `[[inclusion]]` tables (TOML) or `"inclusion"` array (JSON),
//! read into [`Inclusion`]s: each is checked like every input, with a one-line error naming the
//! inclusion: inside the cube, clear of the clamped face z = 0, not overlapping another, its
//! stiffness positive definite and within the moduli the solvers represent.

use nalgebra::Matrix6;
use serde::Deserialize;

use super::{MODULUS_RANGE_PA, MaterialFile, Symmetry};
use crate::mechanics::grid::CUBE_SIDE_M;
use crate::mechanics::inclusion::Inclusion;

/// The keys of one `[[inclusion]]` of a material file: `centre` and `radius` (metres), and either
/// `scale` or its own moduli (the keys of a material: `symmetry`, `units`, `E1`, ...).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs, non_snake_case)]
pub struct InclusionFile {
    #[serde(deserialize_with = "crate::io::shape::numbers")]
    pub centre: [f64; 3],
    pub radius: f64,
    pub scale: Option<f64>,
    pub symmetry: Option<Symmetry>,
    pub units: Option<String>,
    pub E1: Option<f64>,
    pub E2: Option<f64>,
    pub E3: Option<f64>,
    pub nu12: Option<f64>,
    pub nu13: Option<f64>,
    pub nu23: Option<f64>,
    pub G12: Option<f64>,
    pub G13: Option<f64>,
    pub G23: Option<f64>,
}

impl InclusionFile {
    /// The moduli it gives as a material file's keys, if any, in its `units` or else the file's
    /// (`units`).
    fn moduli(&self, units: Option<&str>) -> Option<MaterialFile> {
        let given = [self.E1, self.E2, self.E3, self.nu12, self.nu13, self.nu23, self.G12, self.G13, self.G23];
        if self.symmetry.is_none() && self.units.is_none() && given.iter().all(Option::is_none) {
            return None;
        }
        Some(MaterialFile {
            name: None,
            symmetry: self.symmetry.unwrap_or(Symmetry::Orthotropic),
            units: self.units.clone().or_else(|| units.map(str::to_owned)),
            density: None,
            E1: self.E1,
            E2: self.E2,
            E3: self.E3,
            nu12: self.nu12,
            nu13: self.nu13,
            nu23: self.nu23,
            G12: self.G12,
            G13: self.G13,
            G23: self.G23,
            inclusion: Vec::new(),
        })
    }
}

/// The inclusions `files` list, in a background of stiffness `background` whose file gives its
/// moduli in `units` (an inclusion's own moduli are in these unless it says), checked; the error
/// is one line naming the inclusion (1-based) and what is wrong.
pub fn read(files: &[InclusionFile], background: &Matrix6<f64>, units: Option<&str>) -> Result<Vec<Inclusion>, String> {
    let mut out: Vec<Inclusion> = Vec::with_capacity(files.len());
    for (i, f) in files.iter().enumerate() {
        let n = i + 1;
        let say = |what: String| format!("inclusion {n}: {what}");
        if !f.centre.iter().all(|c| c.is_finite()) || !f.radius.is_finite() {
            return Err(say("its centre and radius must be finite numbers".into()));
        }
        if f.radius <= 0.0 {
            return Err(say(format!("its radius must be positive, got {}", crate::io::num(f.radius))));
        }
        let l = CUBE_SIDE_M;
        if f.centre[2] - f.radius <= 0.0 {
            return Err(say(format!(
                "its sphere (centre z = {} m, radius {} m) reaches the clamped face z = 0",
                crate::io::num(f.centre[2]),
                crate::io::num(f.radius)
            )));
        }
        if (0..3).any(|a| f.centre[a] - f.radius < 0.0 || f.centre[a] + f.radius > l) {
            return Err(say(format!(
                "its sphere (centre {:?} m, radius {} m) is not inside the cube (0 to {l} m per axis)",
                f.centre,
                crate::io::num(f.radius)
            )));
        }
        let stiffness = match (f.scale, f.moduli(units)) {
            (Some(_), Some(_)) => return Err(say("give either scale or its own moduli, not both".into())),
            (None, None) => return Err(say("give its stiffness: scale, or its own moduli (symmetry, E1, ...)".into())),
            (Some(s), None) => {
                if !s.is_finite() || s <= 0.0 {
                    return Err(say(format!("scale must be a positive number, got {s}")));
                }
                let c = background * s;
                let largest = (0..6).map(|k| c[(k, k)]).fold(0.0, f64::max);
                let smallest = (0..6).map(|k| c[(k, k)]).fold(f64::INFINITY, f64::min);
                if largest > MODULUS_RANGE_PA.1 || smallest < MODULUS_RANGE_PA.0 {
                    return Err(say(format!("scale {s} takes the stiffness outside 1 Pa to 1e10 Pa")));
                }
                c
            }
            (None, Some(m)) => {
                if f.symmetry.is_none() {
                    return Err(say("give the symmetry of its moduli".into()));
                }
                m.into_material("inclusion").map_err(|e| say(e.to_string()))?.stiffness
            }
        };
        let inclusion = Inclusion { centre: f.centre, radius: f.radius, stiffness };
        if let Some(j) = out.iter().position(|o| {
            let d: f64 = (0..3).map(|a| (o.centre[a] - f.centre[a]).powi(2)).sum::<f64>().sqrt();
            d < o.radius + f.radius
        }) {
            return Err(say(format!("it overlaps inclusion {}", j + 1)));
        }
        out.push(inclusion);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mechanics::material::Material;

    fn lump(centre: [f64; 3], radius: f64, scale: Option<f64>) -> InclusionFile {
        let text = match scale {
            Some(s) if s.is_nan() => format!("centre = {centre:?}\nradius = {radius}\nscale = nan\n"),
            Some(s) => format!("centre = {centre:?}\nradius = {radius}\nscale = {s:?}\n"),
            None => format!("centre = {centre:?}\nradius = {radius}\n"),
        };
        toml::from_str(&text).expect("parses")
    }

    #[test]
    fn an_inclusions_own_moduli_are_in_the_files_units_unless_it_says() {
        let c = Material::object_a().stiffness;
        let own = "centre = [0.05, 0.05, 0.05]\nradius = 0.005\nsymmetry = \"transversely_isotropic\"\n\
                   E1 = 500.0\nE2 = 400.0\nnu12 = 0.3\nnu23 = 0.3\nG12 = 150.0\n";
        let f: InclusionFile = toml::from_str(own).expect("parses");
        let kpa = read(std::slice::from_ref(&f), &c, Some("kPa")).expect("in kPa");
        let pa = read(&[toml::from_str(&format!("{own}units = \"Pa\"\n")).expect("parses")], &c, Some("kPa"));
        assert!((kpa[0].stiffness[(0, 0)] / 5e5 - 1.0).abs() < 1.0, "{}", kpa[0].stiffness[(0, 0)]);
        assert!((pa.expect("in Pa")[0].stiffness[(0, 0)] * 1e3 / kpa[0].stiffness[(0, 0)] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn an_inclusion_is_checked() {
        let c = Material::object_a().stiffness;
        let ok = read(&[lump([0.05, 0.05, 0.082], 0.008, Some(5.0))], &c, None).expect("a valid lump");
        assert_eq!(ok[0].stiffness, c * 5.0);
        for (files, needle) in [
            (vec![lump([0.05, 0.05, 0.005], 0.008, Some(2.0))], "clamped face"),
            (vec![lump([0.095, 0.05, 0.05], 0.008, Some(2.0))], "not inside the cube"),
            (vec![lump([0.05, 0.05, 0.05], -0.001, Some(2.0))], "radius must be positive"),
            (vec![lump([0.05, 0.05, 0.05], 0.008, Some(-2.0))], "scale must be a positive"),
            (vec![lump([0.05, 0.05, 0.05], 0.008, Some(f64::NAN))], "scale must be a positive"),
            (vec![lump([0.05, 0.05, 0.05], 0.008, None)], "give its stiffness"),
            (vec![lump([0.05, 0.05, 0.05], 0.008, Some(2.0)), lump([0.05, 0.05, 0.06], 0.005, Some(3.0))], "overlaps"),
        ] {
            let e = read(&files, &c, None).expect_err(needle);
            assert!(e.contains(needle) && e.starts_with("inclusion ") && !e.contains('\n'), "{e}");
        }
    }
}
