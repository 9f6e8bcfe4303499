//! The presses the probe's contact can resolve, checked before a run: the one home of the
//! probe's size and depth limits (scripts, `--help` and the viewer's radius take them from here).
//!
//! A press is a rigid frictionless sphere of `radius` tangent to the tissue's undeformed surface
//! at the point `at` ([`centre`]) and moved `depth` along the unit `direction`. Its contact is refused when:
//! - the sphere is smaller than the material's surface grid resolves ([`MIN_RADIUS_M`]: its
//!   contact patch would span about one node of the 2 mm face grid);
//! - it is wider than the contact holds ([`MAX_RADIUS_M`], and at most
//!   [`MAX_CONTACT_NODES`] surface nodes under it);
//! - it goes deeper than it can be pressed ([`MAX_DEPTH_OF_RADIUS`] of its radius: beyond, the
//!   contact linearised along the normals at rest turns the nodes past the sphere's equator and
//!   the force falls, then pulls);
//! - it starts inside the tissue, or moves along a direction that does not take it into the
//!   tissue, or presses a clamped face (held nodes take any load: the force would be the
//!   support's, not the material's).

use glam::DVec3;

use crate::mechanics::grid::CUBE_SIDE_M;
pub use crate::sim::material_surface::compliance::MAX_CONTACT_NODES;
use crate::sim::material_surface::compliance::{DEFAULT_DIVISIONS, window_count};

/// The probe's radius unless one is asked for (the viewer's, the touch benchmark's), metres.
pub const DEFAULT_RADIUS_M: f64 = 0.015;

/// The smallest probe radius, metres: 2.5 nodes of the surface grid.
pub const MIN_RADIUS_M: f64 = 0.005;
/// The largest probe radius, metres.
pub const MAX_RADIUS_M: f64 = 0.05;
/// The deepest press, as a fraction of the radius.
pub const MAX_DEPTH_OF_RADIUS: f64 = 0.75;
/// How far a point may be from a face and still lie on it, metres.
const ON_SURFACE_M: f64 = 1e-6;

/// The limits in one line, for `--help` and messages.
pub const LIMITS: &str = "probe radius 5 to 50 mm, depth at most 3/4 of the radius, starting on or outside the \
                          tissue's surface, moving into it, not into a clamped face";

/// One press: the sphere is tangent to the undeformed surface at `at` (a point of a free face,
/// edge or corner) at depth 0 and moves `depth` into the tissue along `direction`, by default the
/// inward normal there ([`centre`]).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Press {
    /// The touched point on the free surface, metres.
    pub at: [f64; 3],
    /// Sphere radius, metres.
    pub radius: f64,
    /// Depth, metres.
    pub depth: f64,
    /// The unit pressing direction where it is not the inward normal at `at` (an oblique press).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<[f64; 3]>,
}

impl Press {
    /// A press of a sphere of `radius` (metres) along the inward normal of the surface at `at`
    /// (a point of a free face, edge or corner, metres), at depth 0: tangent there ([`Press::depth`]
    /// sets how far it goes in).
    pub fn normal(at: [f64; 3], radius: f64) -> Self {
        Self { at, radius, depth: 0.0, direction: None }
    }

    /// A press of a sphere of `radius` touching the surface at `at` and moving along `direction`
    /// (normalised here; an oblique press), at depth 0.
    pub fn along(at: [f64; 3], direction: [f64; 3], radius: f64) -> Self {
        let d = DVec3::from(direction);
        let unit = if d.length() > 0.0 { (d / d.length()).to_array() } else { direction };
        Self { at, radius, depth: 0.0, direction: Some(unit) }
    }

    /// The press `depth` metres in along its direction.
    #[must_use]
    pub fn depth(self, depth: f64) -> Self {
        Self { depth, ..self }
    }

    /// The probe tool of this press (the sphere at its [`Press::centre`]).
    pub fn tool(&self) -> crate::sim::Tool {
        crate::sim::Tool::Probe { centre: self.centre(), radius: self.radius }
    }

