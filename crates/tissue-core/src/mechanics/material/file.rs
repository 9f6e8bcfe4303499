//! Reading a material from a TOML or JSON file ([`MaterialFile`]'s keys), inclusions included
//! ([`super::inclusion_file`]).

use std::path::Path;

use serde::Deserialize;

use super::{EngineeringConstants, Material, MaterialError, Symmetry, TISSUE_DENSITY};
use super::inclusion_file::{self, InclusionFile};

impl Material {
    /// Reads a material from a TOML or JSON file (chosen by extension; `.json` is JSON, anything
    /// else TOML). See [`MaterialFile`] for the keys.
    pub fn from_file(path: &Path) -> Result<Self, MaterialError> {
        let shown = path.display().to_string();
        // The one bounded reading path of every input file.
        let text = crate::io::read_text(path).map_err(|e| MaterialError::Read(format!("{e:#}")))?;
        let is_json = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("json"));
        // The shape checked alike in both: the key an error is at, lists of the wrong length.
        let file: MaterialFile = if is_json { crate::io::shape::from_json(&text) } else { crate::io::shape::from_toml(&text) }
            .map_err(|message| MaterialError::Parse { path: shown.clone(), message })?;
        let default_name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("custom");
        file.into_material(default_name).map_err(|e| match e {
            MaterialError::Parse { message, .. } => MaterialError::Parse { path: shown, message },
            other => other,
        })
    }
}

/// The keys of a material file. Moduli are in `units` (`Pa` by default, or `kPa`), density in kg/m^3.
///
/// ```toml
/// name = "liver"                   # optional, the file stem otherwise
/// symmetry = "orthotropic"         # or "transversely_isotropic"
/// units = "kPa"                    # optional, "Pa" by default
/// density = 1040.0                 # optional, 1040 kg/m^3 by default
/// E1 = 179.0
/// E2 = 188.0
/// E3 = 228.0                       # orthotropic only
/// nu12 = 0.26
/// nu13 = 0.30                      # orthotropic only
/// nu23 = 0.31
/// G12 = 57.1
/// G13 = 65.8                       # orthotropic only
/// G23 = 71.1                       # orthotropic only
///
/// [[inclusion]]                    # optional, any number: a sphere of another stiffness
/// centre = [0.05, 0.05, 0.082]     # metres
/// radius = 0.008                   # metres
/// scale = 5.0                      # or its own moduli with the keys above
/// ```
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
#[allow(missing_docs, non_snake_case)]
pub struct MaterialFile {
    pub name: Option<String>,
    pub symmetry: Symmetry,
    pub units: Option<String>,
    pub density: Option<f64>,
    pub E1: Option<f64>,
    pub E2: Option<f64>,
    pub E3: Option<f64>,
    pub nu12: Option<f64>,
    pub nu13: Option<f64>,
    pub nu23: Option<f64>,
    pub G12: Option<f64>,
    pub G13: Option<f64>,
    pub G23: Option<f64>,
    #[serde(default)]
    pub inclusion: Vec<InclusionFile>,
}

