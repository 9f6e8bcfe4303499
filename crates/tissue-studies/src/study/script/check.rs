//! The checks of a script, all made before any work: its step, its bounds, and every action's
//! node, points, sizes and samples.

use glam::DVec3;

use super::{
    Action, MAX_ACTION_S, MAX_ACTIONS, MAX_RECORDED, MAX_SAMPLES, MAX_SCRIPT_NODES, MAX_TOTAL_STEPS, PathKey, Script,
    steps_for,
};
use crate::mechanics::grid::Grid;

fn check(name: &str, v: f64, positive: bool) -> anyhow::Result<()> {
    if !v.is_finite() || v < 0.0 || (positive && v == 0.0) {
        anyhow::bail!(
            "{name} must be a {} finite number, got {}",
            if positive { "positive" } else { "non-negative" },
            crate::io::num(v)
        );
    }
    Ok(())
}

/// A point must lie within one cube side of the cube: a coordinate typed in millimetres (or
/// any runaway value) is refused by name rather than flinging the tissue.
fn check_point(what: &str, p: &[f64; 3]) -> anyhow::Result<()> {
    let l = crate::mechanics::grid::CUBE_SIDE_M;
    for (c, v) in p.iter().enumerate() {
        if !v.is_finite() {
            anyhow::bail!("{what}[{c}] is not finite");
        }
        if !(-l..=2.0 * l).contains(v) {
            anyhow::bail!(
                "{what} = {p:?} lies outside the cube's neighbourhood: coordinates are metres, the cube spans \
                 0 to {l} m, and points must lie within {l} m of it"
            );
        }
    }
    Ok(())
}

/// Probe samples of one probe action.
pub const MAX_SAMPLES_PER_PROBE: usize = 10_000;

/// Every check of a script that does not depend on the step, made before any work: the step, the
/// bounds on actions and recorded events, and each action's node, points, sizes and samples.
pub(super) fn check_script(script: &Script, object: &str) -> anyhow::Result<()> {
    crate::sim::check_dt(script.dt).map_err(|e| anyhow::anyhow!("script: dt = {e}"))?;
    if !(4..=MAX_SCRIPT_NODES).contains(&script.nodes) {
        anyhow::bail!("script: nodes = {} is out of range (4 to {MAX_SCRIPT_NODES} nodes per axis)", script.nodes);
    }
    let grid = Grid::new(script.nodes)?;
    if let Some(i) = script.integrator {
        script.model.check_integrator(i).map_err(|e| anyhow::anyhow!("script: {e}"))?;
    }
    if script.actions.len() > MAX_ACTIONS {
        anyhow::bail!("script: {} actions, above the bound of {MAX_ACTIONS}", script.actions.len());
    }
    // Where the tissue is held, for the presses' check: the model's node nearest a point.
    let fixed = super::clamp_case(&grid, object, &script.clamp)?.map(|c| c.fixed_nodes());
    let held = |p: [f64; 3]| {
        let (h, top) = (grid.h(), (grid.n() - 1) as f64);
        let at = |v: f64| (v / h).round().clamp(0.0, top) as usize;
        fixed.as_ref().is_some_and(|f| f[grid.node(at(p[0]), at(p[1]), at(p[2]))])
    };
    let surface = script.contact == super::Contact::Surface;
    let last = script.actions.len().saturating_sub(1);
    let recorded = script.actions.iter().enumerate().filter(|&(i, a)| a.record() || i == last).count();
    if recorded > MAX_RECORDED {
        anyhow::bail!("script: {recorded} actions record positions (with the last), above the bound of {MAX_RECORDED}");
    }
    let mut total_samples = 0usize;
    for (i, a) in script.actions.iter().enumerate() {
        check_action(a, &grid, surface, &held).map_err(|e| anyhow::anyhow!("script: action {i}: {e}"))?;
        match a {
            Action::Probe { samples, .. } => total_samples += samples,
            Action::ProbePath { sample_hz, .. } => {
                // At most one sample per step and per sample time.
                total_samples += (a.duration_s() * sample_hz).floor() as usize + 1;
            }
            _ => {}
        }
    }
    if total_samples > MAX_SAMPLES {
        anyhow::bail!("script: {total_samples} probe samples in all, above the bound of {MAX_SAMPLES}");
    }
    if let Some(r) = &script.recorded {
        check_recorded(&r.force_path, &script.actions, script.dt)?;
    }
    Ok(())
}