    /// Checks the press: on the free surface, radius from 1 to 50 mm, depth from 0 to 0.8 of the
    /// radius, a unit direction into the tissue.
    pub fn check(&self) -> Result<(), String> {
        let n = DVec3::from(free_face_normal(self.at)?);
        if !(self.radius.is_finite() && (1e-3..=0.05).contains(&self.radius)) {
            return Err(format!("probe radius {} m is outside 0.001 to 0.05 m", self.radius));
        }
        if !(self.depth.is_finite() && self.depth >= 0.0 && self.depth <= 0.8 * self.radius) {
            return Err(format!("probe depth {} m is outside 0 to 0.8 of the radius", self.depth));
        }
        let d = DVec3::from(self.direction());
        if !d.is_finite() || (d.length() - 1.0).abs() > 1e-9 || d.dot(n) >= -1e-9 {
            return Err(format!("the press direction {d} is not a unit vector into the tissue at {:?}", self.at));
        }
        Ok(())
    }

    /// The sphere's centre, metres.
    pub fn centre(&self) -> [f64; 3] {
        centre(self.at, DVec3::from(self.direction()), self.radius, self.depth)
    }

    /// The pressing direction (by default the inward normal at `at`).
    pub fn direction(&self) -> [f64; 3] {
        self.direction.unwrap_or_else(|| free_face_normal(self.at).unwrap_or([0.0, 0.0, 1.0]).map(|c| -c))
    }

    /// The component of the tissue's `force` on the sphere against the pressing direction,
    /// newtons: what pushes back.
    pub fn force_along(&self, force: [f64; 3]) -> f64 {
        -DVec3::from(force).dot(DVec3::from(self.direction()))
    }
}

/// The outward normal of the free surface at `at` (a face's, or on an edge or corner the
/// normalised sum of its faces'), or why there is none.
pub fn free_face_normal(at: [f64; 3]) -> Result<[f64; 3], String> {
    let l = CUBE_SIDE_M;
    let n = outward_normal(at)
        .ok_or_else(|| format!("the press point {at:?} is not on the surface of the cube [0, {l}]^3 m"))?;
    if at[2] <= 1e-6 {
        return Err(format!("the press point {at:?} is on the clamped face z = 0"));
    }
    Ok(n.to_array())
}

/// The outward normal of the tissue's surface at `at`: the normal of the face `at` lies on, or
/// on an edge or corner the normalised sum of its faces' normals; `None` off the surface.
pub fn outward_normal(at: [f64; 3]) -> Option<DVec3> {
    let p = DVec3::from(at);
    if (0..3).any(|c| !(-ON_SURFACE_M..=CUBE_SIDE_M + ON_SURFACE_M).contains(&p[c])) {
        return None;
    }
    let mut n = DVec3::ZERO;
    for c in 0..3 {
        if p[c].abs() <= ON_SURFACE_M {
            n[c] -= 1.0;
        } else if (p[c] - CUBE_SIDE_M).abs() <= ON_SURFACE_M {
            n[c] += 1.0;
        }
    }
    (n != DVec3::ZERO).then(|| n.normalize())
}

/// The sphere's centre for a press: at depth 0 tangent to the undeformed surface at `at`
/// (centre at `at + radius n`, `n` its [`outward_normal`]; off the surface, touching `at` along
/// `direction`), moved `depth` along the unit `direction`.
pub fn centre(at: [f64; 3], direction: DVec3, radius: f64, depth: f64) -> [f64; 3] {
    let n = outward_normal(at).unwrap_or(-direction);
    (DVec3::from(at) + radius * n + depth * direction).to_array()
}

/// Where a touch of the (deformed) tissue at `hit` meets its undeformed surface: the point of the
/// nearest face (faces within half a millimetre of as near: an edge or corner), and that
/// surface's [`outward_normal`] there.
pub fn touch(hit: [f64; 3]) -> ([f64; 3], DVec3) {
    const EDGE_M: f64 = 5e-4;
    let mut at = hit.map(|v| v.clamp(0.0, CUBE_SIDE_M));
    let distance = at.map(|v| v.min(CUBE_SIDE_M - v));
    let nearest = distance.iter().copied().fold(f64::INFINITY, f64::min);
    for c in 0..3 {
        if distance[c] <= nearest + EDGE_M {
            at[c] = if at[c] < 0.5 * CUBE_SIDE_M { 0.0 } else { CUBE_SIDE_M };
        }
    }
    let n = outward_normal(at).unwrap_or(DVec3::Z);
    (at, n)
}

