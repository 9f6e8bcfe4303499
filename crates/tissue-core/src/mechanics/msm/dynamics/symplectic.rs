//! Symplectic Euler's step of the lattices: the force in f64 or f32, in the widest instruction set the CPU has.

use super::*;

/// The symplectic step with the springs' force in `f32` ([`SingleForce`]).
#[inline(always)]
pub(super) fn symplectic_single<const FMA: bool>(model: &MsmModel, s: &mut Dynamics, dt: f64) {
    let Some(single) = &mut s.single else { return };
    let springs = single.compute::<FMA>(&s.x);
    let n = s.free.len();
    for c in 0..3 {
        // Every slice cut to `n`: no bounds checks, so the loop vectorises.
        let (x, v, f, fe) = (&mut s.x[c][..n], &mut s.v[c][..n], &springs[c][..n], &s.f_ext[c][..n]);
        let (free, inv_mass, damping) = (&s.free[..n], &s.inv_mass[..n], &model.damping[..n]);
        for p in 0..n {
            advance(&mut x[p], &mut v[p], f64::from(f[p]) + fe[p], inv_mass[p], damping[p], free[p], dt);
        }
    }
}

#[inline(always)]
pub(super) fn symplectic_step_generic(model: &MsmModel, s: &mut Dynamics, dt: f64) {
    for f in &mut s.f {
        f.fill(0.0);
    }
    accumulate_spring_forces::<true>(model, &s.x, &mut s.f, &mut s.scratch);
    for c in 0..3 {
        let (x, v, f, fe) = (&mut s.x[c], &mut s.v[c], &s.f[c], &s.f_ext[c]);
        for ((((((x, v), f), fe), free), inv_m), d) in
            x.iter_mut().zip(v.iter_mut()).zip(f.iter()).zip(fe).zip(&s.free).zip(&s.inv_mass).zip(&model.damping)
        {
            advance(x, v, f + fe, *inv_m, *d, *free, dt);
        }
    }
}

/// A node component's symplectic Euler update under the total load `force` (springs plus
/// external): `v = (v + dt / m (force - c v)) free`, `x += dt v`.
#[inline(always)]
pub(super) fn advance(x: &mut f64, v: &mut f64, force: f64, inv_mass: f64, damping: f64, free: f64, dt: f64) {
    let vn = (*v + dt * inv_mass * (force - damping * *v)) * free;
    *v = vn;
    *x += dt * vn;
}

pub(super) fn symplectic_step(model: &MsmModel, s: &mut Dynamics, dt: f64) {
    if s.single.is_some() {
        dispatch_simd!(symplectic_single, (model: &MsmModel, s: &mut Dynamics, dt: f64));
    } else {
        dispatch_avx2!(symplectic_step_generic, symplectic_step_avx2, (model: &MsmModel, s: &mut Dynamics, dt: f64));
    }
}
