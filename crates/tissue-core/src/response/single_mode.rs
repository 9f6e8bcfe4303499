//! What a time integrator does to one damped mode `q'' + gamma q' + omega^2 q = 0`, in closed
//! form: the one-step map of `(q, q')` has two eigenvalues, the roots of
//! `lambda^2 - trace lambda + det`, and `lambda = exp(s dt)` gives the period and damping ratio
//! that the discrete motion has (`s = -zeta omega_n +- i omega_d`).
//!
//! With mass-proportional damping every mode of a linear model is such an oscillator with the
//! same `gamma = alpha`, so these forms predict exactly what time stepping measures on a pure
//! mode (the validation layer's `dynamic_measure`).

use std::f64::consts::PI;

/// How a scheme steps (linearised backward Euler, prefactored or not, is one scheme on a linear
/// model).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scheme {
    /// Symplectic Euler with the damping force explicit: `v += dt (f(x) - gamma v)`, `x += dt v`.
    Symplectic,
    /// Backward Euler: `(1 + dt gamma + dt^2 omega^2) v' = v - dt omega^2 x`, `x += dt v'`.
    BackwardEuler,
    /// Newmark's average acceleration (the trapezoidal rule): no numerical damping, period
    /// lengthened by about `(omega dt)^2 / 12`.
    Trapezoidal,
}

/// Period and damping ratio of a (discrete or continuous) damped mode.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ModeMotion {
    /// Time between successive maxima, s; infinite when the motion does not oscillate.
    pub period_s: f64,
    /// Damping ratio (1 = critical).
    pub damping_ratio: f64,
}

/// The exact motion of the continuous mode: `zeta = gamma / (2 omega)`, period
/// `2 pi / (omega sqrt(1 - zeta^2))` (infinite at and above critical damping).
pub fn exact(omega: f64, gamma: f64) -> ModeMotion {
    let zeta = gamma / (2.0 * omega);
    let period_s = if zeta < 1.0 { 2.0 * PI / (omega * (1.0 - zeta * zeta).sqrt()) } else { f64::INFINITY };
    ModeMotion { period_s, damping_ratio: zeta }
}

/// The motion `scheme` gives the mode at step `dt`, or `None` when it has no continuous
/// equivalent (unstable, or a negative real eigenvalue: the sign flips every step).
pub fn discrete(scheme: Scheme, omega: f64, gamma: f64, dt: f64) -> Option<ModeMotion> {
    let (w2, g) = (dt * dt * omega * omega, dt * gamma);
    match scheme {
        Scheme::Symplectic => from_recurrence(2.0 - g - w2, 1.0 - g, dt),
        Scheme::BackwardEuler => {
            let d = 1.0 + g + w2;
            from_recurrence((2.0 + g) / d, 1.0 / d, dt)
        }
        Scheme::Trapezoidal => {
            let d = 4.0 + 2.0 * g + w2;
            from_recurrence((8.0 - 2.0 * w2) / d, (4.0 - 2.0 * g + w2) / d, dt)
        }
    }
}

/// The motion of a sequence obeying `q_{n+1} = trace q_n - det q_{n-1}` with samples `dt` apart,
/// or `None` when it is not a decaying or steady motion with a continuous equivalent.
pub fn from_recurrence(trace: f64, det: f64, dt: f64) -> Option<ModeMotion> {
    if !(trace.is_finite() && det.is_finite()) || det <= 0.0 {
        return None;
    }
    let disc = trace * trace - 4.0 * det;
    if disc < 0.0 {
        // lambda = r exp(+- i theta).
        let theta = (-disc).sqrt().atan2(trace);
        let sigma = -0.5 * det.ln() / dt;
        let omega_d = theta / dt;
        if sigma < -1e-9 * omega_d {
            return None; // grows
        }
        return Some(ModeMotion { period_s: 2.0 * PI / omega_d, damping_ratio: sigma / sigma.hypot(omega_d) });
    }
    let (l1, l2) = (0.5 * (trace + disc.sqrt()), 0.5 * (trace - disc.sqrt()));
    if l2 <= 0.0 || l1 > 1.0 {
        return None;
    }
    let (s1, s2) = (l1.ln() / dt, l2.ln() / dt);
    let omega_n = (s1 * s2).sqrt();
    Some(ModeMotion { period_s: f64::INFINITY, damping_ratio: -(s1 + s2) / (2.0 * omega_n) })
}

/// Relative period error of `got` against `want` (infinite periods: 1 when only one is).
pub fn period_error(got: f64, want: f64) -> f64 {
    if got.is_infinite() && want.is_infinite() {
        0.0
    } else if got.is_infinite() || want.is_infinite() {
        1.0
    } else {
        (got / want - 1.0).abs()
    }
}

