//! Find the lump: a seeded random inclusion hidden under the top face, palpated with the probe,
//! marked, then revealed with how near the mark was and how much the probe could feel of it.

use std::time::{Duration, Instant};

use rand::{RngExt as _, SeedableRng as _, rngs::Xoshiro256PlusPlus};

use crate::mechanics::grid::CUBE_SIDE_M;
use crate::mechanics::inclusion::Inclusion;
use crate::mechanics::material::Material;

/// The least distance from the lump to a side face, metres (a lump under the top face, not in
/// an edge).
pub const SIDE_MARGIN_M: f64 = 0.01;

/// What a hidden lump is drawn from: each a range `[low, high]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ranges {
    /// Radius, millimetres.
    pub radius_mm: [f64; 2],
    /// Depth of its top under the top face, millimetres.
    pub depth_mm: [f64; 2],
    /// Its stiffness over the tissue's (the scale of `C`).
    pub contrast: [f64; 2],
}

impl Default for Ranges {
    /// Lumps a hand feels, to learn on: 8 to 10 mm in radius, their top 3 to 8 mm deep, 5 to 10
    /// times as stiff. The weakest of them (8 mm, 8 mm deep, 5 times) raises the 15 mm probe's
    /// force 4 mm deep over its centre by 11.1 % on object A (the strongest, 10 mm, 3 mm, 10 times:
    /// 54.2 %; `palpate --grid 1` of a lump at the face's middle), above the 7 % a hand tells apart.
    fn default() -> Self {
        Self { radius_mm: [8.0, 10.0], depth_mm: [3.0, 8.0], contrast: [5.0, 10.0] }
    }
}

/// The clinical ranges, harder: inclusions 5 to 10 mm in radius, 5 to 20 mm deep, 2 to 10 times as
/// stiff (many of them below what a hand tells apart).
pub const CLINICAL: Ranges = Ranges { radius_mm: [5.0, 10.0], depth_mm: [5.0, 20.0], contrast: [2.0, 10.0] };

/// The most a range reaches: radius and depth, millimetres; contrast.
/// (The surface compliance's correction reaches [`REACH_M`](crate::sim::material_surface::compliance::inclusion::REACH_M)
/// beyond a lump: a lump deeper than that under the top face would not be felt at all.)
pub const LIMITS: Ranges = Ranges { radius_mm: [2.0, 15.0], depth_mm: [2.0, 20.0], contrast: [0.2, 20.0] };

/// A lump hidden under the top face.
#[derive(Debug, Clone, PartialEq)]
pub struct HiddenLump {
    /// The inclusion.
    pub inclusion: Inclusion,
    /// Its stiffness over the tissue's.
    pub contrast: f64,
    /// Depth of its top under the top face, metres.
    pub depth_m: f64,
    /// The seed it was drawn with.
    pub seed: u64,
}

/// Draws a lump in `ranges` under `background`'s top face with `seed` (the same seed, the same
/// lump): its radius, depth and contrast uniform in their ranges, its centre uniform over the face
/// where the lump keeps [`SIDE_MARGIN_M`] from the side faces and its distance from each of
/// `others` (drawn again where it would touch one).
pub fn hide(background: &Material, others: &[Inclusion], ranges: &Ranges, seed: u64) -> Result<HiddenLump, String> {
    let pairs = [
        ("radius", ranges.radius_mm, LIMITS.radius_mm, "mm"),
        ("depth", ranges.depth_mm, LIMITS.depth_mm, "mm"),
        ("contrast", ranges.contrast, LIMITS.contrast, "x"),
    ];
    for (name, [low, high], [least, most], unit) in pairs {
        if !(low.is_finite() && high.is_finite() && least <= low && low <= high && high <= most) {
            return Err(format!(
                "the lump's {name} range {low} to {high} {unit} is not within {least} to {most} {unit}"
            ));
        }
    }
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut draw = |[low, high]: [f64; 2]| low + (high - low) * rng.random::<f64>();
    let radius = draw(ranges.radius_mm) * 1e-3;
    let depth = draw(ranges.depth_mm) * 1e-3;
    let contrast = draw(ranges.contrast);
    let room = [SIDE_MARGIN_M + radius, CUBE_SIDE_M - SIDE_MARGIN_M - radius];
    let apart = |c: &[f64; 3]| {
        others.iter().all(|o| (0..3).map(|a| (c[a] - o.centre[a]).powi(2)).sum::<f64>().sqrt() > o.radius + radius)
    };
    let centre = (0..100)
        .map(|_| [draw(room), draw(room), CUBE_SIDE_M - depth - radius])
        .find(apart)
        .ok_or("no place under the top face keeps a hidden lump clear of the material's own inclusions")?;
    let inclusion = Inclusion { centre, radius, stiffness: background.stiffness * contrast };
    Ok(HiddenLump { inclusion, contrast, depth_m: depth, seed })
}

