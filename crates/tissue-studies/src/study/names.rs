//! The names the chart's and the stability study's files give models and integrators
//! ([`Model::chart_name`], [`integrator_chart_name`]), and their serde adapters.

use serde::{Deserialize as _, Deserializer, Serializer, de::Error as _};

use crate::sim::{Integrator, Model};

/// The integrator of a chart point in the chart's files: `explicit` (symplectic Euler),
/// `implicit` (prefactored backward Euler) or `newmark` (prefactored trapezoidal rule).
pub fn integrator_chart_name(integrator: Integrator) -> &'static str {
    match integrator {
        Integrator::Symplectic => "explicit",
        Integrator::Implicit | Integrator::Prefactored => "implicit",
        Integrator::Newmark => "newmark",
    }
}

/// Writes a model by its chart name.
pub(crate) fn serialize_model<S: Serializer>(m: &Model, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&m.chart_name())
}

/// Reads a model by its chart name.
pub(crate) fn deserialize_model<'de, D: Deserializer<'de>>(d: D) -> Result<Model, D::Error> {
    let name = String::deserialize(d)?;
    Model::from_chart_name(&name).ok_or_else(|| {
        let known: Vec<String> = Model::ALL.iter().map(|k| k.chart_name()).collect();
        D::Error::custom(format!("unknown model {name:?} (expected one of {})", known.join(", ")))
    })
}

/// Writes an integrator by its chart name.
pub(crate) fn serialize_integrator<S: Serializer>(i: &Integrator, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(integrator_chart_name(*i))
}

/// Reads an integrator by its chart name (the chart's schemes only).
pub(crate) fn deserialize_integrator<'de, D: Deserializer<'de>>(d: D) -> Result<Integrator, D::Error> {
    let name = String::deserialize(d)?;
    [Integrator::Symplectic, Integrator::Prefactored, Integrator::Newmark]
        .into_iter()
        .find(|i| integrator_chart_name(*i) == name)
        .ok_or_else(|| {
            D::Error::custom(format!("unknown variant `{name}`, expected `explicit`, `implicit` or `newmark`"))
        })
}
