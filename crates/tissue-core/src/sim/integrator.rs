//! The one integrator vocabulary and the step policy: which integrator and step a model may run
//! at the step asked for ([`choose_step`], with [`choose_integrator`]'s stability rule for a fixed
//! step), meeting a dynamic budget on the fundamental that each scheme's closed form on one mode
//! predicts ([`crate::response::single_mode`]).

use crate::response::damping::Damping;

/// Time integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Integrator {
    /// Symplectic (semi-implicit) Euler: cheap, stable below a critical time step.
    Symplectic,
    /// Linearised backward Euler: stable for any time step, one sparse factorisation per step.
    Implicit,
    /// Backward Euler with the rest tangent factorised once: one solve per step for the linear
    /// FEM; the lattices and the corotational FEM solve the step's equation by Newton's method,
    /// conjugate gradients on that factor ([`crate::mechanics::newton_krylov`]).
    Prefactored,
    /// Newmark's average acceleration (the trapezoidal rule) with the rest tangent factorised
    /// once: no numerical damping, second order; solved as [`Integrator::Prefactored`] is.
    Newmark,
}

impl Integrator {
    /// What the integrator is on a linear model's mode ([`crate::response::single_mode`]).
    pub fn scheme(self) -> crate::response::single_mode::Scheme {
        match self {
            Integrator::Symplectic => crate::response::single_mode::Scheme::Symplectic,
            Integrator::Implicit | Integrator::Prefactored => crate::response::single_mode::Scheme::BackwardEuler,
            Integrator::Newmark => crate::response::single_mode::Scheme::Trapezoidal,
        }
    }

    /// The lower-case name used on the command line and in files.
    pub fn name(self) -> &'static str {
        match self {
            Integrator::Symplectic => "symplectic",
            Integrator::Implicit => "implicit",
            Integrator::Prefactored => "prefactored",
            Integrator::Newmark => "newmark",
        }
    }
}

/// The integrator's [`Integrator::name`] (width and alignment honoured).
impl std::fmt::Display for Integrator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

/// The time steps a run may ask for, s: from 1 us to 50 ms.
pub const DT_RANGE_S: std::ops::RangeInclusive<f64> = 1e-6..=0.05;

/// Refuses a time step outside [`DT_RANGE_S`] (or not finite), with a message.
pub fn check_dt(dt: f64) -> Result<(), String> {
    if DT_RANGE_S.contains(&dt) {
        Ok(())
    } else {
        Err(format!(
            "{} is out of range: a time step from {} to {} s",
            crate::io::num(dt),
            crate::io::num(*DT_RANGE_S.start()),
            crate::io::num(*DT_RANGE_S.end())
        ))
    }
}

/// The automatic choice runs symplectic Euler up to this fraction of a deforming tissue's
/// stability limit: a margin under the limit from the rest stiffness's stiffest mode (a Lanczos
/// upper estimate, capped by a rigorous bound), for springs stretched by a drag, which stiffen
/// across (0.8 of the step leaves room for `omega_max^2` 1.56 times the rest one).
pub const AUTO_EXPLICIT_FRACTION: f64 = 0.8;
/// Symplectic Euler, asked for by name, is accepted up to this fraction of its limit; the
/// automatic choice goes as far on a tissue whose stiffness does not change as it deforms (the
/// linear FEM: its rest limit is its limit in every state, so no room for stiffening is needed).
pub const MAX_EXPLICIT_FRACTION: f64 = 0.9;

/// The explicit stability limit a step must respect, s: the tissue's (symplectic Euler on its
/// stiffest mode). The tools do not bound the step: the dragging spring is a split step after
/// symplectic Euler, backward Euler on its node ([`crate::sim::drag_velocity_change`]), and
/// inside the implicit schemes' solves ([`crate::mechanics::anchor`]); the probe's contact
/// acts on positions or through the material's surface compliance.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepLimit {
    /// The tissue's explicit limit at rest, s.
    pub tissue: f64,
    /// Whether the tissue's stiffness is the same in every state (the linear FEM), so that its
    /// rest limit holds however it deforms.
    pub constant_stiffness: bool,
}

