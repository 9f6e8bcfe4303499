//! The probe against the material: the surface compliance's force on every scored press (training
//! and validation, both objects; every free face, edges, a corner, oblique) within 7 % of the
//! converged continuum reference shipped in `assets/continuum/`, and the slide across the top face
//! smooth.

use tissue_core::mechanics::material::Material;
use tissue_core::sim::material_surface::compliance::{DEFAULT_DIVISIONS, SurfaceCompliance, SurfaceContactScratch};
use tissue_studies::validate::continuum::DEFAULT_TOLERANCE;
use tissue_studies::validate::continuum::cache::ContinuumCache;
use tissue_studies::validate::probe::presses::press_cases;

#[test]
#[ignore = "slow: in the slow group, cargo test --release -- --ignored"]
fn the_surface_compliance_feels_like_the_material_wherever_the_probe_lands() {
    for material in [Material::object_a(), Material::object_b()] {
        let compliance = SurfaceCompliance::compute(&material, DEFAULT_DIVISIONS, &mut |_| true).unwrap();
        let kept = ContinuumCache::open(&material, None);
        let mut scratch = SurfaceContactScratch::default();
        for case in press_cases() {
            let kept = kept.get(&case.press, DEFAULT_TOLERANCE).expect("the shipped continuum answers");
            let reference = kept.force_n;
            let f = compliance.press(case.press.centre(), case.press.radius, &mut scratch).unwrap();
            let along = case.press.force_along(f);
            // A shallow press on an edge or a corner touches a strip a few millimetres wide: the
            // lattice's rows are 1 mm apart across the edges (at 2 mm the continuum's own mesh and
            // the lattice alike gave 17 % too much on B's top/+x edge, 15 mm sphere 2 mm deep).
            // Measured: worst 3.6 % (A, a top-face press 2 mm deep) and 2.7 % (B).
            let bound = 0.07;
            let error = along / reference - 1.0;
            assert!(
                error.abs() < bound,
                "{} {}: {along} N against the material's {reference} N",
                material.name,
                case.id
            );
            // The whole force (sideways too: near an edge the tissue also pushes outwards).
            let miss = (0..3).map(|c| (f[c] - kept.force[c]).powi(2)).sum::<f64>().sqrt();
            let size = kept.force.iter().map(|c| c * c).sum::<f64>().sqrt();
            assert!(miss < bound * size, "{}: {f:?} against {:?}", case.id, kept.force);
        }
        // A slow slide at 4 mm with the 15 mm sphere across the middle of the top face: the
        // force varies little (the material's by about 2 % there).
        let forces: Vec<f64> = (0..=40)
            .map(|i| {
                let x = 0.03 + 0.04 * i as f64 / 40.0;
                compliance.press([x, 0.05, 0.1 + 0.015 - 0.004], 0.015, &mut scratch).unwrap()[2]
            })
            .collect();
        let (lo, hi) = forces.iter().fold((f64::INFINITY, 0.0f64), |(l, h), &f| (l.min(f), h.max(f)));
        assert!((hi - lo) / hi < 0.07, "{}: the slide varies from {lo} to {hi} N", material.name);
    }
}
