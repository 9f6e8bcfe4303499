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
    /// Linearised backward Euler with the rest tangent factorised once: one solve per step.
    Prefactored,
    /// Newmark's average acceleration (the trapezoidal rule) with the rest tangent factorised
    /// once: one solve per step, no numerical damping, second order.
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

/// The automatic choice runs symplectic Euler up to this fraction of its stability limit.
pub const AUTO_EXPLICIT_FRACTION: f64 = 0.5;
/// Symplectic Euler, asked for by name, is accepted up to this fraction of its limit.
pub const MAX_EXPLICIT_FRACTION: f64 = 0.9;

/// The explicit stability limits a step must respect, s: the tissue's (symplectic Euler on its
/// stiffest mode) and the dragging spring's (an external force, explicit under every integrator;
/// infinite when no node can be dragged).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepLimit {
    /// The tissue's explicit limit, s.
    pub tissue: f64,
    /// The dragging spring's limit on the lightest node it may hold, s.
    pub tool: f64,
}

impl StepLimit {
    /// Only the tissue's limit (no tool).
    pub fn tissue(tissue: f64) -> Self {
        Self { tissue, tool: f64::INFINITY }
    }

    /// The limit of `integrator`: symplectic Euler steps the tissue and the tool explicitly
    /// (their squared frequencies add), the implicit schemes the tool only.
    pub fn of(self, integrator: Integrator) -> f64 {
        match integrator {
            Integrator::Symplectic => 1.0 / (self.tissue.powi(-2) + self.tool.powi(-2)).sqrt(),
            Integrator::Implicit | Integrator::Prefactored | Integrator::Newmark => self.tool,
        }
    }

    /// Whether the automatic choice may run `integrator` at `h`: stable with a margin
    /// ([`MAX_EXPLICIT_FRACTION`] of its limit), and symplectic Euler within
    /// [`AUTO_EXPLICIT_FRACTION`] of the tissue's limit (its accuracy on the stiff modes).
    pub fn auto_allows(self, integrator: Integrator, h: f64) -> bool {
        h <= MAX_EXPLICIT_FRACTION * self.of(integrator)
            && (integrator != Integrator::Symplectic || h <= AUTO_EXPLICIT_FRACTION * self.tissue)
    }

    /// Why `integrator` at `dt` is refused, if it is: symplectic Euler above
    /// [`MAX_EXPLICIT_FRACTION`] of its limit, an implicit scheme above the spring's limit.
    pub fn refusal(self, integrator: Integrator, dt: f64) -> Option<String> {
        // Symplectic Euler keeps a margin below its limit; under an implicit scheme the tissue
        // only steadies the node the spring holds, so the spring's own limit is the bound.
        let limit = self.of(integrator);
        let (margin, above) = match integrator {
            Integrator::Symplectic => (MAX_EXPLICIT_FRACTION, format!("{MAX_EXPLICIT_FRACTION} x ")),
            Integrator::Implicit | Integrator::Prefactored | Integrator::Newmark => (1.0, String::new()),
        };
        if dt <= margin * limit {
            return None;
        }
        let dt = crate::io::num(dt);
        Some(if integrator == Integrator::Symplectic && self.tissue <= self.tool {
            format!(
                "symplectic Euler at dt = {dt} s is above {MAX_EXPLICIT_FRACTION} x its stability limit of about {} s \
                 for this tissue",
                crate::io::num(limit)
            )
        } else {
            format!(
                "{} at dt = {dt} s is above {above}the stability limit of about {} s of the dragging spring \
                 ({} N/m, {} N s/m, applied explicitly) on the lightest node it holds",
                integrator.name(),
                crate::io::num(limit),
                super::tool::DRAG_STIFFNESS,
                super::tool::DRAG_DAMPING
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
///   (`k <= MAX_AUTO_SUBSTEPS`) at which it is stable ([`StepLimit::auto_allows`]: the tissue and
///   the dragging spring) and, for a model damped by a ratio, meets `budget` on the fundamental
///   ([`fewest_substeps`]); then the cheaper tick: symplectic Euler unless prefactored Euler
///   needs under 1 / [`PREFACTORED_STEP_COST`] of its substeps. When the budget is out of reach, the fewest
///   stable prefactored substeps, with a note; when even `dt / MAX_AUTO_SUBSTEPS` is unstable, a
///   refusal.
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
        "keeps the tissue and the dragging spring stable".to_owned()
    };
    Ok(match choice {
        Some((i, 1)) => (i, dt, None),
        Some((i, k)) => {
            let h = dt / k as f64;
            let (h_s, dt_s) = (crate::io::num(h), crate::io::num(dt));
            (i, h, Some(format!("automatic: {} at {h_s} s ({k} substeps of the {dt_s} s asked for) {keeps}", i.name())))
        }
        None => {
            // The budget is out of reach: the fewest prefactored substeps the tool allows.
            let stable = |k: &usize| limit.auto_allows(Integrator::Prefactored, dt / *k as f64);
            let Some(k) = (1..=MAX_AUTO_SUBSTEPS).find(stable) else {
                let h = dt / MAX_AUTO_SUBSTEPS as f64;
                return Err(format!(
                    "even dt / {MAX_AUTO_SUBSTEPS} = {} s is above {MAX_EXPLICIT_FRACTION} x the stability limit of \
                     about {} s of the dragging spring on the lightest node it holds",
                    crate::io::num(h),
                    crate::io::num(limit.tool)
                ));
            };
            let h = dt / k as f64;
            (
                Integrator::Prefactored,
                h,
                Some(format!(
                    "no step down to dt / {MAX_AUTO_SUBSTEPS} meets the dynamic budget; prefactored implicit Euler at \
                     {} s",
                    crate::io::num(h)
                )),
            )
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::tool::drag_dt_limit;

    /// The dragging spring is in the choice: a step the tissue alone allows but the spring on a
    /// light node does not is substepped automatically, and refused by name when asked for.
    #[test]
    fn the_drag_spring_bounds_every_integrator() {
        let tool = drag_dt_limit(3.6e-4);
        assert!(tool > 1e-4 && tool < 1e-3, "{tool}");
        let limit = StepLimit { tissue: 6e-4, tool };
        let damping = Damping::Ratio { zeta: 0.2, omega_1: 90.0 };
        let (i, h, _) = choose_step(None, 1e-3, limit, damping, DEFAULT_DYNAMIC_BUDGET).expect("auto substeps");
        assert!(h <= MAX_EXPLICIT_FRACTION * limit.of(i), "{i:?} at {h}");
        for named in [Integrator::Symplectic, Integrator::Prefactored, Integrator::Implicit] {
            let why = choose_step(Some(named), 1e-3, limit, damping, DEFAULT_DYNAMIC_BUDGET).expect_err("refused");
            assert!(why.contains("s is above"), "{why}");
        }
        let why = StepLimit { tissue: 1.0, tool }.refusal(Integrator::Prefactored, 1e-3).expect("refused");
        assert!(why.contains("dragging spring"), "{why}");
        // Without a tool the implicit schemes have no limit.
        assert!(StepLimit::tissue(1e-5).refusal(Integrator::Prefactored, 1.0).is_none());
        assert_eq!(StepLimit::tissue(1e-5).of(Integrator::Symplectic), 1e-5);
    }
}
