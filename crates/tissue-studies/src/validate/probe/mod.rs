//! A probe against the material: the presses a probe is scored on ([`presses`]: training and
//! held-out sets over every free face, its edges and a corner, along the normal and oblique), the score of a probe's force against the converged
//! continuum ([`score`]), and the viewer's fast tap run against the material's ([`tap`]).

pub mod presses;
pub mod score;
pub mod tap;
