//! The core's one error type.

/// What can go wrong in the core, each with a one-line message that names the problem.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A material that cannot be (its file unreadable, malformed, or its constants out of range).
    #[error(transparent)]
    Material(#[from] crate::mechanics::material::MaterialError),
    /// A choice or an input out of its range (a grid, a damping ratio, a step, a press, a node).
    #[error("{0}")]
    Input(String),
    /// A computation that failed (the material's surface compliance, a model that cannot be
    /// built).
    #[error("{0}")]
    Compute(String),
    /// The simulation blew up and its guard gave up: the state went back to rest and the tool
    /// was let go.
    #[error(transparent)]
    BlowUp(#[from] crate::sim::BlowUp),
}

impl Error {
    /// An [`Error::Compute`] of any error, its causes on one line.
    pub(crate) fn compute(e: impl std::fmt::Display) -> Self {
        Self::Compute(format!("{e:#}").replace('\n', " "))
    }
}
