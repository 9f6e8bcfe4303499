//! A model's probe force against the material's ([`crate::validate::continuum`]) on the scored
//! presses ([`crate::validate::probe::presses`]), with the same-mesh FEM beside it ("against its own
//! mesh"): the `material` part of `validate`.

use crate::mechanics::material::Material;
use crate::validate::continuum::Press;
use crate::validate::continuum::cache::ContinuumCache;
use crate::validate::probe::presses::{PressCase, press_cases};
use crate::validate::touch::Set;
use crate::validate::touch::score::Responder;

/// One press's forces, newtons along the pressing direction.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PressScore {
    /// Case id.
    pub id: String,
    /// training or validation.
    pub set: Set,
    /// The press.
    pub press: Press,
    /// The model's force.
    pub force_n: f64,
    /// The material's (the converged continuum reference).
    pub material_force_n: f64,
    /// The hex8 FEM's on the model's own mesh, same node contact.
    pub own_mesh_fem_force_n: f64,
    /// `force_n / material_force_n - 1`.
    pub error: f64,
    /// `force_n / own_mesh_fem_force_n - 1`; none (`null`) where the FEM feels nothing.
    pub own_mesh_error: Option<f64>,
}

/// The scores against the material.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MaterialReport {
    /// How the model's probe touches: `surface` (the material's surface compliance) or `nodes`
    /// (the model's surface nodes).
    pub contact: crate::sim::press::Contact,
    /// What the reference is.
    pub reference: String,
    /// Its convergence tolerance (relative change of the force between two spacings).
    pub tolerance: f64,
    /// Per press.
    pub cases: Vec<PressScore>,
    /// Largest `|error|` over the validation presses.
    pub worst_error: f64,
    /// Median `|error|` over the validation presses.
    pub median_error: f64,
    /// Largest `|error|` over the training presses; none (`null`) without training presses.
    pub worst_training_error: Option<f64>,
    /// Largest `|own_mesh_fem_force_n / material_force_n - 1|` over the validation presses.
    pub own_mesh_fem_worst_error: f64,
    /// Presses over inclusions whose continuum answer could not be computed (within its memory
    /// bound), and why: left out of the scores.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub missing: Vec<String>,
}

/// The force along the press's direction of a responder's node contact.
pub fn responder_force_n(responder: &mut Responder, press: &Press) -> anyhow::Result<f64> {
    Ok(press.force_along(responder.press(press.centre(), press.radius)?))
}

/// The force along the press's direction with the material's surface compliance as contact.
pub fn compliance_force_n(
    compliance: &crate::sim::material_surface::compliance::SurfaceCompliance,
    scratch: &mut crate::sim::material_surface::compliance::SurfaceContactScratch,
    press: &Press,
) -> anyhow::Result<f64> {
    Ok(press.force_along(compliance.press(press.centre(), press.radius, scratch)?))
}

/// Scores a model's probe (`model_force(press)`, newtons along the press, touching as
/// `contact` says) with the same-mesh FEM `fem` beside it, on every press against `material`'s
/// continuum answers from `cache` (computed where missing, `progress(i, n, case, spacing)`
/// before each spacing of a computation).
pub fn evaluate(
    material: &Material,
    contact: crate::sim::press::Contact,
    model_force: &mut dyn FnMut(&Press) -> anyhow::Result<f64>,
    fem: &mut Responder,
    cache: &mut ContinuumCache,
    tolerance: f64,
    progress: &mut dyn FnMut(usize, usize, &PressCase, f64),
) -> anyhow::Result<MaterialReport> {
    // A material with inclusions is scored over them, at their rims and away from them.
    let cases =
        if material.inclusions.is_empty() { press_cases() } else { super::presses::inclusion_press_cases(material) };
    let mut scores = Vec::with_capacity(cases.len());
    let mut missing = Vec::new();
    for (i, case) in cases.iter().enumerate() {
        let material_force = cache.force(material, &case.press, tolerance, &mut |s| progress(i, cases.len(), case, s));
        // Keep what was computed even when a later press fails; a press over an inclusion the
        // continuum cannot resolve within its bounds is reported missing.
        let material_force = match material_force {
            Ok(f) => f,
            Err(e) if !material.inclusions.is_empty() => {
                missing.push(format!("{}: {e:#}", case.id));
                continue;
            }
            Err(e) => {
                cache.save();
                return Err(e);
            }
        };
        let force_n = model_force(&case.press)?;
        let own = responder_force_n(fem, &case.press)?;
        let m = material_force.force_n;
        scores.push(PressScore {
            id: case.id.clone(),
            set: case.set,
            press: case.press,
            force_n,
            material_force_n: m,
            own_mesh_fem_force_n: own,
            error: force_n / m - 1.0,
            own_mesh_error: (own > 0.0).then(|| force_n / own - 1.0),
        });
    }
    cache.save();
    let of = |set: Set, f: &dyn Fn(&PressScore) -> f64| -> Vec<f64> {
        let mut v: Vec<f64> = scores.iter().filter(|c| c.set == set).map(f).collect();
        v.sort_by(f64::total_cmp);
        v
    };
    let validation = of(Set::Validation, &|c| c.error.abs());
    let median_error = match validation.len() {
        0 => 0.0,
        n if n % 2 == 1 => validation[n / 2],
        n => 0.5 * (validation[n / 2 - 1] + validation[n / 2]),
    };
    Ok(MaterialReport {
        contact,
        reference: "the material: hex8 FEM on meshes graded around the contact, refined until the force changes by \
                    less than the tolerance; frictionless sphere, face z = 0 clamped"
            .into(),
        tolerance,
        worst_error: validation.last().copied().unwrap_or(0.0),
        median_error,
        worst_training_error: of(Set::Training, &|c| c.error.abs()).last().copied(),
        own_mesh_fem_worst_error: of(Set::Validation, &|c| (c.own_mesh_fem_force_n / c.material_force_n - 1.0).abs())
            .last()
            .copied()
            .unwrap_or(0.0),
        missing,
        cases: scores,
    })
}

