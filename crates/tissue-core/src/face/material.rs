//! A material as a program names it.

use std::path::Path;

use crate::mechanics::material::{EngineeringConstants, Material as Constants};
use crate::mechanics::object::Object;

/// A tissue's material: the paper's objects A and B (Table II of Choi's paper: A orthotropic, B
/// transversely isotropic), or a material file (TOML or JSON: engineering constants in Pa,
/// density, inclusions; `docs/cli.md` gives the format).
///
/// ```
/// use tissue_core::prelude::*;
///
/// let a = Material::object(Object::A);
/// assert_eq!(a.name(), "A");
/// assert_eq!(a.constants().e1, 179e3); // Pa
///
/// // A file that is not there is refused with one line that names it.
/// let e = Material::from_file("no/such/tissue.toml").unwrap_err();
/// assert!(e.to_string().contains("no/such/tissue.toml"), "{e}");
/// ```
#[derive(Debug, Clone)]
pub struct Material {
    inner: Constants,
}

impl Material {
    /// One of the paper's objects.
    pub fn object(object: Object) -> Self {
        Self { inner: object.material() }
    }

    /// A material file: TOML, or JSON where its name ends in `.json`; checked whole (every
    /// constant in range, the stiffness positive definite, every inclusion inside the cube).
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self, crate::Error> {
        Ok(Self { inner: Constants::from_file(path.as_ref())? })
    }

    /// Its name (`A`, `B`, or the file's).
    pub fn name(&self) -> &str {
        &self.inner.name
    }

    /// Its engineering constants (Pa; Poisson's ratios dimensionless).
    pub fn constants(&self) -> EngineeringConstants {
        self.inner.constants
    }

    /// Its density, kg/m^3.
    pub fn density(&self) -> f64 {
        self.inner.density
    }

    /// How many inclusions (inclusions of another stiffness) it holds.
    pub fn inclusions(&self) -> usize {
        self.inner.inclusions.len()
    }

    /// The material as the layers below name it.
    pub(crate) fn constants_ref(&self) -> &Constants {
        &self.inner
    }

    /// The material as tissue-sim's own crates name it (feature `internals`).
    #[cfg(feature = "internals")]
    pub fn as_internal(&self) -> &Constants {
        &self.inner
    }
}

impl From<Object> for Material {
    fn from(object: Object) -> Self {
        Self::object(object)
    }
}
