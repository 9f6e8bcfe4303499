//! The user's tools: a dragging spring and a rigid spherical probe.

use crate::response::single_mode::damped_explicit_limit;

/// A user tool acting on the tissue.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tool {
    /// Nothing held.
    None,
    /// A node pulled towards `target` (metres) by a stiff spring.
    Drag {
        /// The held node.
        node: usize,
        /// Where the mouse puts it, metres.
        target: [f64; 3],
    },
    /// A rigid sphere; no node may be inside it.
    Probe {
        /// Centre, metres.
        centre: [f64; 3],
        /// Radius, metres.
        radius: f64,
    },
}

/// Stiffness of the dragging spring, N/m.
pub const DRAG_STIFFNESS: f64 = 1000.0;
/// Damping of the dragging spring, N s/m.
pub const DRAG_DAMPING: f64 = 1.0;

/// The largest step at which the dragging spring, applied explicitly as an external force, stays
/// stable on a node of mass `node_mass` (kg): symplectic Euler's limit on the spring-damper alone
/// ([`damped_explicit_limit`] of `sqrt(k / m)` and `c / m`), s. Light nodes (a cube corner's) are
/// the tightest.
pub fn drag_dt_limit(node_mass: f64) -> f64 {
    damped_explicit_limit((DRAG_STIFFNESS / node_mass).sqrt(), DRAG_DAMPING / node_mass)
}
