//! The shape of what a reader of outside input takes, checked alike in TOML and JSON: a list of
//! exactly as many numbers as a point or a direction has ([`numbers`]), and an error that names
//! the key it is at ([`from_json`], [`from_toml`]: `inclusion 1, centre: expected 3 numbers, got
//! 4`), trailing data refused.

use serde::de::{DeserializeOwned, Error as _};
use serde::{Deserialize, Deserializer};

/// A list of exactly `N` numbers: a longer or a shorter one is refused by its length (serde's
/// arrays would let TOML drop what is past `N`).
pub fn numbers<'de, D: Deserializer<'de>, const N: usize>(d: D) -> Result<[f64; N], D::Error> {
    let v = Vec::<f64>::deserialize(d)?;
    let n = v.len();
    v.try_into().map_err(|_| D::Error::custom(format!("expected {N} numbers, got {n}")))
}

/// As [`numbers`], for a key that may be left out.
pub fn maybe_numbers<'de, D: Deserializer<'de>, const N: usize>(d: D) -> Result<Option<[f64; N]>, D::Error> {
    match Option::<Vec<f64>>::deserialize(d)? {
        None => Ok(None),
        Some(v) => {
            let n = v.len();
            v.try_into().map(Some).map_err(|_| D::Error::custom(format!("expected {N} numbers, got {n}")))
        }
    }
}

/// Where in the file a value is, as a person reads it: `inclusion 2, centre` for the path
/// `inclusion[1].centre` (lists counted from 1), nothing at the top.
fn place(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    let mut out = String::new();
    for segment in path.iter() {
        match segment {
            Segment::Seq { index } => out.push_str(&format!(" {}", index + 1)),
            Segment::Map { key } => {
                if !out.is_empty() {
                    out.push_str(", ");
                }
                out.push_str(key);
            }
            Segment::Enum { variant } => {
                if !out.is_empty() {
                    out.push_str(", ");
                }
                out.push_str(variant);
            }
            Segment::Unknown => {}
        }
    }
    out
}

/// `message` at `path`: `inclusion 1, centre: message`, or the message alone at the top.
fn at(path: &serde_path_to_error::Path, message: &str) -> String {
    let place = place(path);
    let message = message.trim().replace('\n', "; ");
    if place.is_empty() { message } else { format!("{place}: {message}") }
}

/// Reads JSON `text` as a `T`; the error names the key it is at and the line and column.
pub fn from_json<T: DeserializeOwned>(text: &str) -> Result<T, String> {
    let mut de = serde_json::Deserializer::from_str(text);
    let value: T = serde_path_to_error::deserialize(&mut de).map_err(|e| at(e.path(), &e.inner().to_string()))?;
    de.end().map_err(|e| format!("{e} (after the document)"))?;
    Ok(value)
}

/// Reads TOML `text` as a `T`; the error names the key it is at and the line and column.
pub fn from_toml<T: DeserializeOwned>(text: &str) -> Result<T, String> {
    let de = toml::Deserializer::parse(text).map_err(|e| toml_message(text, &e))?;
    serde_path_to_error::deserialize(de).map_err(|e| at(e.path(), &toml_message(text, e.inner())))
}

/// A TOML error on one line, its place as serde_json gives it: `message at line L column C`.
fn toml_message(text: &str, e: &toml::de::Error) -> String {
    let message = e.message().trim().replace('\n', "; ");
    match e.span() {
        Some(span) => {
            let before = &text[..span.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("{message} at line {line} column {column}")
        }
        None => message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct File {
        #[serde(default)]
        inclusion: Vec<Sphere>,
    }

    #[derive(Debug, serde::Deserialize)]
    #[serde(deny_unknown_fields)]
    struct Sphere {
        #[serde(deserialize_with = "numbers")]
        centre: [f64; 3],
        radius: f64,
    }

    #[test]
    fn a_list_of_the_wrong_length_is_named_alike_in_toml_and_json() {
        let toml = "[[inclusion]]\ncentre = [0.05, 0.05, 0.08]\nradius = 0.008\n\n[[inclusion]]\n\
                    centre = [0.05, 0.05, 0.08, 0.3]\nradius = 0.008\n";
        let json = r#"{"inclusion": [{"centre": [0.05, 0.05, 0.08], "radius": 0.008},
                       {"centre": [0.05, 0.05, 0.08, 0.3], "radius": 0.008}]}"#;
        let t = from_toml::<File>(toml).expect_err("four numbers");
        let j = from_json::<File>(json).expect_err("four numbers");
        for e in [&t, &j] {
            assert!(e.starts_with("inclusion 2, centre: ") && e.contains("expected 3 numbers, got 4"), "{e}");
            assert!(!e.contains('\n'), "{e}");
        }
        let two = from_toml::<File>("[[inclusion]]\ncentre = [0.05, 0.05]\nradius = 0.008\n").expect_err("two");
        assert!(two.contains("expected 3 numbers, got 2"), "{two}");
        let ok = from_toml::<File>("[[inclusion]]\ncentre = [0.05, 0.05, 0.08]\nradius = 0.008\n").expect("three");
        assert_eq!(ok.inclusion[0].centre, [0.05, 0.05, 0.08]);
        assert!((ok.inclusion[0].radius - 0.008).abs() < 1e-15);
    }

    #[test]
    fn a_key_of_the_wrong_type_and_trailing_data_are_named() {
        let e = from_json::<File>(r#"{"inclusion": [{"centre": [0, 0, 0], "radius": "big"}]}"#).expect_err("a string");
        assert!(e.starts_with("inclusion 1, radius: "), "{e}");
        let e = from_json::<File>(r#"{"inclusion": []} {}"#).expect_err("trailing");
        assert!(e.contains("trailing"), "{e}");
        let e = from_toml::<File>("[[inclusion]]\ncentre = [0, 0, 0]\nradius = \"big\"\n").expect_err("a string");
        assert!(e.starts_with("inclusion 1, radius: "), "{e}");
    }

    proptest::proptest! {
        /// Any text, as TOML or as JSON, gives a value or a one-line error, never a panic.
        #[test]
        fn any_text_is_a_value_or_one_line(text in ".{0,200}") {
            for e in [from_toml::<File>(&text).err(), from_json::<File>(&text).err()].into_iter().flatten() {
                proptest::prop_assert!(!e.contains('\n'), "{}", e);
            }
        }
    }
}