/// The deepest press of a probe of `radius` that its contact resolves anywhere on the top face
/// (at most [`MAX_DEPTH_OF_RADIUS`] of the radius, and at most [`MAX_CONTACT_NODES`] surface nodes
/// under it: in the middle of the face, and near an edge and a corner, where the surface grid's
/// rows are 1 mm apart), metres. The last answer is kept (the viewer asks every frame).
pub fn max_depth(radius: f64) -> f64 {
    static LAST: std::sync::Mutex<Option<(u64, f64)>> = std::sync::Mutex::new(None);
    if let Ok(last) = LAST.lock()
        && let Some((r, d)) = *last
        && r == radius.to_bits()
    {
        return d;
    }
    let d = deepest_fitting(radius);
    if let Ok(mut last) = LAST.lock() {
        *last = Some((radius.to_bits(), d));
    }
    d
}

/// Where [`max_depth`] counts the contact's nodes: offsets on the top face from its middle (half a
/// grid spacing), and every millimetre within 20 mm of an edge's middle and of a corner (where the
/// rows are 1 mm apart), metres.
fn depth_samples() -> impl Iterator<Item = [f64; 2]> {
    let (l, s) = (CUBE_SIDE_M, CUBE_SIDE_M / DEFAULT_DIVISIONS as f64);
    let middle = [[0.5 * l, 0.5 * l], [0.5 * (l + s), 0.5 * l], [0.5 * (l + s), 0.5 * (l + s)]];
    let mm = |i: u32| 0.001 * f64::from(i);
    let edge = (0..=20).map(move |i| [l - mm(i), 0.5 * l]);
    let corner = (0..=20).flat_map(move |i| (0..=i).map(move |j| [l - mm(i), l - mm(j)]));
    middle.into_iter().chain(edge).chain(corner)
}

fn deepest_fitting(radius: f64) -> f64 {
    let fits = |depth: f64| {
        depth_samples().all(|[x, y]| {
            let centre = [x, y, CUBE_SIDE_M + radius - depth];
            window_count(DEFAULT_DIVISIONS, centre, radius) <= MAX_CONTACT_NODES
        })
    };
    let deepest = MAX_DEPTH_OF_RADIUS * radius;
    if fits(deepest) {
        return deepest;
    }
    let (mut lo, mut hi) = (0.0, deepest);
    for _ in 0..30 {
        let mid = 0.5 * (lo + hi);
        if fits(mid) { lo = mid } else { hi = mid }
    }
    lo
}

/// How far `p` lies inside the cube, metres (negative outside).
fn inside_by(p: DVec3) -> f64 {
    (0..3).map(|c| p[c].min(CUBE_SIDE_M - p[c])).fold(f64::INFINITY, f64::min)
}

/// Checks a probe's radius, metres.
pub fn check_radius(radius: f64) -> Result<(), String> {
    if radius.is_nan() || radius < MIN_RADIUS_M {
        return Err(format!(
            "a probe of radius {} is smaller than the material's surface grid resolves (2 mm nodes): the radius \
             must be at least {} mm",
            crate::io::length(radius),
            MIN_RADIUS_M * 1e3
        ));
    }
    if radius > MAX_RADIUS_M {
        return Err(format!(
            "a probe of radius {} is wider than the contact can hold: the radius must be at most {} mm",
            crate::io::length(radius),
            MAX_RADIUS_M * 1e3
        ));
    }
    Ok(())
}