impl StepLimit {
    /// The limit of a tissue that may stiffen as it deforms (a lattice, the corotational FEM).
    pub fn tissue(tissue: f64) -> Self {
        Self { tissue, constant_stiffness: false }
    }

    /// The limit of a tissue whose stiffness does not change (the linear FEM).
    pub fn constant_stiffness(tissue: f64) -> Self {
        Self { tissue, constant_stiffness: true }
    }

    /// The fraction of the limit the automatic choice runs symplectic Euler up to:
    /// [`MAX_EXPLICIT_FRACTION`] for a constant stiffness, [`AUTO_EXPLICIT_FRACTION`] otherwise.
    pub fn auto_fraction(self) -> f64 {
        if self.constant_stiffness { MAX_EXPLICIT_FRACTION } else { AUTO_EXPLICIT_FRACTION }
    }

    /// The limit of `integrator`: the tissue's for symplectic Euler, none for the implicit schemes.
    pub fn of(self, integrator: Integrator) -> f64 {
        match integrator {
            Integrator::Symplectic => self.tissue,
            Integrator::Implicit | Integrator::Prefactored | Integrator::Newmark => f64::INFINITY,
        }
    }

    /// Whether the automatic choice may run `integrator` at `h`: symplectic Euler within
    /// [`StepLimit::auto_fraction`] of the tissue's limit, an implicit scheme at any step.
    pub fn auto_allows(self, integrator: Integrator, h: f64) -> bool {
        h <= self.auto_fraction() * self.of(integrator)
    }

    /// Why `integrator` at `dt` is refused, if it is: symplectic Euler above
    /// [`MAX_EXPLICIT_FRACTION`] of the tissue's limit.
    pub fn refusal(self, integrator: Integrator, dt: f64) -> Option<String> {
        let limit = self.of(integrator);
        (dt > MAX_EXPLICIT_FRACTION * limit).then(|| {
            format!(
                "symplectic Euler at dt = {} s is above {MAX_EXPLICIT_FRACTION} x its stability limit of about {} s \
                 for this tissue",
                crate::io::num(dt),
                crate::io::num(limit)
            )
        })
    }
}

/// The integrator policy at a fixed step: `requested` (or the automatic choice for `None`:
/// symplectic where [`StepLimit::auto_allows`] it, prefactored implicit otherwise), refused with
/// the message of [`StepLimit::refusal`].
pub fn choose_integrator(requested: Option<Integrator>, dt: f64, limit: StepLimit) -> Result<Integrator, String> {
    let i = requested.unwrap_or(if limit.auto_allows(Integrator::Symplectic, dt) {
        Integrator::Symplectic
    } else {
        Integrator::Prefactored
    });
    match limit.refusal(i, dt) {
        Some(why) => Err(why),
        None => Ok(i),
    }
}

/// Budgets on the dynamic error of the fundamental that the automatic choice of
/// [`choose_step`] meets: the period's relative error and the damping ratio's error (in units of
/// critical), both against the model's own damped fundamental, predicted by the integrator's
/// closed form ([`crate::response::single_mode`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DynamicBudget {
    /// Largest relative period error (0.02 = 2 %).
    pub period: f64,
    /// Largest damping ratio error, in units of critical (0.01 = 1 % of critical).
    pub damping: f64,
}

/// The viewer's dynamic budget: period within 2 %, damping within 1 % of critical.
pub const DEFAULT_DYNAMIC_BUDGET: DynamicBudget = DynamicBudget { period: 0.02, damping: 0.01 };

/// The automatic choice divides the step asked for into at most this many substeps.
pub const MAX_AUTO_SUBSTEPS: usize = 64;

