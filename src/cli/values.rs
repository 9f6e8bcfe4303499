//! The core enums' names on the command line ([`Named`], read by [`parser`]), so that clap stays in
//! the command-line layer.

use crate::calibrate::{CaseSet, CostMode, Method};
use crate::gpu::Compute;
use crate::mechanics::cases::Bc;
use crate::mechanics::fem::dynamics::Formulation;
use crate::mechanics::msm::Topology;
use crate::render::scene::ColourMode;
use crate::sim::Integrator;
use crate::study::choose::Metric;

/// A core enum's command-line names: each variant with its name and its help (the variant's doc,
/// as clap's derive showed it). The enums live below the command line, so clap's own trait cannot
/// be implemented for them here; [`parser`] gives clap their values.
pub(crate) trait Named: Sized + Clone + Send + Sync + 'static {
    /// Every variant, its name and its help.
    fn values() -> &'static [(Self, &'static str, &'static str)];
}

macro_rules! value_enum {
    ($ty:ident { $($variant:ident => $name:literal, $help:literal;)+ }) => {
        impl Named for $ty {
            fn values() -> &'static [(Self, &'static str, &'static str)] {
                &[$(($ty::$variant, $name, $help)),+]
            }
        }
    };
}

/// The parser of a [`Named`] enum's values, which `--help` lists with their help.
pub(crate) fn parser<T: Named>() -> impl clap::builder::TypedValueParser<Value = T> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
    PossibleValuesParser::new(T::values().iter().map(|(_, name, help)| PossibleValue::new(*name).help(*help))).map(
        |s: String| {
            let values = T::values();
            // The parser above took only these names.
            values.iter().find(|(_, name, _)| *name == s).unwrap_or(&values[0]).0.clone()
        },
    )
}

value_enum!(Formulation {
    Linear => "linear", "Small-strain linear elasticity, `f = -K u`";
    Corotational => "corotational", "Corotational: linear elasticity in each element's rotated frame";
});
value_enum!(Bc {
    Clamped => "clamped", "Face `x_a = 0` fully fixed, equal nodal forces `F / n^2` on face `x_a = L`";
    Patch => "patch", "Roller supports removing rigid motion only, consistent nodal loads of a uniform traction";
});
value_enum!(Topology {
    Axis => "axis", "The paper's model: axis-aligned structural springs only (no shear stiffness)";
    Shear => "shear", "Axis springs plus both diagonals of every lattice square, one stiffness per plane";
    Hex => "hex",
        "The springs of every hex element: its 12 edges, 12 face diagonals and 4 body diagonals, one stiffness per \
         family group (`k1..k3`, `c12..c23`, `b`). A spring shared by several elements gets each element's share, so \
         springs on the surface are softer than inside (an edge spring on a face has half, on a cube edge a quarter of \
         an interior one's stiffness). Calibrated, it is the most accurate lattice here: see the `reproduce` report";
});
value_enum!(Method {
    Hybrid => "hybrid", "GA with Metropolis screening of crossover (XSA) and mutation (MSA): the paper's method";
    Ga => "ga", "Plain GA, same operators and settings, no screening";
    Sa => "sa", "Simulated annealing alone: `sa_iterations` moves at each of `generations` temperatures";
    StiffnessFit => "stiffness-fit", "Load-free baseline: non-negative least-squares fit of the lattice's stiffness matrix to the FEM's";
});
value_enum!(CaseSet {
    Paper => "paper", "The paper's nine clamped face loads (eq. 1)";
    Touch => "touch", "The touch benchmark's training cases (point loads, top shear, probe), then an L-BFGS polish";
    Both => "both", "The touch cost plus the paper's cost relative to the FEM's displacements";
    Presses => "presses", "The continuum's 24 training presses (the material's probe force, node contact at --nodes), then an L-BFGS polish";
});
value_enum!(CostMode {
    Static => "static", "Static equilibria (the paper's cost; `d` is not identified)";
    Transient => "transient", "The state a fixed time after a step load from rest (see [`transient`]); identifies `d`";
});
value_enum!(ColourMode {
    None => "none", "Plain shading";
    Displacement => "displacement", "Displacement magnitude";
    Error => "error", "Distance between the MSM and the FEM answer of the case";
});
value_enum!(Integrator {
    Symplectic => "symplectic", "Symplectic (semi-implicit) Euler: cheap, stable below a critical time step";
    Implicit => "implicit", "Linearised backward Euler with the tangent of every step (lattices only)";
    Prefactored => "prefactored", "Backward Euler with the rest tangent factorised once (the lattices and the corotational FEM: Newton on the step's equation, conjugate gradients on that factor)";
    Newmark => "newmark", "Newmark average acceleration (trapezoidal, no numerical damping) with the rest tangent factorised once (the lattices and the corotational FEM: as prefactored)";
});
value_enum!(Compute {
    Cpu => "cpu", "The CPU, in f64";
    CpuF32 => "cpu-f32", "The CPU, the symplectic step of the lattices and the linear FEM with its force summed in f32";
    Gpu => "gpu", "Symplectic steps of the lattices and the linear FEM as wgpu compute shaders, in f32";
});
value_enum!(Metric {
    Max => "max", "The worst node (the default: a budget holds everywhere)";
    Avg => "avg", "The average over nodes (the paper's headline figure)";
});

#[cfg(test)]
mod tests {
    use clap::CommandFactory as _;

    use super::*;
    use crate::cli::Cli;

    /// Command-line names are those of the files (`name()`) and of serde.
    #[test]
    fn value_names_match_the_core_names() {
        fn check<T: Named + serde::Serialize>(name: impl Fn(&T) -> String) {
            for (v, value, _) in T::values() {
                assert_eq!(*value, name(v));
                assert_eq!(serde_json::to_value(v).expect("serialises"), *value);
            }
        }
        check::<Formulation>(|v| v.name().into());
        check::<Bc>(|v| v.name().into());
        check::<Topology>(|v| v.name().into());
        check::<Method>(|v| v.name().into());
        check::<CaseSet>(|v| v.name().into());
        check::<CostMode>(|v| format!("{v:?}").to_lowercase());
        check::<ColourMode>(|v| format!("{v:?}").to_lowercase());
        check::<Compute>(|v| v.name().into());
        assert_eq!(Metric::values().len(), 2);
        Cli::command().debug_assert();
    }
}