/// Checks one press (`direction` non-zero; `fixed(p)`: whether the tissue is held at the surface
/// point `p`). `surface`: the force comes from the material's surface compliance, whose contact
/// holds at most [`MAX_CONTACT_NODES`] nodes of the surface.
pub fn check(
    at: [f64; 3],
    direction: [f64; 3],
    radius: f64,
    depth: f64,
    surface: bool,
    fixed: &dyn Fn([f64; 3]) -> bool,
) -> Result<(), String> {
    check_radius(radius)?;
    if depth > MAX_DEPTH_OF_RADIUS * radius {
        return Err(format!(
            "depth {} is deeper than a probe of radius {} can be pressed (at most {} of its radius, {})",
            crate::io::length(depth),
            crate::io::length(radius),
            MAX_DEPTH_OF_RADIUS,
            crate::io::length(MAX_DEPTH_OF_RADIUS * radius)
        ));
    }
    let (p, dir) = (DVec3::from(at), DVec3::from(direction).normalize());
    let under = inside_by(p);
    if under > ON_SURFACE_M {
        return Err(format!(
            "the probe point {at:?} lies {} inside the tissue: a press starts on or outside its surface",
            crate::io::length(under)
        ));
    }
    // The sphere at its depth must overlap the tissue.
    let c = DVec3::from(centre(at, dir, radius, depth));
    if depth > 0.0 && c.distance(c.clamp(DVec3::ZERO, DVec3::splat(CUBE_SIDE_M))) >= radius {
        return Err(format!(
            "the press does not enter the tissue: from {at:?} along {direction:?}, {} deep, the probe stays outside",
            crate::io::length(depth)
        ));
    }
    if under > -ON_SURFACE_M && fixed(at) {
        return Err(format!(
            "the probe point {at:?} is on a clamped face: the support, not the material, would push back"
        ));
    }
    if surface {
        let nodes = window_count(DEFAULT_DIVISIONS, centre(at, dir, radius, depth), radius);
        if nodes > MAX_CONTACT_NODES {
            return Err(format!(
                "a probe of radius {} pressed {} is wider than the contact can hold: it covers {nodes} nodes \
                 of the surface, above the bound of {MAX_CONTACT_NODES}",
                crate::io::length(radius),
                crate::io::length(depth)
            ));
        }
    }
    Ok(())
}

/// How the probe touches the tissue: the one name of the contact in scripts, flags and reports.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Contact {
    /// The material's surface compliance on a fine lattice of the free surface
    /// ([`crate::sim::material_surface`]).
    #[default]
    Surface,
    /// The running model's surface nodes, projected out of the sphere.
    Nodes,
}

impl Contact {
    /// The contact that produced the simulation's last probe force.
    pub fn of(sim: &super::Simulation) -> Self {
        if sim.probe_on_surface() { Contact::Surface } else { Contact::Nodes }
    }

    /// `surface` or `nodes`.
    pub fn name(self) -> &'static str {
        match self {
            Contact::Surface => "surface",
            Contact::Nodes => "nodes",
        }
    }
}

/// One reading of the probe, all of one step: the tissue's force on the sphere, the press that
/// put it there and the contact that produced the force. The library's
/// `Simulation::probe`, the viewer's physics thread and the scripts give this one reading.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ProbeReading {
    /// The tissue's force on the sphere, newtons (x, y, z).
    pub force: [f64; 3],
    /// Its component against the push (what pushes back), newtons.
    pub force_n: f64,
    /// How far the sphere is pressed in along its direction from touching the undeformed
    /// surface, metres.
    pub depth_m: f64,
    /// The contact that produced the force.
    pub contact: Contact,
    /// Simulated time of the step, seconds.
    pub time_s: f64,
}

impl ProbeReading {
    /// The reading of `sim`'s last step under `press`.
    pub fn of(sim: &super::Simulation, press: &Press) -> Self {
        let force = sim.tool_force;
        Self { force, force_n: press.force_along(force), depth_m: press.depth, contact: Contact::of(sim), time_s: sim.time_s }
    }
}

