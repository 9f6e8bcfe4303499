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