/// The worst `|force / material - 1|` over the validation presses of a probe `force(press)`
/// (newtons along the press) against `material`'s continuum answers from `cache` (computed and
/// kept where missing).
pub fn worst_validation_error(
    material: &Material,
    cache: &mut ContinuumCache,
    force: &mut dyn FnMut(&Press) -> anyhow::Result<f64>,
) -> anyhow::Result<f64> {
    let mut worst = 0.0f64;
    for case in press_cases().iter().filter(|c| c.set == Set::Validation) {
        let m = cache.force(material, &case.press, crate::validate::continuum::DEFAULT_TOLERANCE, &mut |_| {})?;
        worst = worst.max((force(&case.press)? / m.force_n - 1.0).abs());
    }
    cache.save();
    Ok(worst)
}

/// The training presses on the top face (the calibrations') with the material's force on each
/// (the magnitude, newtons), from the shipped answers or the cache folder (computed and kept there where missing: minutes, each
/// press said on standard error as it starts).
pub fn training_forces(material: &Material) -> anyhow::Result<Vec<(Press, f64)>> {
    let mut cache = ContinuumCache::open(material, crate::io::cache_dir().as_deref());
    let mut out = Vec::new();
    let all = press_cases();
    let cases: Vec<&PressCase> = all.iter().filter(|c| c.set == Set::Training && c.on_top_face()).collect();
    let tolerance = crate::validate::continuum::DEFAULT_TOLERANCE;
    for (i, case) in cases.iter().enumerate() {
        if cache.get(&case.press, tolerance).is_none() {
            crate::io::progress(&format!(
                "tissue-sim: computing the material's force on training press {} of {} ({}; 2 to 15 s each)",
                i + 1,
                cases.len(),
                case.id
            ));
        }
        let m = cache.force(material, &case.press, tolerance, &mut |_| {})?;
        out.push((case.press, glam::DVec3::from(m.force).length()));
    }
    cache.save();
    Ok(out)
}

/// A relative error as a percentage column, `n/a` where it is not defined (the reference is 0).
fn percent(e: Option<f64>) -> String {
    e.map_or_else(|| "n/a".to_owned(), |e| format!("{:.1}%", 100.0 * e))
}

impl MaterialReport {
    /// The table `validate` prints.
    pub fn to_text(&self) -> String {
        let mut s = format!(
            "Probe force against the material (the continuum: graded hex8 meshes refined to {:.1} %), newtons; \
             contact: {}\n\
             {:<34} {:<10} {:>8} {:>9} {:>9} {:>8} {:>9}\n",
            100.0 * self.tolerance,
            self.contact.name(),
            "press",
            "set",
            "model",
            "material",
            "own FEM",
            "error",
            "vs own"
        );
        for c in &self.cases {
            s += &format!(
                "{:<34} {:<10} {:>8.3} {:>9.3} {:>9.3} {:>7.1}% {:>9}\n",
                c.id,
                format!("{:?}", c.set).to_lowercase(),
                c.force_n,
                c.material_force_n,
                c.own_mesh_fem_force_n,
                100.0 * c.error,
                percent(c.own_mesh_error)
            );
        }
        s += &format!(
            "validation presses against the material: worst {:.1} %, median {:.1} % (training worst {}); \
             the same-mesh FEM: worst {:.1} %\n",
            100.0 * self.worst_error,
            100.0 * self.median_error,
            self.worst_training_error
                .map_or_else(|| "n/a: no training presses".to_owned(), |e| format!("{:.1} %", 100.0 * e)),
            100.0 * self.own_mesh_fem_worst_error
        );
        for m in &self.missing {
            s += &format!("missing (the continuum did not converge): {m}\n");
        }
        s
    }
}