/// How many symplectic steps the automatic choice counts one prefactored step as worth: a
/// prefactored step (a force pass and a sparse solve) cost 39x (hex lattice, 8^3) to 100x
/// (16^3) a symplectic one in `bench`'s resolution sweep, so prefactored Euler is chosen only
/// where it needs under a tenth of symplectic Euler's substeps.
pub const PREFACTORED_STEP_COST: usize = 10;

/// What `scheme` at step `h` does to the fundamental of `damping` (`None`: no fundamental known),
/// as (period error, damping error), or `None` when it does not keep the mode (unstable).
pub fn predicted_error(integrator: Integrator, h: f64, damping: Damping) -> Option<(f64, f64)> {
    let omega = damping.omega_1()?;
    let zeta = damping.ratio()?;
    let gamma = 2.0 * zeta * omega;
    let want = crate::response::single_mode::exact(omega, gamma);
    let got = crate::response::single_mode::discrete(integrator.scheme(), omega, gamma, h)?;
    Some((
        crate::response::single_mode::period_error(got.period_s, want.period_s),
        (got.damping_ratio - want.damping_ratio).abs(),
    ))
}

/// The fewest substeps `k <= MAX_AUTO_SUBSTEPS` of `dt` at which `integrator` is stable
/// ([`StepLimit::auto_allows`]) and, for a model damped by a ratio, meets `budget` on the
/// fundamental (with no fundamental known, the paper's nodal damping, stability alone decides).
pub fn fewest_substeps(
    integrator: Integrator,
    dt: f64,
    limit: StepLimit,
    damping: Damping,
    budget: DynamicBudget,
) -> Option<usize> {
    let budgeted = damping.omega_1().is_some();
    (1..=MAX_AUTO_SUBSTEPS).find(|&k| {
        let h = dt / k as f64;
        limit.auto_allows(integrator, h)
            && (!budgeted
                || predicted_error(integrator, h, damping)
                    .is_some_and(|(p, d)| p <= budget.period && d <= budget.damping))
    })
}