/// The exercise under way.
#[derive(Debug, Clone, PartialEq)]
pub struct Exercise {
    /// The lump.
    pub lump: HiddenLump,
    /// When the probe began to feel it (its surface compliance ready).
    pub ready: Option<Instant>,
    /// Where the user marked it on the top face (x, y, metres) and how long after `ready`.
    pub mark: Option<([f64; 2], Duration)>,
    /// The force of the probe pressed over the lump's centre, with it and without (newtons), at
    /// [`FELT_DEPTH_M`] with the probe's radius then.
    pub felt: Option<[f64; 2]>,
}

/// How deep the press is that says what the probe could feel over the lump, metres.
pub const FELT_DEPTH_M: f64 = 0.004;

impl Exercise {
    /// The distance from the mark to the lump's centre along the top face, metres.
    pub fn miss(&self) -> Option<f64> {
        let ([x, y], _) = self.mark?;
        let c = self.lump.inclusion.centre;
        Some((x - c[0]).hypot(y - c[1]))
    }

    /// The force over the lump against the force there without it, less 1.
    pub fn contrast_felt(&self) -> Option<f64> {
        self.felt.map(|[with, without]| with / without - 1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_seed_hides_one_lump_inside_its_ranges_and_bad_ranges_are_refused() {
        let a = Material::object_a();
        let ranges = CLINICAL;
        for seed in 0..50 {
            let lump = hide(&a, &[], &ranges, seed).expect("a lump");
            assert_eq!(hide(&a, &[], &ranges, seed), Ok(lump.clone()));
            let i = &lump.inclusion;
            assert!((0.005..=0.010).contains(&i.radius) && (0.005..=0.020).contains(&lump.depth_m), "{lump:?}");
            assert!((2.0..=10.0).contains(&lump.contrast));
            let easy = hide(&a, &[], &Ranges::default(), seed).expect("a lump");
            assert!((0.008..=0.010).contains(&easy.inclusion.radius) && (0.003..=0.008).contains(&easy.depth_m));
            assert!((5.0..=10.0).contains(&easy.contrast));
            assert!((CUBE_SIDE_M - i.centre[2] - i.radius - lump.depth_m).abs() < 1e-15);
            assert!(i.centre[..2].iter().all(|&c| c - i.radius >= 0.01 - 1e-15 && c + i.radius <= 0.09 + 1e-15));
            let mut with = a.clone();
            with.inclusions.push(i.clone());
            assert!(with.stiffness_at(i.centre) != &a.stiffness);
        }
        assert!(hide(&a, &[], &ranges, 1) != hide(&a, &[], &ranges, 2));
        // Clear of the material's own inclusions: a lump where seed 3 would put one is avoided.
        let there = hide(&a, &[], &ranges, 3).expect("a lump").inclusion;
        let other = hide(&a, std::slice::from_ref(&there), &ranges, 3).expect("a lump elsewhere").inclusion;
        let apart = (0..3).map(|k| (other.centre[k] - there.centre[k]).powi(2)).sum::<f64>().sqrt();
        assert!(apart > other.radius + there.radius, "{apart}");
        let bad = Ranges { radius_mm: [10.0, 5.0], ..ranges };
        assert!(hide(&a, &[], &bad, 1).unwrap_err().contains("radius"));
        let bad = Ranges { contrast: [2.0, f64::NAN], ..ranges };
        assert!(hide(&a, &[], &bad, 1).unwrap_err().contains("contrast"));
    }

    #[test]
    fn the_mark_is_scored_by_its_distance_along_the_face() {
        let lump = hide(&Material::object_a(), &[], &Ranges::default(), 7).expect("a lump");
        let c = lump.inclusion.centre;
        let mut e = Exercise { lump, ready: None, mark: None, felt: Some([10.5, 10.0]) };
        assert_eq!(e.miss(), None);
        e.mark = Some(([c[0] + 0.003, c[1] - 0.004], Duration::from_secs(20)));
        assert!((e.miss().expect("marked") - 0.005).abs() < 1e-12);
        assert!((e.contrast_felt().expect("felt") - 0.05).abs() < 1e-12);
    }
}
