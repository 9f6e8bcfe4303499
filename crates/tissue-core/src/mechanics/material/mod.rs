//! Linear-elastic anisotropic materials: engineering constants to compliance `S` and stiffness `C`.
//!
//! Voigt order is (11, 22, 33, 23, 13, 12) with engineering shear strain `gamma_ij = 2 eps_ij`
//! (`shared/spec/benchmark.md`). All moduli are in Pa, density in kg/m^3.
//!
//! `nu_ij = -eps_j / eps_i` under uniaxial stress along `i`, so `nu_ij / E_i = nu_ji / E_j`.

use nalgebra::Matrix6;
use serde::Deserialize;

use crate::mechanics::inclusion::Inclusion;

mod file;
pub mod inclusion_file;
pub use file::MaterialFile;

/// Density of the paper's tissue, kg/m^3.
pub const TISSUE_DENSITY: f64 = 1040.0;

/// Errors raised while building or reading a material.
#[derive(Debug, thiserror::Error)]
pub enum MaterialError {
    /// A constant is NaN or infinite.
    #[error("material constant {name} is not a finite number ({value})")]
    NotFinite {
        /// Name of the constant, e.g. `E1`.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A modulus or the density is zero or negative.
    #[error("material constant {name} must be positive, got {}", crate::io::num(*value))]
    NonPositive {
        /// Name of the constant.
        name: &'static str,
        /// The offending value.
        value: f64,
    },
    /// A modulus or the density lies outside what the solvers can represent.
    #[error("material constant {name} = {} is out of range ({range})", crate::io::num(*value))]
    OutOfRange {
        /// Name of the constant.
        name: &'static str,
        /// The offending value.
        value: f64,
        /// The accepted range, in words.
        range: &'static str,
    },
    /// The stiffness matrix `C` is not positive definite.
    #[error("material stiffness C is not positive definite: {0}")]
    NotPositiveDefinite(String),
    /// A material file could not be read (or is above the input bound).
    #[error("material file: {0}")]
    Read(String),
    /// The material has inclusions where what is asked models a homogeneous one only.
    #[error("material {name} has {count} inclusion(s): {what} does not model inclusions yet")]
    Heterogeneous {
        /// The material's name.
        name: String,
        /// How many inclusions.
        count: usize,
        /// What was asked, in words.
        what: &'static str,
    },
    /// A material file could not be parsed or misses a constant.
    #[error("invalid material file {path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
}

/// The kind of anisotropy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Symmetry {
    /// Nine independent constants.
    Orthotropic,
    /// Axis 1 distinct, the 2-3 plane isotropic: five independent constants.
    TransverselyIsotropic,
}

impl Symmetry {
    /// The name in words, as a material file spells it (with spaces).
    pub fn name(self) -> &'static str {
        match self {
            Symmetry::Orthotropic => "orthotropic",
            Symmetry::TransverselyIsotropic => "transversely isotropic",
        }
    }
}

/// The nine engineering constants of an orthotropic material, moduli in Pa.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[allow(missing_docs)] // the names are the standard symbols
pub struct EngineeringConstants {
    pub e1: f64,
    pub e2: f64,
    pub e3: f64,
    pub nu12: f64,
    pub nu13: f64,
    pub nu23: f64,
    pub g12: f64,
    pub g13: f64,
    pub g23: f64,
}

/// A validated linear-elastic material.
#[derive(Debug, Clone)]
pub struct Material {
    /// Short label used in case ids (`A`, `B`, or a file's `name`).
    pub name: String,
    /// Orthotropic or transversely isotropic.
    pub symmetry: Symmetry,
    /// The engineering constants (for a transversely isotropic material, the derived ones filled in).
    pub constants: EngineeringConstants,
    /// Density, kg/m^3.
    pub density: f64,
    /// Compliance matrix `S` (1/Pa), Voigt order.
    pub compliance: Matrix6<f64>,
    /// Stiffness matrix `C = S^-1` (Pa), Voigt order, exactly symmetric.
    pub stiffness: Matrix6<f64>,
    /// Spheres of another stiffness inside the cube (none for the paper's objects).
    pub inclusions: Vec<Inclusion>,
}

fn check_finite(name: &'static str, value: f64) -> Result<(), MaterialError> {
    if value.is_finite() { Ok(()) } else { Err(MaterialError::NotFinite { name, value }) }
}

fn check_positive(name: &'static str, value: f64) -> Result<(), MaterialError> {
    check_finite(name, value)?;
    if value > 0.0 { Ok(()) } else { Err(MaterialError::NonPositive { name, value }) }
}

