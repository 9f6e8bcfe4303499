//! Tests of the parent module.
use super::*;

#[test]
fn the_component_wise_symplectic_steps_are_the_interleaved_ones_bit_for_bit() {
    let mut with_inclusions = crate::mechanics::material::Material::object_a();
    let stiffness = with_inclusions.stiffness * 5.0;
    with_inclusions.inclusions.push(crate::mechanics::inclusion::Inclusion {
        centre: [0.06, 0.05, 0.07],
        radius: 0.012,
        stiffness,
    });
    for material in [crate::mechanics::material::Material::object_a(), with_inclusions] {
        component_wise_is_interleaved(&material);
    }
}

fn component_wise_is_interleaved(material: &crate::mechanics::material::Material) {
    let grid = Grid::new(6).unwrap();
    let mut case = LoadCase::bottom_clamp(&grid, "A");
    // A load on the top corner, so the state moves.
    let corner = grid.num_nodes() - 1;
    case.load[3 * corner..3 * corner + 3].copy_from_slice(&[0.3, -0.2, -1.0]);
    for formulation in [Formulation::Linear, Formulation::Corotational] {
        let mut tissue = FemTissue::new(grid, material, formulation);
        tissue.set_damping_ratio(0.2).unwrap();
        tissue.apply_case(&case);
        let mut reference = FemDynamics::new(FemModel::new(grid, material), material.density, formulation, 0.0);
        reference.alpha = tissue.dynamics.alpha;
        reference.apply_case(&case);
        let dt = 0.5 * tissue.explicit_dt_limit();
        for _ in 0..200 {
            tissue.step(Integrator::Symplectic, dt).unwrap();
            reference.step_symplectic(dt);
        }
        let moved =
            (0..grid.num_nodes()).map(|p| (tissue.x()[2][p] - reference.rest()[3 * p + 2]).abs()).fold(0.0, f64::max);
        assert!(moved > 1e-6, "{formulation:?}: the load moved the cube by {moved} m");
        for p in 0..grid.num_nodes() {
            for c in 0..3 {
                let (x, v) = (reference.x[3 * p + c], reference.v[3 * p + c]);
                assert_eq!(tissue.x()[c][p].to_bits(), x.to_bits(), "{formulation:?}: node {p}, {c}");
                assert_eq!(tissue.v()[c][p].to_bits(), v.to_bits(), "{formulation:?}: node {p}, {c}");
            }
        }
    }
}

/// The linear FEM's `f32` step with a lump (its elements' change summed in `f64`, added in
/// `f32`) follows the `f64` step to `f32`'s rounding.
#[test]
fn the_f32_step_takes_the_lump_too() {
    let mut material = crate::mechanics::material::Material::object_a();
    let stiffness = material.stiffness * 5.0;
    material.inclusions.push(crate::mechanics::inclusion::Inclusion {
        centre: [0.06, 0.05, 0.07],
        radius: 0.012,
        stiffness,
    });
    let grid = Grid::new(6).unwrap();
    let mut case = LoadCase::bottom_clamp(&grid, "A");
    let corner = grid.num_nodes() - 1;
    case.load[3 * corner..3 * corner + 3].copy_from_slice(&[0.3, -0.2, -1.0]);
    let run = |single: bool| {
        let mut tissue = FemTissue::new(grid, &material, Formulation::Linear);
        tissue.set_single_precision(single).expect("the f32 step takes a lump");
        tissue.apply_case(&case);
        let dt = 0.5 * tissue.explicit_dt_limit();
        for _ in 0..200 {
            tissue.step(Integrator::Symplectic, dt).unwrap();
        }
        tissue.x().clone()
    };
    let (double, single) = (run(false), run(true));
    let rest = grid.positions();
    let moved = (0..grid.num_nodes()).map(|p| (double[2][p] - rest[p][2]).abs()).fold(0.0, f64::max);
    let gap = (0..3)
        .flat_map(|c| (0..grid.num_nodes()).map(move |p| (c, p)))
        .map(|(c, p)| (double[c][p] - single[c][p]).abs())
        .fold(0.0, f64::max);
    assert!(moved > 1e-6 && gap < 1e-4 * moved, "{gap} of {moved}");
    let e = FemTissue::new(grid, &material, Formulation::Linear).explicit_form().expect_err("no GPU step");
    assert!(e.contains("GPU"), "{e}");
}

