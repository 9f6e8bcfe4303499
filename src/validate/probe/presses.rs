//! The probe presses a model's force is scored on against the material
//! ([`crate::validate::continuum`]): the rigid sphere pressed along -z into the top face over a
//! node of the viewer's 8^3 grid, between two nodes, at a cell's centre, near the cube's edges and
//! elsewhere, at several radii and depths. Training presses are the ones a calibration may fit
//! to; validation presses share no point, and have radii and depths of their own.

use crate::mechanics::grid::CUBE_SIDE_M;
use crate::validate::continuum::Press;
use crate::validate::touch::Set;

/// One scored press.
#[derive(Debug, Clone, PartialEq)]
pub struct PressCase {
    /// e.g. `press_node_2_3_r15_d4`.
    pub id: String,
    /// Training or validation.
    pub set: Set,
    /// The press.
    pub press: Press,
}

/// Points on the top face in lattice units of the 8^3 grid (spacing 0.1/7 m), what they are
/// there, and their set.
const POINTS: [(Set, &str, [f64; 2]); 10] = [
    (Set::Training, "node", [2.0, 3.0]),
    (Set::Training, "between", [1.0, 4.5]),
    (Set::Training, "cell", [2.5, 1.5]),
    (Set::Training, "near-edge", [0.25, 2.0]),
    (Set::Validation, "node", [3.0, 5.0]),
    (Set::Validation, "between", [4.5, 3.0]),
    (Set::Validation, "cell", [3.5, 3.5]),
    (Set::Validation, "near-edge", [6.75, 4.5]),
    (Set::Validation, "anywhere", [4.3, 1.7]),
    (Set::Validation, "anywhere", [5.6, 5.9]),
];

/// Training radii and depths, metres: every combination at every training point.
const TRAINING: ([f64; 2], [f64; 3]) = ([0.010, 0.015], [0.002, 0.004, 0.006]);
/// Validation radius and depth pairs, metres; point `i` takes pairs `i` and `i + 3` (mod 6).
const VALIDATION: [(f64, f64); 6] =
    [(0.015, 0.003), (0.0125, 0.005), (0.010, 0.0025), (0.015, 0.0055), (0.0125, 0.002), (0.010, 0.0045)];

/// The scored presses.
pub fn press_cases() -> Vec<PressCase> {
    let h8 = CUBE_SIDE_M / 7.0;
    let mut out = Vec::new();
    let mut validation = 0;
    for (set, what, uv) in POINTS {
        let at = [uv[0] * h8, uv[1] * h8, CUBE_SIDE_M];
        let pairs: Vec<(f64, f64)> = match set {
            Set::Training => TRAINING.0.iter().flat_map(|&r| TRAINING.1.iter().map(move |&d| (r, d))).collect(),
            Set::Validation => {
                let i = validation;
                validation += 1;
                vec![VALIDATION[i % 6], VALIDATION[(i + 3) % 6]]
            }
        };
        for (radius, depth) in pairs {
            out.push(PressCase {
                id: format!("press_{what}_{}_{}_r{}_d{}", uv[0], uv[1], radius * 1e3, depth * 1e3),
                set,
                press: Press { at, radius, depth },
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presses_are_valid_and_the_sets_share_no_point() {
        let cases = press_cases();
        assert_eq!(cases.len(), 4 * 6 + 6 * 2);
        for c in &cases {
            c.press.check().unwrap();
            assert!((0.002..=0.006).contains(&c.press.depth) && (0.010..=0.015).contains(&c.press.radius));
        }
        for a in cases.iter().filter(|c| c.set == Set::Training) {
            for b in cases.iter().filter(|c| c.set == Set::Validation) {
                assert_ne!(a.press.at, b.press.at);
            }
        }
    }
}