/// The recorded samples of a recording agree with themselves and with their actions: each names
/// a probe path, its numbers are finite, and its `force_n` is its force along the push (to
/// 1e-6 of the force), and no two are of one step of one action (`dt`); the error names the
/// sample (0-based, as in `force_path`).
fn check_recorded(samples: &[super::PathSample], actions: &[Action], dt: f64) -> anyhow::Result<()> {
    if samples.len() > MAX_SAMPLES {
        anyhow::bail!("script: {} recorded samples, above the bound of {MAX_SAMPLES}", samples.len());
    }
    let mut steps = std::collections::HashMap::with_capacity(samples.len());
    for (k, s) in samples.iter().enumerate() {
        let say = |why: String| anyhow::anyhow!("script: recorded sample {k}: {why}");
        let Some(Action::ProbePath { direction, .. }) = actions.get(s.action) else {
            return Err(say(format!("action {} is not a probe path of the script", s.action)));
        };
        let numbers = [s.t, s.depth_m, s.force_n].into_iter().chain(s.at).chain(s.force);
        if !numbers.into_iter().all(f64::is_finite) {
            return Err(say("its time, point, depth and forces must be finite numbers".into()));
        }
        if let Some(j) = steps.insert((s.action, (s.t / dt).round() as i64), k) {
            return Err(say(format!("it is of the same step of action {} as recorded sample {j}", s.action)));
        }
        let d = glam::DVec3::from(*direction);
        let along = -glam::DVec3::from(s.force).dot(d / d.length());
        let scale = glam::DVec3::from(s.force).length();
        if (along - s.force_n).abs() > 1e-6 * scale + 1e-12 {
            return Err(say(format!(
                "force_n {} N is not its force along the push ({} N)",
                crate::io::num(s.force_n),
                crate::io::num(along)
            )));
        }
    }
    Ok(())
}

/// A probe's radius and depth.
fn check_sizes(radius: f64, depth: f64) -> anyhow::Result<()> {
    let l = crate::mechanics::grid::CUBE_SIDE_M;
    check("radius", radius, true)?;
    check("depth", depth, false)?;
    if radius > l || depth > l {
        anyhow::bail!(
            "probe radius {} m and depth {} m must each be at most the cube's side ({l} m); sizes are metres",
            crate::io::num(radius),
            crate::io::num(depth)
        );
    }
    Ok(())
}

/// A probe's direction.
fn check_direction(direction: &[f64; 3]) -> anyhow::Result<()> {
    let len = DVec3::from(*direction).length();
    if !(len.is_finite() && len > 0.0) {
        anyhow::bail!("probe needs a finite, non-zero direction");
    }
    Ok(())
}

/// Largest sample rate of a probe path, Hz.
pub const MAX_SAMPLE_HZ: f64 = 1e6;
/// Keys of one probe path.
pub const MAX_PATH_KEYS: usize = 10_000;

/// A probe path's keys and sample rate.
fn check_path(radius: f64, keys: &[PathKey], sample_hz: f64) -> anyhow::Result<()> {
    if keys.is_empty() || keys.len() > MAX_PATH_KEYS {
        anyhow::bail!("a probe path needs 1 to {MAX_PATH_KEYS} keys, got {}", keys.len());
    }
    let mut last = f64::NEG_INFINITY;
    for (k, key) in keys.iter().enumerate() {
        check(&format!("keys[{k}].t"), key.t, false)?;
        if key.t <= last {
            anyhow::bail!("keys[{k}].t = {} s does not increase (the key before is at {} s)", key.t, last);
        }
        last = key.t;
        check_point(&format!("keys[{k}].at"), &key.at)?;
        check_sizes(radius, key.depth).map_err(|e| anyhow::anyhow!("keys[{k}]: {e}"))?;
    }
    if !(sample_hz.is_finite() && sample_hz > 0.0 && sample_hz <= MAX_SAMPLE_HZ) {
        anyhow::bail!(
            "sample_hz = {} is out of range (above 0, at most {MAX_SAMPLE_HZ} Hz)",
            crate::io::num(sample_hz)
        );
    }
    Ok(())
}

