//! The paper's two objects, by name: the one vocabulary of `A` and `B` in scripts, flags, charts
//! and the viewer.

use std::fmt;
use std::str::FromStr;

use super::material::Material;

/// One of the paper's objects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Object {
    /// The orthotropic object A.
    A,
    /// The transversely isotropic object B.
    B,
}

impl Object {
    /// Both objects, in order.
    pub const ALL: [Self; 2] = [Self::A, Self::B];

    /// The name in files and messages: `A` or `B`.
    pub fn name(self) -> &'static str {
        match self {
            Self::A => "A",
            Self::B => "B",
        }
    }

    /// The object's material (the paper's Table II).
    pub fn material(self) -> Material {
        match self {
            Self::A => Material::object_a(),
            Self::B => Material::object_b(),
        }
    }
}

impl fmt::Display for Object {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// An object name that is neither `A` nor `B`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("unknown object {0:?}: the objects are A and B")]
pub struct UnknownObject(pub String);

impl FromStr for Object {
    type Err = UnknownObject;

    /// `A` or `B`, in either case, around white space.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim() {
            "A" | "a" => Ok(Self::A),
            "B" | "b" => Ok(Self::B),
            other => Err(UnknownObject(other.to_owned())),
        }
    }
}

impl serde::Serialize for Object {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> serde::Deserialize<'de> for Object {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        name.parse().map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_others_are_refused() {
        for o in Object::ALL {
            assert_eq!(o.name().parse::<Object>(), Ok(o));
            assert_eq!(o.name().to_ascii_lowercase().parse::<Object>(), Ok(o));
            assert_eq!(serde_json::to_string(&o).expect("json"), format!("\"{o}\""));
            assert_eq!(o.material().name, o.name());
        }
        assert!("C".parse::<Object>().is_err());
        assert!(serde_json::from_str::<Object>("\"file\"").is_err());
    }
}
