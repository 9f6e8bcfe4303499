//! The probe presses a model's force is scored on against the material
//! ([`crate::validate::continuum`]): the rigid sphere pressed into every free face of the cube,
//! along the face's inward normal over a node of the viewer's 8^3 grid, between two nodes, at a
//! cell's centre, near the cube's edges and elsewhere; across an edge (along the normalised sum
//! of the two faces' inward normals) and into a corner; and obliquely (tilted from the normal),
//! at several radii and depths. Training presses are the ones a calibration may fit to (the
//! lattices' calibrations take those on the top face); validation presses share no point, and
//! have radii and depths of their own.

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

impl PressCase {
    /// Whether the press is along the top face's normal on the top face (the presses the lattices'
    /// calibrations fit to).
    pub fn on_top_face(&self) -> bool {
        self.press.direction.is_none()
            && self.press.at[2] == CUBE_SIDE_M
            && self.press.at[..2].iter().all(|&c| c > 0.0 && c < CUBE_SIDE_M)
    }
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

/// Presses elsewhere on the free surface: the set, what the press is, the touched point in lattice
/// units (on a side face, an edge or a corner) and the pressing direction where it is oblique
/// (unnormalised; else the inward normal).
const ELSEWHERE: [(Set, &str, [f64; 3], Option<[f64; 3]>); 15] = [
    (Set::Training, "side+x", [7.0, 2.0, 3.0], None),
    (Set::Training, "side-y", [4.5, 0.0, 5.0], None),
    (Set::Training, "edge-top+x", [7.0, 3.0, 7.0], None),
    (Set::Training, "oblique-top", [3.0, 2.0, 7.0], Some([0.5, 0.0, -0.866_025_403_784_438_6])),
    (Set::Validation, "side-x", [0.0, 3.5, 4.0], None),
    (Set::Validation, "side+x", [7.0, 5.5, 1.5], None),
    (Set::Validation, "side+y", [2.0, 7.0, 6.0], None),
    (Set::Validation, "side-y", [6.6, 0.0, 3.0], None),
    (Set::Validation, "edge-top-y", [4.4, 0.0, 7.0], None),
    (Set::Validation, "edge-top-x", [0.0, 1.6, 7.0], None),
    (Set::Validation, "edge+x+y", [7.0, 7.0, 4.0], None),
    (Set::Validation, "corner", [7.0, 7.0, 7.0], None),
    (Set::Validation, "oblique-top", [4.0, 4.6, 7.0], Some([-0.3, 0.3, -0.9])),
    (Set::Validation, "oblique+x", [7.0, 2.5, 3.5], Some([-0.866_025_403_784_438_6, 0.0, 0.5])),
    (Set::Validation, "oblique-y", [2.2, 0.0, 5.2], Some([0.4, 0.9, -0.3])),
];

/// Training radii and depths, metres: every combination at every training point.
const TRAINING: ([f64; 2], [f64; 3]) = ([0.010, 0.015], [0.002, 0.004, 0.006]);
/// Validation radius and depth pairs, metres; point `i` takes pairs `i` and `i + 3` (mod 6).
const VALIDATION: [(f64, f64); 6] =
    [(0.015, 0.003), (0.0125, 0.005), (0.010, 0.0025), (0.015, 0.0055), (0.0125, 0.002), (0.010, 0.0045)];

/// `u` in lattice units of the 8^3 grid, metres (the faces exactly).
fn lattice(u: f64) -> f64 {
    if u == 7.0 { CUBE_SIDE_M } else { u * (CUBE_SIDE_M / 7.0) }
}

/// The scored presses.
pub fn press_cases() -> Vec<PressCase> {
    let mut out = Vec::new();
    let mut validation = 0;
    let top = POINTS.iter().map(|&(set, what, uv)| (set, what, [uv[0], uv[1], 7.0], None, true));
    let elsewhere = ELSEWHERE.iter().map(|&(set, what, at, dir)| (set, what, at, dir, false));
    for (set, what, at, dir, on_top) in top.chain(elsewhere) {
        let pairs: Vec<(f64, f64)> = match set {
            Set::Training => TRAINING.0.iter().flat_map(|&r| TRAINING.1.iter().map(move |&d| (r, d))).collect(),
            Set::Validation => {
                let i = validation;
                validation += 1;
                vec![VALIDATION[i % 6], VALIDATION[(i + 3) % 6]]
            }
        };
        let direction = dir.map(|d: [f64; 3]| {
            let n = d.iter().map(|c| c * c).sum::<f64>().sqrt();
            d.map(|c| c / n)
        });
        let point = if on_top { format!("{}_{}", at[0], at[1]) } else { format!("{}_{}_{}", at[0], at[1], at[2]) };
        for (radius, depth) in pairs {
            out.push(PressCase {
                id: format!("press_{what}_{point}_r{}_d{}", radius * 1e3, depth * 1e3),
                set,
                press: Press { at: at.map(lattice), radius, depth, direction },
            });
        }
    }
    out
}

/// The probe of the presses over inclusions: radius and depth, metres (what a hand feels with).
const INCLUSION_PROBES: [(f64, f64); 2] = [(0.015, 0.004), (0.010, 0.003)];
/// How far from the point over an inclusion's centre the press away from it is, beyond its
/// radius, metres.
const AWAY_M: f64 = 0.025;

/// The presses scored for a material with inclusions, all in the validation set (nothing is
/// fitted to a lump): for each inclusion, on the free face nearest its centre, the 15 mm probe
/// 4 mm deep over its centre, over its rim and 25 mm beyond the rim (along the face, towards the
/// cube's middle; left out where that is off the face), and the 10 mm probe 3 mm deep over its
/// centre.
pub fn inclusion_press_cases(material: &crate::mechanics::material::Material) -> Vec<PressCase> {
    let l = CUBE_SIDE_M;
    let mut out = Vec::new();
    for (i, inclusion) in material.inclusions.iter().enumerate() {
        let c = inclusion.centre;
        // (distance, normal axis, face coordinate, tangent axis) of each free face.
        let faces =
            [(l - c[2], 2, l, 0), (l - c[0], 0, l, 1), (c[0], 0, 0.0, 1), (l - c[1], 1, l, 0), (c[1], 1, 0.0, 0)];
        let (_, axis, level, tangent) = faces.into_iter().fold(faces[0], |a, b| if b.0 < a.0 { b } else { a });
        let towards_middle = if c[tangent] < 0.5 * l { 1.0 } else { -1.0 };
        // On the face, off its edges by a millimetre at least; a press that would not be is left out.
        let at = |shift: f64| {
            let mut p = c;
            p[axis] = level;
            p[tangent] = c[tangent] + towards_middle * shift;
            (0.001..=l - 0.001).contains(&p[tangent]).then_some(p)
        };
        let (r15, r10) = (INCLUSION_PROBES[0], INCLUSION_PROBES[1]);
        for (what, shift, (radius, depth)) in [
            ("over", 0.0, r15),
            ("rim", inclusion.radius, r15),
            ("away", inclusion.radius + AWAY_M, r15),
            ("over", 0.0, r10),
        ] {
            if let Some(at) = at(shift) {
                out.push(PressCase {
                    id: format!("press_lump{}_{what}_r{}_d{}", i + 1, radius * 1e3, depth * 1e3),
                    set: Set::Validation,
                    press: Press::normal(at, radius).depth(depth),
                });
            }
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
        assert_eq!(cases.len(), (4 + 4) * 6 + (6 + 11) * 2);
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

    #[test]
    fn inclusion_presses_sit_on_the_nearest_free_face_over_rim_and_away() {
        let mut material = crate::mechanics::material::Material::object_a();
        let stiffness = material.stiffness * 5.0;
        material.inclusions.push(crate::mechanics::inclusion::Inclusion {
            centre: [0.07, 0.05, 0.082],
            radius: 0.008,
            stiffness,
        });
        material.inclusions.push(crate::mechanics::inclusion::Inclusion {
            centre: [0.09, 0.03, 0.04],
            radius: 0.006,
            stiffness,
        });
        let cases = inclusion_press_cases(&material);
        assert_eq!(cases.len(), 8);
        for c in &cases {
            c.press.check().unwrap();
            assert_eq!(c.set, Set::Validation);
        }
        assert_eq!(cases[0].press.at, [0.07, 0.05, CUBE_SIDE_M]);
        assert!((cases[1].press.at[0] - 0.062).abs() < 1e-12 && (cases[2].press.at[0] - 0.037).abs() < 1e-12);
        assert_eq!(cases[4].press.at, [CUBE_SIDE_M, 0.03, 0.04]);
        assert!((cases[5].press.at[1] - 0.036).abs() < 1e-12, "{:?}", cases[5].press.at);
    }
}