/// The stability limit of symplectic Euler on a mode `omega` with damping rate `gamma` (1/s)
/// treated explicitly: the one-step matrix has determinant `1 - h gamma` and trace
/// `2 - h gamma - h^2 omega^2`, stable while `h^2 omega^2 + 2 h gamma < 4`, i.e.
/// `h < 4 / (gamma + sqrt(gamma^2 + 4 omega^2))` (`2 / omega` undamped).
pub fn damped_explicit_limit(omega: f64, gamma: f64) -> f64 {
    4.0 / (gamma + (gamma * gamma + 4.0 * omega * omega).sqrt())
}

/// Least-squares fit of `q_{n+1} = a q_n - b q_{n-1}`: the motion of `(a, b)` (NaN when it has
/// none: unstable or not oscillating in a continuous way) and the relative residual.
pub fn fit_recurrence(q: &[f64], dt: f64) -> (ModeMotion, f64) {
    let (mut s11, mut s12, mut s22, mut r1, mut r2, mut yy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for w in q.windows(3) {
        let (x1, x2, y) = (w[1], -w[0], w[2]);
        s11 += x1 * x1;
        s12 += x1 * x2;
        s22 += x2 * x2;
        r1 += x1 * y;
        r2 += x2 * y;
        yy += y * y;
    }
    let det = s11 * s22 - s12 * s12;
    let nan = ModeMotion { period_s: f64::NAN, damping_ratio: f64::NAN };
    if !(det.is_finite() && det > 0.0) {
        return (nan, f64::NAN);
    }
    let a = (r1 * s22 - r2 * s12) / det;
    let b = (s11 * r2 - s12 * r1) / det;
    let res: f64 = q.windows(3).map(|w| (w[2] - a * w[1] + b * w[0]).powi(2)).sum();
    let motion = from_recurrence(a, b, dt).unwrap_or(nan);
    (motion, (res / yy).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Symplectic Euler with explicit damping on one mode, `n` steps of `h` from `x = 1`.
    fn grows(omega: f64, gamma: f64, h: f64) -> bool {
        let (mut x, mut v) = (1.0f64, 0.0f64);
        for _ in 0..20_000 {
            v += h * (-omega * omega * x - gamma * v);
            x += h * v;
        }
        x.is_nan() || x.abs() > 1e3 // NaN after an overflow counts as growth
    }

    #[test]
    fn damped_limit_separates_stable_from_unstable_steps() {
        for (omega, gamma) in [(1000.0, 0.0), (990.0, 425.0), (300.0, 2000.0)] {
            let h = damped_explicit_limit(omega, gamma);
            assert!(!grows(omega, gamma, 0.99 * h), "omega {omega} gamma {gamma}: 0.99 h grows");
            assert!(grows(omega, gamma, 1.01 * h), "omega {omega} gamma {gamma}: 1.01 h is stable");
        }
        assert!((damped_explicit_limit(1000.0, 0.0) - 2e-3).abs() < 1e-15);
    }

    /// Steps one mode from `q = 1` and returns the samples of `q`.
    fn run(scheme: Scheme, omega: f64, gamma: f64, dt: f64, steps: usize) -> Vec<f64> {
        let (mut x, mut v) = (1.0f64, 0.0f64);
        let mut out = vec![x];
        for _ in 0..steps {
            match scheme {
                Scheme::Symplectic => v += dt * (-omega * omega * x - gamma * v),
                Scheme::BackwardEuler => {
                    v = (v - dt * omega * omega * x) / (1.0 + dt * gamma + dt * dt * omega * omega)
                }
                Scheme::Trapezoidal => {
                    let dx =
                        (4.0 * v / dt - 2.0 * omega * omega * x) / (4.0 / (dt * dt) + 2.0 * gamma / dt + omega * omega);
                    v = 2.0 * dx / dt - v;
                    x += dx - dt * v; // undone below: x moves by dx
                }
            }
            x += dt * v;
            out.push(x);
        }
        out
    }

    /// Times of successive maxima of the samples (parabola through three samples).
    fn peaks(q: &[f64], dt: f64) -> Vec<(f64, f64)> {
        (1..q.len() - 1)
            .filter(|&i| q[i] > q[i - 1] && q[i] >= q[i + 1])
            .map(|i| {
                let (a, b, c) = (q[i - 1], q[i], q[i + 1]);
                let off = 0.5 * (a - c) / (a - 2.0 * b + c);
                ((i as f64 + off) * dt, b - 0.25 * (a - c) * off)
            })
            .collect()
    }

    #[test]
    fn backward_euler_damps_an_undamped_mode_by_its_closed_form() {
        // Backward Euler on an undamped mode: |lambda| = (1 + (omega dt)^2)^(-1/2), so the
        // numerical damping ratio is ln(1 + (omega dt)^2) / (2 atan(omega dt)) ~ omega dt / 2.
        let omega = 2.0 * PI * 15.0;
        for dt in [1e-4, 1e-3, 1.0 / 60.0] {
            let got = discrete(Scheme::BackwardEuler, omega, 0.0, dt).unwrap();
            let wh = omega * dt;
            let sigma = 0.5 * (1.0 + wh * wh).ln();
            let theta = wh.atan();
            let zeta = sigma / sigma.hypot(theta);
            assert!((got.damping_ratio - zeta).abs() < 1e-12, "dt {dt}: {} vs {zeta}", got.damping_ratio);
            assert!((got.period_s - 2.0 * PI * dt / theta).abs() < 1e-12 * got.period_s);
            // Measured from the steps: the decay of successive maxima.
            let q = run(Scheme::BackwardEuler, omega, 0.0, dt, (4.0 * got.period_s / dt) as usize + 8);
            if dt < 1e-3 + 1e-12 {
                let p = peaks(&q, dt);
                let per = (p[2].0 - p[0].0) / 2.0;
                assert!((per / got.period_s - 1.0).abs() < 1e-3, "dt {dt}: period {per} vs {}", got.period_s);
                let decay = (p[0].1 / p[2].1).ln() / (p[2].0 - p[0].0);
                let zeta_measured = decay / decay.hypot(2.0 * PI / per);
                assert!((zeta_measured - zeta).abs() < 1e-3, "dt {dt}: {zeta_measured} vs {zeta}");
            }
        }
        // At 1/60 s the 15 Hz mode keeps almost nothing of its motion: zeta above 0.4.
        assert!(discrete(Scheme::BackwardEuler, omega, 0.0, 1.0 / 60.0).unwrap().damping_ratio > 0.4);
    }

    #[test]
    fn symplectic_euler_period_error_matches_its_closed_form() {
        // Undamped symplectic Euler: cos(theta) = 1 - (omega dt)^2 / 2, period 2 pi dt / theta,
        // no decay; the period shortens as dt grows and the mode is lost at omega dt = 2.
        let omega = 2.0 * PI * 15.0;
        for wh in [0.01, 0.1, 0.5, 1.0, 1.9] {
            let dt = wh / omega;
            let got = discrete(Scheme::Symplectic, omega, 0.0, dt).unwrap();
            let theta = (1.0 - 0.5 * wh * wh).acos();
            assert!((got.period_s - 2.0 * PI * dt / theta).abs() < 1e-12 * got.period_s, "wh {wh}");
            assert!(got.damping_ratio.abs() < 1e-12);
            let q = run(Scheme::Symplectic, omega, 0.0, dt, (6.0 * got.period_s / dt) as usize + 8);
            if wh <= 0.5 {
                let p = peaks(&q, dt);
                let per = (p[4].0 - p[0].0) / 4.0;
                assert!((per / got.period_s - 1.0).abs() < 2e-3, "wh {wh}: {per} vs {}", got.period_s);
            }
        }
        assert!(discrete(Scheme::Symplectic, omega, 0.0, 2.01 / omega).is_none());
        // Small steps converge to the exact damped motion, for both schemes.
        let gamma = 2.0 * 0.2 * omega;
        let want = exact(omega, gamma);
        for scheme in [Scheme::Symplectic, Scheme::BackwardEuler, Scheme::Trapezoidal] {
            let got = discrete(scheme, omega, gamma, 1e-6).unwrap();
            assert!(period_error(got.period_s, want.period_s) < 1e-4, "{scheme:?}");
            assert!((got.damping_ratio - want.damping_ratio).abs() < 1e-4, "{scheme:?}");
        }
    }

    #[test]
    fn the_trapezoidal_rule_keeps_the_damping_and_its_closed_form_is_the_stepped_one() {
        let omega = 2.0 * std::f64::consts::PI * 15.0;
        let gamma = 2.0 * 0.2 * omega;
        let want = exact(omega, gamma);
        // One 1 ms step per tick: period within 0.1 %, damping within 0.01 of critical.
        let got = discrete(Scheme::Trapezoidal, omega, gamma, 1e-3).unwrap();
        assert!(period_error(got.period_s, want.period_s) < 1e-3, "{got:?} {want:?}");
        assert!((got.damping_ratio - want.damping_ratio).abs() < 1e-2, "{got:?} {want:?}");
        // Undamped: no numerical damping at any step.
        let free = discrete(Scheme::Trapezoidal, omega, 0.0, 5e-3).unwrap();
        assert!(free.damping_ratio.abs() < 1e-12, "{free:?}");
        // The closed form is what stepping does: the recurrence fitted to a stepped run.
        let q = run(Scheme::Trapezoidal, omega, gamma, 1e-3, 400);
        let (stepped, residual) = fit_recurrence(&q, 1e-3);
        assert!(residual < 1e-9, "{residual}");
        assert!(period_error(stepped.period_s, got.period_s) < 1e-9, "{stepped:?} {got:?}");
        assert!((stepped.damping_ratio - got.damping_ratio).abs() < 1e-9);
    }

    #[test]
    fn overdamped_and_unstable_recurrences() {
        let m = from_recurrence(1.0, 0.2, 1e-3).unwrap();
        assert!(m.period_s.is_infinite() && m.damping_ratio > 1.0);
        assert!(from_recurrence(2.2, 1.1, 1e-3).is_none());
        assert!(from_recurrence(-2.5, 1.0, 1e-3).is_none());
    }
}
