//! The user's tools: a dragging spring and a rigid spherical probe.

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

/// The velocity change of the held node (mass `node_mass`, kg; at `x` moving at `v` after the
/// tissue's step) that the dragging spring towards `target` makes over a step `dt`, m/s: backward
/// Euler on the node's spring and damper, `dv (1 + dt c / m + dt^2 k / m) = dt / m (k (target - x)
/// - c v)`, then `v += dv`, `x += dt dv`. Applied after the tissue's step (a split step), it is
/// stable at any step on any node, so the drag does not bound the step (its damper alone, applied
/// explicitly, held a cube corner's step at 16^3 to 70 us); at rest the pull balances the
/// tissue exactly (`k (target - x)` at any step). The force on the hand is `-m dv / dt`. It
/// follows symplectic Euler only; the implicit schemes carry the spring inside their solves
/// ([`crate::mechanics::anchor`]), where a split step left a trapezoidal step's held node a
/// steady velocity of `dt f / (2 m)`.
pub fn drag_velocity_change(target: [f64; 3], x: [f64; 3], v: [f64; 3], node_mass: f64, dt: f64) -> [f64; 3] {
    let (k, c) = (DRAG_STIFFNESS / node_mass, DRAG_DAMPING / node_mass);
    let scale = dt / (1.0 + dt * c + dt * dt * k);
    std::array::from_fn(|i| scale * (k * (target[i] - x[i]) - c * v[i]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A node held only by the dragging spring, stepped by its split step: it settles on the
    /// target without overshooting past its start, at any step and however light.
    #[test]
    fn the_drag_settles_at_any_step_on_any_node() {
        for m in [3.6e-4, 3.7e-5, 4.2e-6, 1e-8] {
            for dt in [1e-6, 1e-4, 1e-3, 1e-2] {
                let (mut x, mut v, mut peak) = ([0.01, 0.0, 0.0], [0.0; 3], 0.0f64);
                for _ in 0..20_000 {
                    let dv = drag_velocity_change([0.0; 3], x, v, m, dt);
                    for c in 0..3 {
                        v[c] += dv[c];
                        x[c] += dt * v[c];
                    }
                    peak = peak.max(x[0].abs());
                }
                assert!(peak <= 0.01 + 1e-12, "m = {m}, dt = {dt}: peak {peak}");
                assert!(x[0].abs() < 1e-4, "m = {m}, dt = {dt}: {x:?}");
            }
        }
    }

    /// Against a steady force `f` on the node (the tissue's, stepped explicitly before the
    /// spring), the node comes to rest where the spring balances it, whatever the step.
    #[test]
    fn the_static_pull_balances_the_tissue_at_any_step() {
        let (m, f) = (3.7e-5, 2.0);
        for dt in [1e-5, 1e-4, 1e-3] {
            let (mut x, mut v) = ([0.0; 3], [0.0; 3]);
            for _ in 0..200_000 {
                v[0] += dt * f / m;
                x[0] += dt * v[0];
                let dv = drag_velocity_change([0.0; 3], x, v, m, dt);
                for c in 0..3 {
                    v[c] += dv[c];
                    x[c] += dt * dv[c];
                }
            }
            let want = f / DRAG_STIFFNESS;
            assert!((x[0] - want).abs() < 1e-9 * want.max(1.0), "dt = {dt}: {} vs {want}", x[0]);
        }
    }
}