/// Range of a modulus, Pa: from a gel's 1 Pa to 10 GPa (stiffer than any soft tissue, and the
/// stiffest whose spring and FEM matrices stay well inside floating point).
pub const MODULUS_RANGE_PA: (f64, f64) = (1.0, 1e10);

fn check_modulus(name: &'static str, value: f64) -> Result<(), MaterialError> {
    check_positive(name, value)?;
    if (MODULUS_RANGE_PA.0..=MODULUS_RANGE_PA.1).contains(&value) {
        Ok(())
    } else {
        Err(MaterialError::OutOfRange { name, value, range: "moduli from 1 Pa to 1e10 Pa" })
    }
}

impl EngineeringConstants {
    /// Compliance matrix `S` in Voigt order (11, 22, 33, 23, 13, 12).
    pub fn compliance(&self) -> Matrix6<f64> {
        let mut s = Matrix6::zeros();
        s[(0, 0)] = 1.0 / self.e1;
        s[(1, 1)] = 1.0 / self.e2;
        s[(2, 2)] = 1.0 / self.e3;
        s[(0, 1)] = -self.nu12 / self.e1;
        s[(1, 0)] = s[(0, 1)];
        s[(0, 2)] = -self.nu13 / self.e1;
        s[(2, 0)] = s[(0, 2)];
        s[(1, 2)] = -self.nu23 / self.e2;
        s[(2, 1)] = s[(1, 2)];
        s[(3, 3)] = 1.0 / self.g23;
        s[(4, 4)] = 1.0 / self.g13;
        s[(5, 5)] = 1.0 / self.g12;
        s
    }

    /// Checks every constant and the positive definiteness of `S` (equivalently `C`), naming the
    /// constant or the condition at fault.
    pub fn validate(&self) -> Result<(), MaterialError> {
        for (name, v) in [("E1", self.e1), ("E2", self.e2), ("E3", self.e3)] {
            check_modulus(name, v)?;
        }
        for (name, v) in [("G12", self.g12), ("G13", self.g13), ("G23", self.g23)] {
            check_modulus(name, v)?;
        }
        for (name, v) in [("nu12", self.nu12), ("nu13", self.nu13), ("nu23", self.nu23)] {
            check_finite(name, v)?;
        }
        // Leading 2x2 minors of the normal block of S: nu_ij^2 < E_i / E_j.
        for (name, nu, ei, ej, ni, nj) in [
            ("nu12", self.nu12, self.e1, self.e2, "E1", "E2"),
            ("nu13", self.nu13, self.e1, self.e3, "E1", "E3"),
            ("nu23", self.nu23, self.e2, self.e3, "E2", "E3"),
        ] {
            let bound = (ei / ej).sqrt();
            if nu.abs() >= bound {
                return Err(MaterialError::NotPositiveDefinite(format!(
                    "|{name}| = {} must be below sqrt({ni}/{nj}) = {bound:.6}",
                    nu.abs()
                )));
            }
        }
        let nu21 = self.nu12 * self.e2 / self.e1;
        let nu31 = self.nu13 * self.e3 / self.e1;
        let nu32 = self.nu23 * self.e3 / self.e2;
        let det = 1.0 - self.nu12 * nu21 - self.nu23 * nu32 - self.nu13 * nu31 - 2.0 * nu21 * nu32 * self.nu13;
        if det <= 0.0 {
            return Err(MaterialError::NotPositiveDefinite(format!(
                "1 - nu12 nu21 - nu23 nu32 - nu13 nu31 - 2 nu21 nu32 nu13 = {det:.6} must be positive \
                 (nu12, nu13, nu23 are jointly too large)"
            )));
        }
        Ok(())
    }
}

impl Material {
    /// An orthotropic material from its nine engineering constants (Pa) and density (kg/m^3).
    pub fn orthotropic(
        name: impl Into<String>,
        constants: EngineeringConstants,
        density: f64,
    ) -> Result<Self, MaterialError> {
        Self::build(name.into(), Symmetry::Orthotropic, constants, density)
    }

