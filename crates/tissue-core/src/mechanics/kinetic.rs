//! The kinetic energy of lumped node masses, `1/2 sum_p m_p |v_p|^2`, for the step's guard on
//! every step: in four running sums, which the compiler keeps in one vector register (one running
//! sum of floats is a chain of dependent additions, which it may not reorder).

/// `1/2 sum_p masses[p] |v_p|^2` over component-wise velocities `v[c][p]`.
pub fn kinetic_energy(masses: &[f64], v: &[Vec<f64>; 3]) -> f64 {
    let mut sums = [0.0; 4];
    for vc in v {
        debug_assert_eq!(vc.len(), masses.len());
        let (mut m, mut w) = (masses.chunks_exact(4), vc.chunks_exact(4));
        for (m, w) in (&mut m).zip(&mut w) {
            for l in 0..4 {
                sums[l] += m[l] * w[l] * w[l];
            }
        }
        for (m, w) in m.remainder().iter().zip(w.remainder()) {
            sums[0] += m * w * w;
        }
    }
    0.5 * ((sums[0] + sums[1]) + (sums[2] + sums[3]))
}

#[cfg(test)]
mod tests {
    #[test]
    fn is_half_the_mass_times_the_speed_squared() {
        // 7 nodes: a group of four and three left over.
        let masses: Vec<f64> = (0..7).map(|p| 0.5 + p as f64).collect();
        let v: [Vec<f64>; 3] = std::array::from_fn(|c| (0..7).map(|p| (p + c) as f64 * 0.1 - 0.3).collect());
        let plain: f64 = (0..7).map(|p| 0.5 * masses[p] * (0..3).map(|c| v[c][p] * v[c][p]).sum::<f64>()).sum();
        let e = super::kinetic_energy(&masses, &v);
        assert!((e - plain).abs() <= 1e-15 * plain, "{e} vs {plain}");
    }
}