impl MaterialFile {
    /// The material the keys give, inclusions checked against its stiffness.
    pub(crate) fn into_material(self, default_name: &str) -> Result<Material, MaterialError> {
        let parse = |message: String| MaterialError::Parse { path: String::new(), message };
        let scale = match self.units.as_deref().unwrap_or("Pa") {
            "Pa" => 1.0,
            "kPa" => 1e3,
            "MPa" => 1e6,
            other => return Err(parse(format!("units must be Pa, kPa or MPa, got {other:?}"))),
        };
        let need = |name: &str, v: Option<f64>| {
            v.ok_or_else(|| parse(format!("missing constant {name} for an {} material", self.symmetry.name())))
        };
        let name = self.name.clone().unwrap_or_else(|| default_name.to_owned());
        let density = self.density.unwrap_or(TISSUE_DENSITY);
        let background = match self.symmetry {
            Symmetry::Orthotropic => {
                let constants = EngineeringConstants {
                    e1: need("E1", self.E1)? * scale,
                    e2: need("E2", self.E2)? * scale,
                    e3: need("E3", self.E3)? * scale,
                    nu12: need("nu12", self.nu12)?,
                    nu13: need("nu13", self.nu13)?,
                    nu23: need("nu23", self.nu23)?,
                    g12: need("G12", self.G12)? * scale,
                    g13: need("G13", self.G13)? * scale,
                    g23: need("G23", self.G23)? * scale,
                };
                Material::orthotropic(name, constants, density)
            }
            Symmetry::TransverselyIsotropic => {
                for (key, v) in [("E3", self.E3), ("nu13", self.nu13), ("G13", self.G13), ("G23", self.G23)] {
                    if v.is_some() {
                        return Err(parse(format!(
                            "{key} is derived for a transversely isotropic material \
                             (E3 = E2, nu13 = nu12, G13 = G12, G23 = E2/(2(1+nu23))): remove it"
                        )));
                    }
                }
                Material::transversely_isotropic(
                    name,
                    need("E1", self.E1)? * scale,
                    need("E2", self.E2)? * scale,
                    need("nu12", self.nu12)?,
                    need("nu23", self.nu23)?,
                    need("G12", self.G12)? * scale,
                    density,
                )
            }
        }?;
        let inclusions =
            inclusion_file::read(&self.inclusion, &background.stiffness, self.units.as_deref()).map_err(parse)?;
        Ok(Material { inclusions, ..background })
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// A file of `text` named `name` in a fresh folder, read as a material.
    fn read(name: &str, text: &[u8]) -> Result<Material, MaterialError> {
        let dir = tempfile::tempdir().expect("a folder");
        let path = dir.path().join(name);
        std::fs::write(&path, text).expect("written");
        Material::from_file(&path)
    }

    /// A valid background and one inclusion with these keys, as TOML.
    fn with_inclusion(centre: &[f64], radius: f64, scale: f64) -> String {
        let list = centre.iter().map(|c| format!("{c:?}")).collect::<Vec<_>>().join(", ");
        format!(
            "symmetry = \"orthotropic\"\nunits = \"kPa\"\nE1 = 10.0\nE2 = 12.0\nE3 = 15.0\nnu12 = 0.3\nnu13 = 0.3\n\
             nu23 = 0.3\nG12 = 4.0\nG13 = 4.0\nG23 = 4.0\n\n[[inclusion]]\ncentre = [{list}]\nradius = {radius:?}\n\
             scale = {scale:?}\n"
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]

        /// Any bytes, as TOML or JSON, give a material or a one-line error, never a panic.
        #[test]
        fn any_bytes_are_a_material_or_one_line(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
            for name in ["m.toml", "m.json"] {
                if let Err(e) = read(name, &bytes) {
                    prop_assert!(!e.to_string().contains('\n'), "{}", e);
                }
            }
        }

        /// An inclusion near the bounds (any number of coordinates, sizes across the cube, any
        /// scale) is read as written, with finite numbers, or refused in one line naming it: a
        /// list of other than three coordinates is never cut or padded.
        #[test]
        fn an_inclusion_is_read_as_written_or_refused(
            centre in proptest::collection::vec(-0.02f64..0.12, 0..6),
            radius in -0.01f64..0.08,
            scale in prop_oneof![-2.0f64..30.0, Just(f64::MIN_POSITIVE), Just(1e12)],
        ) {
            match read("m.toml", with_inclusion(&centre, radius, scale).as_bytes()) {
                Ok(m) => {
                    prop_assert_eq!(centre.len(), 3);
                    prop_assert_eq!(m.inclusions.len(), 1);
                    let i = &m.inclusions[0];
                    prop_assert_eq!(i.centre.to_vec(), centre);
                    prop_assert_eq!(i.radius, radius);
                    prop_assert!(i.stiffness.iter().all(|v| v.is_finite()));
                }
                Err(e) => {
                    let e = e.to_string();
                    prop_assert!(!e.contains('\n') && e.contains("inclusion 1"), "{}", e);
                }
            }
        }
    }
}