    /// A transversely isotropic material, axis 1 distinct and the 2-3 plane isotropic:
    /// `E3 = E2`, `nu13 = nu12`, `G13 = G12`, `G23 = E2 / (2 (1 + nu23))`.
    pub fn transversely_isotropic(
        name: impl Into<String>,
        e1: f64,
        e2: f64,
        nu12: f64,
        nu23: f64,
        g12: f64,
        density: f64,
    ) -> Result<Self, MaterialError> {
        check_positive("E2", e2)?;
        check_finite("nu23", nu23)?;
        if nu23 <= -1.0 {
            return Err(MaterialError::NotPositiveDefinite(format!(
                "nu23 = {nu23} must exceed -1 so that G23 = E2 / (2 (1 + nu23)) is positive"
            )));
        }
        let constants = EngineeringConstants {
            e1,
            e2,
            e3: e2,
            nu12,
            nu13: nu12,
            nu23,
            g12,
            g13: g12,
            g23: e2 / (2.0 * (1.0 + nu23)),
        };
        Self::build(name.into(), Symmetry::TransverselyIsotropic, constants, density)
    }

    fn build(
        name: String,
        symmetry: Symmetry,
        constants: EngineeringConstants,
        density: f64,
    ) -> Result<Self, MaterialError> {
        constants.validate()?;
        check_positive("density", density)?;
        if !(1.0..=1e5).contains(&density) {
            return Err(MaterialError::OutOfRange {
                name: "density",
                value: density,
                range: "densities from 1 to 1e5 kg/m^3",
            });
        }
        let compliance = constants.compliance();
        let chol = compliance
            .cholesky()
            .ok_or_else(|| MaterialError::NotPositiveDefinite("Cholesky factorisation of S failed".into()))?;
        let c = chol.inverse();
        let stiffness = (c + c.transpose()) * 0.5;
        if stiffness.cholesky().is_none() {
            return Err(MaterialError::NotPositiveDefinite("Cholesky factorisation of C failed".into()));
        }
        Ok(Self { name, symmetry, constants, density, compliance, stiffness, inclusions: Vec::new() })
    }

    /// The paper's orthotropic object A (Table II, kPa read as 1e3 Pa).
    pub fn object_a() -> Self {
        let k = 1e3;
        let constants = EngineeringConstants {
            e1: 179.0 * k,
            e2: 188.0 * k,
            e3: 228.0 * k,
            nu12: 0.26,
            nu13: 0.30,
            nu23: 0.31,
            g12: 57.1 * k,
            g13: 65.8 * k,
            g23: 71.1 * k,
        };
        // The constants are fixed and valid: a failure here is a programming error caught by tests.
        Self::orthotropic("A", constants, TISSUE_DENSITY)
            .unwrap_or_else(|e| unreachable!("object A preset is invalid: {e}"))
    }

    /// The paper's transversely isotropic object B (Table II, kPa read as 1e3 Pa).
    pub fn object_b() -> Self {
        let k = 1e3;
        Self::transversely_isotropic("B", 170.0 * k, 115.0 * k, 0.46, 0.58, 33.0 * k, TISSUE_DENSITY)
            .unwrap_or_else(|e| unreachable!("object B preset is invalid: {e}"))
    }

    /// A preset by its name, `A` or `B` (case-insensitive).
    pub fn preset(name: &str) -> Option<Self> {
        match name {
            "A" | "a" => Some(Self::object_a()),
            "B" | "b" => Some(Self::object_b()),
            _ => None,
        }
    }

    /// The stiffness `C` at the point `x` (metres): an inclusion's where `x` is inside one, the
    /// background's elsewhere.
    pub fn stiffness_at(&self, x: [f64; 3]) -> &Matrix6<f64> {
        self.inclusions.iter().find(|i| i.contains(x)).map_or(&self.stiffness, |i| &i.stiffness)
    }

    /// What identifies the material's stiffness everywhere, the key of what is computed from it:
    /// `C` row by row, then per inclusion its centre, radius and `C` row by row (`C` alone for a
    /// material without inclusions).
    pub fn key(&self) -> Vec<f64> {
        let rows = |c: &Matrix6<f64>| -> [f64; 36] { std::array::from_fn(|k| c[(k / 6, k % 6)]) };
        let mut key: Vec<f64> = rows(&self.stiffness).to_vec();
        for i in &self.inclusions {
            key.extend(i.centre);
            key.push(i.radius);
            key.extend(rows(&i.stiffness));
        }
        key
    }

    /// The material without its inclusions.
    pub fn background(&self) -> Self {
        Self { inclusions: Vec::new(), ..self.clone() }
    }

    /// `Ok` for a material without inclusions; else the error that `what` does not model them.
    pub fn require_homogeneous(&self, what: &'static str) -> Result<(), MaterialError> {
        if self.inclusions.is_empty() {
            return Ok(());
        }
        Err(MaterialError::Heterogeneous { name: self.name.clone(), count: self.inclusions.len(), what })
    }