/// The linear FEM runs to [`crate::sim::MAX_EXPLICIT_FRACTION`] of its limit under the
/// automatic choice ([`Tissue::step_limit`]): from random velocities, undamped, its kinetic
/// energy stays within symplectic Euler's bound there (on a mode at `h omega = 2 f`, from
/// rest, at most `1 / (1 - f^2)` times the start's), and grows without bound just above the
/// limit (the limit is tight, so the fraction is the whole margin).
#[test]
fn the_linear_fem_is_stable_at_the_named_fraction_of_its_limit() {
    let material = crate::mechanics::material::Material::object_a();
    let peak = |fraction: f64| {
        let mut tissue = FemTissue::new(Grid::new(10).unwrap(), &material, Formulation::Linear);
        assert!(tissue.step_limit().constant_stiffness);
        let mut seed = 12345u64;
        for v in tissue.v_mut().iter_mut().flatten() {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            *v = ((seed >> 33) as f64 / 2f64.powi(31) - 0.5) * 1e-3;
        }
        let start = tissue.kinetic_energy();
        let dt = fraction * tissue.explicit_dt_limit();
        let mut peak = 0.0f64;
        for _ in 0..4000 {
            tissue.step(Integrator::Symplectic, dt).unwrap();
            peak = peak.max(tissue.kinetic_energy());
        }
        peak / start
    };
    let fraction = crate::sim::MAX_EXPLICIT_FRACTION;
    let at = peak(fraction);
    let bound = 1.0 / (1.0 - fraction * fraction);
    assert!(at <= bound, "kinetic energy rose to {at} x the start's (bound {bound})");
    let above = peak(1.1);
    assert!(above.is_nan() || above >= 1e3, "10 % above the limit: {above} x the start's");
}

#[test]
fn the_limits_omega_max_is_at_the_stiffest_mode_and_below_both_bounds() {
    let material = crate::mechanics::material::Material::object_b();
    for clamped in [false, true] {
        let grid = Grid::new(4).unwrap();
        let model = FemModel::new(grid, &material);
        let dofs = 3 * grid.num_nodes();
        let k = model.dense_stiffness();
        let mass = crate::mechanics::msm::model::lumped_masses(&grid, material.density);
        let gershgorin =
            (0..dofs).map(|r| k.row(r).iter().map(|v| v.abs()).sum::<f64>() / mass[r / 3]).fold(0.0, f64::max);
        // The bottom face held, or none.
        let free: Vec<bool> = (0..dofs).map(|d| !clamped || grid.position(d / 3)[2] > 0.0).collect();
        let dof_mass: Vec<f64> = (0..dofs).map(|d| mass[d / 3]).collect();
        let stiffest = crate::response::stiffest_mode::dense_omega_max_sq(&k, &dof_mass, &free);
        let m_e = material.density * grid.h().powi(3) / 8.0;
        let element = model.ke.symmetric_eigenvalues().max() / m_e;
        let limit = fem_stiffest(&model, material.density, &dof_mass);
        // Estimated with no dof held: above the clamped cube's stiffest mode, at the free one's.
        assert!(limit >= stiffest, "limit's omega_max^2 {limit} below omega_max^2 = {stiffest}");
        assert!(clamped || limit <= stiffest * 1.001, "limit's omega_max^2 {limit} against {stiffest}");
        assert!(element >= stiffest * (1.0 - 1e-12), "element bound {element} below omega_max^2 = {stiffest}");
        assert!(limit <= element && element <= gershgorin, "{limit} {element} {gershgorin}");
        eprintln!(
            "clamped {clamped}: omega_max^2 {stiffest:.4e}, limit's {limit:.4e}, element bound {element:.4e}, \
             Gershgorin {gershgorin:.4e}"
        );
    }
}