impl std::str::FromStr for Contact {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "surface" => Ok(Contact::Surface),
            "nodes" => Ok(Contact::Nodes),
            _ => Err(format!("unknown contact \"{s}\" (surface or nodes)")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DOWN: [f64; 3] = [0.0, 0.0, -1.0];
    const TOP: [f64; 3] = [0.05, 0.05, 0.1];

    fn free(_: [f64; 3]) -> bool {
        false
    }

    fn bottom(p: [f64; 3]) -> bool {
        p[2] < 1e-9
    }

    #[test]
    fn the_viewers_press_passes_and_each_limit_is_refused_with_its_reason() {
        assert!(check(TOP, DOWN, 0.015, 0.004, true, &free).is_ok());
        assert!(check(TOP, DOWN, 0.01, 0.006, true, &free).is_ok());
        let refused = |at, dir, r, d, why: &str| {
            let e = check(at, dir, r, d, true, &bottom).expect_err(why);
            assert!(e.contains(why), "{e}");
        };
        refused(TOP, DOWN, 0.001, 0.0005, "smaller than the material's surface grid resolves");
        refused(TOP, DOWN, 0.1, 0.004, "wider than the contact can hold");
        refused(TOP, DOWN, 0.05, 0.02, "above the bound of");
        refused(TOP, DOWN, 0.015, 0.016, "deeper than");
        refused([0.05, 0.05, 0.09], DOWN, 0.015, 0.004, "inside the tissue");
        refused(TOP, [0.0, 0.0, 1.0], 0.015, 0.004, "does not enter the tissue");
        refused([0.05, 0.05, 0.12], DOWN, 0.015, 0.004, "does not enter the tissue");
        refused([0.05, 0.05, 0.0], [0.0, 0.0, 1.0], 0.015, 0.004, "clamped face");
        // Straight down at an edge: the sphere starts tangent there and enters.
        assert!(check([0.0, 0.05, 0.1], DOWN, 0.015, 0.0025, true, &free).is_ok());
        // An edge's normal is its faces' sum; the start is tangent there whatever the direction.
        let edge = outward_normal([0.1, 0.05, 0.1]).expect("on the surface");
        assert!((edge - DVec3::new(1.0, 0.0, 1.0).normalize()).length() < 1e-12);
        let tilted = DVec3::new(0.3, 0.0, -1.0).normalize();
        assert_eq!(centre(TOP, tilted, 0.015, 0.0), [0.05, 0.05, 0.115]);
        assert!(outward_normal([0.05, 0.05, 0.12]).is_none());
        // A touch of the deformed surface lands on the undeformed face nearest it.
        let (at, n) = touch([0.05, 0.05, 0.097]);
        assert_eq!((at, n), ([0.05, 0.05, 0.1], DVec3::Z));
        assert_eq!(touch([0.0998, 0.05, 0.0999]).1, DVec3::new(1.0, 0.0, 1.0).normalize());
        // The deepest press fits the contact: 3/4 of a 15 mm radius; less for 50 mm (4.85 mm: near
        // a corner the 1 mm rows put more nodes under it).
        assert!((max_depth(0.015) - 0.01125).abs() < 1e-12);
        let d = max_depth(0.05);
        assert!(d < 0.0375 && d > 0.004 && check(TOP, DOWN, 0.05, d, true, &free).is_ok(), "{d}");
        // Anywhere on the top face, near its edges and corners too (1 mm rows there).
        for r in [0.015, 0.023, 0.03, 0.05] {
            let d = max_depth(r);
            for i in 0..=20 {
                for j in 0..=i {
                    let at = [0.1 - 0.001 * f64::from(i), 0.1 - 0.001 * f64::from(j), 0.1];
                    assert!(check(at, DOWN, r, d, true, &free).is_ok(), "{r} {d} {at:?}");
                }
            }
        }
        // A side face, and the bottom where nothing holds it, are pressed.
        assert!(check([0.0, 0.05, 0.05], [1.0, 0.0, 0.0], 0.015, 0.004, true, &bottom).is_ok());
        assert!(check([0.05, 0.05, 0.0], [0.0, 0.0, 1.0], 0.015, 0.004, true, &free).is_ok());
    }
}