    /// `true` for a transversely isotropic material (its MSM has `k3 = k2`).
    pub fn is_transversely_isotropic(&self) -> bool {
        self.symmetry == Symmetry::TransverselyIsotropic
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(m: &Material) {
        let i = m.compliance * m.stiffness;
        let err = (i - Matrix6::identity()).abs().max();
        assert!(err < 1e-13, "S C - I = {err}");
        let c = &m.constants;
        let pairs = [
            (c.nu12 / c.e1, (c.nu12 * c.e2 / c.e1) / c.e2),
            (m.compliance[(0, 2)], m.compliance[(2, 0)]),
            (m.compliance[(1, 2)], m.compliance[(2, 1)]),
        ];
        for (a, b) in pairs {
            assert!((a - b).abs() <= 1e-15 * a.abs().max(1e-30));
        }
        assert_eq!(m.stiffness, m.stiffness.transpose());
    }

    #[test]
    fn presets_round_trip() {
        round_trip(&Material::object_a());
        round_trip(&Material::object_b());
    }

    #[test]
    fn reciprocity_of_poisson_ratios() {
        let m = Material::object_a();
        let c = m.constants;
        // nu_ji = -S[i][j] E_j: the spec's reciprocity nu_ij/E_i = nu_ji/E_j.
        let nu21 = -m.compliance[(1, 0)] * c.e2;
        assert!((c.nu12 / c.e1 - nu21 / c.e2).abs() < 1e-18);
    }

    #[test]
    fn object_b_is_transversely_isotropic() {
        let m = Material::object_b();
        let c = m.stiffness;
        assert!((c[(1, 1)] - c[(2, 2)]).abs() < 1e-9 * c[(1, 1)]);
        assert!((c[(0, 1)] - c[(0, 2)]).abs() < 1e-9 * c[(0, 1)]);
        // In-plane isotropy: C44 = (C22 - C23) / 2.
        assert!((c[(3, 3)] - 0.5 * (c[(1, 1)] - c[(1, 2)])).abs() < 1e-9 * c[(3, 3)]);
        assert!((m.constants.g23 - 115e3 / (2.0 * 1.58)).abs() < 1e-9);
    }

    #[test]
    fn rejects_bad_constants_by_name() {
        let mut c = Material::object_a().constants;
        c.e2 = -1.0;
        let e = Material::orthotropic("x", c, 1040.0).unwrap_err().to_string();
        assert!(e.contains("E2"), "{e}");
        let mut c = Material::object_a().constants;
        c.g13 = f64::NAN;
        let e = Material::orthotropic("x", c, 1040.0).unwrap_err().to_string();
        assert!(e.contains("G13") && e.contains("finite"), "{e}");
        let mut c = Material::object_a().constants;
        c.nu12 = 1.2;
        let e = Material::orthotropic("x", c, 1040.0).unwrap_err().to_string();
        assert!(e.contains("positive definite") && e.contains("nu12"), "{e}");
        let mut c = Material::object_a().constants;
        (c.nu12, c.nu13, c.nu23) = (0.7, 0.7, 0.7);
        let e = Material::orthotropic("x", c, 1040.0).unwrap_err().to_string();
        assert!(e.contains("positive definite"), "{e}");
        let e = Material::orthotropic("x", Material::object_a().constants, 0.0).unwrap_err();
        assert!(e.to_string().contains("density"));
    }

    proptest::proptest! {
        /// For any orthotropic constants the material accepts, its stiffness is the inverse of its
        /// compliance: `C S = I`.
        #[test]
        fn stiffness_times_compliance_is_the_identity(
            e in proptest::array::uniform3(1e3f64..1e6),
            nu in proptest::array::uniform3(0.0f64..0.45),
            g in proptest::array::uniform3(1e3f64..1e6),
        ) {
            let constants = EngineeringConstants {
                e1: e[0], e2: e[1], e3: e[2], nu12: nu[0], nu13: nu[1], nu23: nu[2], g12: g[0], g13: g[1], g23: g[2],
            };
            let Ok(m) = Material::orthotropic("any", constants, TISSUE_DENSITY) else {
                // Constants whose stiffness is not positive definite are refused, not inverted.
                return Ok(());
            };
            let product = m.stiffness * m.compliance;
            let worst = (product - Matrix6::identity()).abs().max();
            proptest::prop_assert!(worst < 1e-9, "C S - I up to {}", worst);
        }
    }
}