/// The step policy: the integrator and step for the step `dt` asked for.
///
/// * An integrator asked for by name runs at `dt`, or is refused ([`StepLimit::refusal`]).
/// * The automatic choice (`None`) takes, for each integrator, the fewest substeps `dt / k`
///   (`k <= MAX_AUTO_SUBSTEPS`) at which it is stable ([`StepLimit::auto_allows`]) and, for a model damped by a ratio, meets `budget` on the fundamental
///   ([`fewest_substeps`]); then the cheaper tick: symplectic Euler unless prefactored Euler
///   needs under 1 / [`PREFACTORED_STEP_COST`] of its substeps. When the budget is out of reach, prefactored
///   Euler at `dt`, with a note.
///
/// Returns the integrator, the step and a note for the user.
pub fn choose_step(
    requested: Option<Integrator>,
    dt: f64,
    limit: StepLimit,
    damping: Damping,
    budget: DynamicBudget,
) -> Result<(Integrator, f64, Option<String>), String> {
    let meets = |i: Integrator, h: f64| {
        predicted_error(i, h, damping).is_some_and(|(p, d)| p <= budget.period && d <= budget.damping)
    };
    if let Some(i) = requested {
        if let Some(why) = limit.refusal(i, dt) {
            return Err(why);
        }
        let note = predicted_error(i, dt, damping).filter(|_| !meets(i, dt)).map(|(p, d)| {
            format!(
                "{} at dt = {} s misses the dynamic budget on the fundamental: period error {:.2} % (budget {:.1} %), \
                 damping error {:.2} % of critical (budget {:.1} %)",
                i.name(),
                crate::io::num(dt),
                100.0 * p,
                100.0 * budget.period,
                100.0 * d,
                100.0 * budget.damping
            )
        });
        return Ok((i, dt, note));
    }
    let budgeted = damping.omega_1().is_some();
    let first = |i: Integrator| fewest_substeps(i, dt, limit, damping, budget);
    let choice = match (first(Integrator::Symplectic), first(Integrator::Prefactored)) {
        (Some(e), Some(i)) if i * PREFACTORED_STEP_COST < e => Some((Integrator::Prefactored, i)),
        (Some(e), _) => Some((Integrator::Symplectic, e)),
        (None, Some(i)) => Some((Integrator::Prefactored, i)),
        (None, None) => None,
    };
    let keeps = if budgeted {
        format!(
            "keeps the fundamental's period within {:.1} % and its damping within {:.1} % of critical",
            100.0 * budget.period,
            100.0 * budget.damping
        )
    } else {
        "keeps the tissue stable".to_owned()
    };
    Ok(match choice {
        Some((i, 1)) => (i, dt, None),
        Some((i, k)) => {
            let h = dt / k as f64;
            let (h_s, dt_s) = (crate::io::num(h), crate::io::num(dt));
            (i, h, Some(format!("automatic: {} at {h_s} s ({k} substeps of the {dt_s} s asked for) {keeps}", i.name())))
        }
        // The budget is out of reach: prefactored Euler at the step asked for.
        None => (
            Integrator::Prefactored,
            dt,
            Some(format!(
                "no step down to dt / {MAX_AUTO_SUBSTEPS} meets the dynamic budget; prefactored implicit Euler at {} s",
                crate::io::num(dt)
            )),
        ),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only the tissue bounds the step: symplectic Euler is substepped to within
    /// [`AUTO_EXPLICIT_FRACTION`] of its limit and refused by name above
    /// [`MAX_EXPLICIT_FRACTION`]; the implicit schemes run at any step (the drag is inside their
    /// solves).
    #[test]
    fn only_the_tissue_bounds_the_step() {
        let limit = StepLimit::tissue(6e-4);
        let damping = Damping::Ratio { zeta: 0.2, omega_1: 90.0 };
        let (i, h, _) = choose_step(None, 1e-3, limit, damping, DEFAULT_DYNAMIC_BUDGET).expect("auto substeps");
        assert_eq!((i, h), (Integrator::Symplectic, 1e-3 / 3.0));
        let why = choose_step(Some(Integrator::Symplectic), 1e-3, limit, damping, DEFAULT_DYNAMIC_BUDGET)
            .expect_err("refused");
        assert!(why.contains("s is above") && why.contains("for this tissue"), "{why}");
        for named in [Integrator::Prefactored, Integrator::Newmark, Integrator::Implicit] {
            assert!(limit.refusal(named, 1.0).is_none(), "{named:?}");
            assert!(choose_step(Some(named), 1e-3, limit, damping, DEFAULT_DYNAMIC_BUDGET).is_ok(), "{named:?}");
        }
        assert_eq!(limit.of(Integrator::Symplectic), 6e-4);
    }

    /// A tissue whose stiffness does not change (the linear FEM) needs no room for stiffening:
    /// the automatic choice goes up to [`MAX_EXPLICIT_FRACTION`] of its limit, where a deforming
    /// one stops at [`AUTO_EXPLICIT_FRACTION`] (the linear FEM at 24^3: 5 substeps, not 6).
    #[test]
    fn a_constant_stiffness_runs_to_the_named_fraction() {
        let damping = Damping::Ratio { zeta: 0.2, omega_1: 90.0 };
        let substeps = |limit: StepLimit| {
            fewest_substeps(Integrator::Symplectic, 1e-3, limit, damping, DEFAULT_DYNAMIC_BUDGET).expect("stable")
        };
        // 0.2 ms is 0.83 of a 0.242 ms limit.
        assert_eq!(substeps(StepLimit::tissue(2.42e-4)), 6);
        assert_eq!(substeps(StepLimit::constant_stiffness(2.42e-4)), 5);
        let fixed = StepLimit::constant_stiffness(2.42e-4);
        assert!(fixed.auto_allows(Integrator::Symplectic, MAX_EXPLICIT_FRACTION * 2.42e-4));
        assert!(fixed.refusal(Integrator::Symplectic, MAX_EXPLICIT_FRACTION * 2.42e-4).is_none());
    }
}
