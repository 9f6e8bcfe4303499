//! A model's symplectic Euler step written out as plain numbers, for a step computed elsewhere
//! (the GPU's, in the layer above): the force operator, each node's inverse mass and damping rate,
//! and which components are free. No GPU types here; the step it describes is
//! `v' = (v + dt (f(u) + f_ext) / m - dt c v) free`, `u' = u + dt v'`, with `u = x - X` the
//! displacement from rest, exactly the lattices' and the linear FEM's CPU step.

use crate::mechanics::grid::Grid;

/// One spring family of a lattice: the pairs `(p, p + offset)`.
#[derive(Debug, Clone)]
pub struct FamilyForm {
    /// Linear node offset between the two nodes of a pair.
    pub offset: usize,
    /// The rest vector from the first node of a pair to the second, metres.
    pub rest: [f64; 3],
    /// Rest length, metres.
    pub rest_length: f64,
    /// Stiffness of the pair starting at each node, N/m (zero where there is no spring).
    pub stiffness: Vec<f64>,
}

/// The internal force of a model, as a function of the displacement `u`.
#[derive(Debug, Clone)]
pub enum ForceForm {
    /// Springs, family by family (the lattices; nonlinear in `u`).
    Springs(Vec<FamilyForm>),
    /// `-K u` with `K` as 27 classes x 27 blocks of 3x3 (row-major), the linear FEM's
    /// [`crate::mechanics::fem::stencil::Stencil`].
    Stencil(Vec<[[f64; 9]; 27]>),
}

/// A model's explicit step, in numbers.
#[derive(Debug, Clone)]
pub struct ExplicitForm {
    /// The grid the nodes lie on.
    pub grid: Grid,
    /// The internal force.
    pub force: ForceForm,
    /// `1 / m` of each node, 1/kg.
    pub inv_mass: Vec<f64>,
    /// The damping force over the mass of each node, `c_p / m_p`, 1/s.
    pub damping_rate: Vec<f64>,
    /// 1 for a free component, 0 for a held one, component-major (`free[c][p]`).
    pub free: [Vec<f64>; 3],
}
