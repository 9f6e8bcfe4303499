//! Damping as a physical quantity: a damping ratio `zeta` at the fundamental of the viewer's
//! scene (face z = 0 clamped), applied as mass-proportional Rayleigh damping,
//! `C = alpha M` with `alpha = 2 zeta omega_1` (`omega_1`: the model's own lowest natural
//! frequency with its lumped masses). Every mode then keeps its shape and decays on its own;
//! mode `k` has the ratio `zeta omega_1 / omega_k`, so the fundamental, which a user sees and
//! feels, has exactly `zeta`. A velocity force, it never changes a static answer.
//!
//! The paper's nodal damper `d` (force `-d v` on every node) stays for the paper's axis lattice
//! (whose rest stiffness has no shear, so no fundamental to set a ratio at) and for `reproduce`.

/// The damping ratio of the viewer, scripts and `dynamics` unless one is given.
pub const DEFAULT_DAMPING_RATIO: f64 = 0.2;
/// The largest damping ratio accepted (twice critical).
pub const MAX_DAMPING_RATIO: f64 = 2.0;

/// The mass-proportional rate `alpha = 2 zeta omega_1`, 1/s.
pub fn mass_proportional_rate(zeta: f64, omega_1: f64) -> f64 {
    2.0 * zeta * omega_1
}

/// `zeta`, checked: finite, from 0 to [`MAX_DAMPING_RATIO`].
pub fn check_ratio(zeta: f64) -> Result<f64, String> {
    if zeta.is_finite() && (0.0..=MAX_DAMPING_RATIO).contains(&zeta) {
        Ok(zeta)
    } else {
        Err(format!(
            "damping ratio {} is out of range: it must be a number from 0 (undamped) to {MAX_DAMPING_RATIO} \
             (1 = critical at the fundamental)",
            crate::io::num(zeta)
        ))
    }
}

/// How a running model is damped.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub enum Damping {
    /// The paper's nodal damper `d`, N s/m.
    Nodal(f64),
    /// The ratio `zeta` at the fundamental `omega_1` (rad/s), mass-proportional.
    Ratio {
        /// Damping ratio at the fundamental.
        zeta: f64,
        /// The model's fundamental on the viewer's scene, rad/s.
        omega_1: f64,
    },
}

impl Damping {
    /// The damping ratio set, if the model is damped by one.
    pub fn ratio(self) -> Option<f64> {
        match self {
            Damping::Ratio { zeta, .. } => Some(zeta),
            Damping::Nodal(_) => None,
        }
    }

    /// The model's fundamental, rad/s, if known.
    pub fn omega_1(self) -> Option<f64> {
        match self {
            Damping::Ratio { omega_1, .. } => Some(omega_1),
            Damping::Nodal(_) => None,
        }
    }

    /// The mass-proportional rate, 1/s (NaN for the nodal damper, whose rate varies by node).
    pub fn rate(self) -> f64 {
        match self {
            Damping::Ratio { zeta, omega_1 } => mass_proportional_rate(zeta, omega_1),
            Damping::Nodal(_) => f64::NAN,
        }
    }
}