/// One action's node, points, sizes, duration and samples; a press also by the limits of its
/// contact ([`crate::sim::press`]; `surface`: on the material's surface compliance, `held(p)`:
/// the tissue is held at `p`).
fn check_action(action: &Action, grid: &Grid, surface: bool, held: &dyn Fn([f64; 3]) -> bool) -> anyhow::Result<()> {
    match action {
        Action::Drag { node, to, .. } => {
            let nodes = grid.num_nodes();
            if *node >= nodes {
                anyhow::bail!("node {node} does not exist (0..{nodes} on the {}^3 grid)", grid.n());
            }
            check_point("drag target \"to\"", to)
        }
        Action::Probe { at, direction, radius, depth, samples, .. } => {
            check_sizes(*radius, *depth)?;
            check_point("probe point \"at\"", at)?;
            check_direction(direction)?;
            if !(1..=MAX_SAMPLES_PER_PROBE).contains(samples) {
                anyhow::bail!("samples = {samples} is out of range (1 to {MAX_SAMPLES_PER_PROBE} per probe)");
            }
            crate::sim::press::check(*at, *direction, *radius, *depth, surface, held).map_err(anyhow::Error::msg)
        }
        Action::ProbePath { radius, direction, keys, sample_hz, .. } => {
            check_sizes(*radius, 0.0)?;
            check_direction(direction)?;
            check_path(*radius, keys, *sample_hz)?;
            for (k, key) in keys.iter().enumerate() {
                crate::sim::press::check(key.at, *direction, *radius, key.depth, surface, held)
                    .map_err(|e| anyhow::anyhow!("keys[{k}]: {e}"))?;
            }
            Ok(())
        }
        Action::Release { .. } | Action::Wait { .. } => Ok(()),
    }?;
    check("duration_s", action.duration_s(), false)?;
    if action.duration_s() > MAX_ACTION_S {
        anyhow::bail!("duration_s = {} s is too long (at most {MAX_ACTION_S} s)", crate::io::num(action.duration_s()));
    }
    Ok(())
}

/// The steps of the whole script at the step `dt` the policy chose, within [`MAX_TOTAL_STEPS`].
pub(super) fn check_steps(script: &Script, dt: f64) -> anyhow::Result<()> {
    let mut total_steps = 0u64;
    for a in &script.actions {
        let n = steps_for(a.duration_s(), dt);
        total_steps += match a {
            Action::Release { .. } => 0,
            Action::Wait { .. } => n,
            _ => n.max(1),
        };
    }
    if total_steps > MAX_TOTAL_STEPS {
        anyhow::bail!(
            "script: {total_steps} steps in all (at dt = {} s), above the bound of {MAX_TOTAL_STEPS} steps per script",
            crate::io::num(dt)
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::super::Script;

    /// A probe action's keys near the bounds, as a script's JSON.
    fn probe_script(at: &[f64], radius: f64, depth: f64) -> String {
        let at = at.iter().map(|c| format!("{c:?}")).collect::<Vec<_>>().join(",");
        format!(
            r#"{{"object":"A","model":"axis","contact":"nodes","actions":[{{"probe":{{"at":[{at}],"direction":[0,0,-1],
               "radius":{radius:?},"depth":{depth:?},"duration_s":0.01}}}}]}}"#
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(128))]

        /// Any bytes read as a script give a checked script or a one-line error, never a panic.
        #[test]
        fn any_bytes_are_a_script_or_one_line(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
            let text = String::from_utf8_lossy(&bytes);
            let read = crate::io::shape::from_json::<Script>(&text).map_err(anyhow::Error::msg);
            if let Err(e) = read.and_then(|s| super::check_script(&s, "A")) {
                prop_assert!(!format!("{e:#}").contains('\n'), "{:#}", e);
            }
        }

        /// A probe near the bounds (any number of coordinates, sizes around the limits) is
        /// accepted as written or refused in one line; a point of other than three numbers never.
        #[test]
        fn a_probe_is_read_as_written_or_refused(
            at in proptest::collection::vec(-0.01f64..0.11, 0..5),
            radius in 0.0f64..0.06,
            depth in -0.001f64..0.05,
        ) {
            let read = crate::io::shape::from_json::<Script>(&probe_script(&at, radius, depth));
            match read.map_err(anyhow::Error::msg).and_then(|s| super::check_script(&s, "A").map(|()| s)) {
                Ok(s) => {
                    prop_assert_eq!(at.len(), 3);
                    let super::Action::Probe { at: got, radius: r, depth: d, .. } = &s.actions[0] else {
                        return Err(TestCaseError::fail("not a probe"));
                    };
                    prop_assert_eq!(got.to_vec(), at);
                    prop_assert_eq!((*r, *d), (radius, depth));
                }
                Err(e) => prop_assert!(!format!("{e:#}").contains('\n'), "{:#}", e),
            }
        }
    }
}
