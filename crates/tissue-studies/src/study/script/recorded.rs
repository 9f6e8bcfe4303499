//! A recording of the viewer (`view --record`) replayed: the force samples the viewer showed,
//! kept in the script, beside the ones the replay computes.

use serde::{Deserialize, Serialize};

use super::PathSample;

/// What the viewer saw while it recorded.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Recorded {
    /// The probe's force as the viewer computed it, in the `force_path` sample format.
    pub force_path: Vec<PathSample>,
    /// What the script does not carry of what was done, if anything (edited parameters, a part
    /// before a setting changed).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
}

/// The replay's probe forces against the recorded ones.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Replay {
    /// Recorded samples.
    pub recorded: usize,
    /// Recorded samples the replay has too (the same action, the same step).
    pub matched: usize,
    /// `|f_replay - f_recorded| / |f_recorded|` over the matched samples' force vectors (L2 over
    /// all of them); 0 where both are zero, 1 where only the recording is.
    pub relative_l2: f64,
    /// The same over their components along the push (`force_n`).
    pub force_n_relative_l2: f64,
    /// Matched samples that differ in any recorded quantity (force, `force_n`, depth, point,
    /// contact) beyond round-off.
    pub mismatched: usize,
    /// The first of them (at most `MAX_LISTED`), each as `sample K (action A, t = T s): what differs`.
    pub mismatches: Vec<String>,
}

/// Mismatched samples listed, at most.
pub const MAX_LISTED: usize = 20;

/// A relative L2 of `diff` over `norm` (sums of squares): 0 where both are zero, 1 where only the
/// difference is.
fn relative(diff: f64, norm: f64) -> f64 {
    if norm > 0.0 {
        (diff / norm).sqrt()
    } else if diff > 0.0 {
        1.0
    } else {
        0.0
    }
}

/// What differs between a recorded sample `r` and its replay `p` beyond round-off (a replay is
/// deterministic: the same build gives the same bits), in words; empty where nothing does.
fn differences(r: &PathSample, p: &PathSample) -> Vec<String> {
    let close = |a: f64, b: f64, scale: f64| (a - b).abs() <= 1e-6 * scale + 1e-12;
    let scale = glam::DVec3::from(r.force).length().max(glam::DVec3::from(p.force).length());
    let mut out = Vec::new();
    if !(0..3).all(|c| close(r.force[c], p.force[c], scale)) {
        out.push(format!("force {:?} N recorded, {:?} N replayed", r.force, p.force));
    }
    if !close(r.force_n, p.force_n, scale) {
        out.push(format!("force_n {} N recorded, {} N replayed", crate::io::num(r.force_n), crate::io::num(p.force_n)));
    }
    if !close(r.depth_m, p.depth_m, 1e-3) {
        out.push(format!("depth {} recorded, {} replayed", crate::io::length(r.depth_m), crate::io::length(p.depth_m)));
    }
    if !(0..3).all(|c| close(r.at[c], p.at[c], 1e-3)) {
        out.push(format!("point {:?} m recorded, {:?} m replayed", r.at, p.at));
    }
    if r.contact != p.contact {
        out.push(format!("contact {} recorded, {} replayed", r.contact.name(), p.contact.name()));
    }
    out
}

/// Compares `recorded` samples with `replayed` ones, matched by action and step (`dt`): every
/// recorded quantity, each mismatch named by its sample.
pub(super) fn compare(recorded: &[PathSample], replayed: &[PathSample], dt: f64) -> Replay {
    let key = |s: &PathSample| (s.action, (s.t / dt).round() as i64);
    let replay: std::collections::HashMap<_, _> = replayed.iter().map(|s| (key(s), s)).collect();
    let (mut diff, mut norm, mut matched) = (0.0, 0.0, 0);
    let (mut diff_n, mut norm_n) = (0.0, 0.0);
    let (mut mismatched, mut mismatches) = (0, Vec::new());
    for (k, r) in recorded.iter().enumerate() {
        let Some(p) = replay.get(&key(r)) else { continue };
        matched += 1;
        for c in 0..3 {
            diff += (p.force[c] - r.force[c]).powi(2);
            norm += r.force[c].powi(2);
        }
        diff_n += (p.force_n - r.force_n).powi(2);
        norm_n += r.force_n.powi(2);
        let what = differences(r, p);
        if !what.is_empty() {
            mismatched += 1;
            if mismatches.len() < MAX_LISTED {
                mismatches.push(format!(
                    "sample {k} (action {}, t = {} s): {}",
                    r.action,
                    crate::io::num(r.t),
                    what.join("; ")
                ));
            }
        }
    }
    Replay {
        recorded: recorded.len(),
        matched,
        relative_l2: relative(diff, norm),
        force_n_relative_l2: relative(diff_n, norm_n),
        mismatched,
        mismatches,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::script::Contact;

    fn sample(action: usize, t: f64, fz: f64) -> PathSample {
        PathSample {
            action,
            t,
            at: [0.05, 0.05, 0.1],
            depth_m: 0.004,
            force_n: fz,
            force: [0.0, 0.0, fz],
            contact: Contact::Surface,
        }
    }

    #[test]
    fn samples_are_matched_by_action_and_step() {
        let rec = [sample(1, 0.01, 2.0), sample(1, 0.02, 4.0), sample(3, 0.01, 1.0)];
        let rep = [sample(1, 0.010_000_000_1, 2.0), sample(1, 0.02, 4.4), sample(2, 0.01, 9.0)];
        let r = compare(&rec, &rep, 1e-4);
        assert_eq!((r.recorded, r.matched), (3, 2));
        assert!((r.relative_l2 - 0.4 / 20f64.sqrt()).abs() < 1e-12, "{r:?}");
        assert_eq!(r.mismatched, 1, "{r:?}");
        assert!(r.mismatches[0].starts_with("sample 1 (action 1, t = 0.02 s): force "), "{r:?}");
    }

    #[test]
    fn every_recorded_quantity_is_compared() {
        let rec = [sample(1, 0.01, 2.0), sample(1, 0.02, 4.0), sample(1, 0.03, 4.0)];
        let mut rep = rec.clone();
        rep[0].force_n = 6.0;
        rep[1].contact = Contact::Nodes;
        rep[2].depth_m = 0.003;
        let r = compare(&rec, &rep, 1e-4);
        assert_eq!((r.matched, r.mismatched), (3, 3), "{r:?}");
        assert_eq!(r.relative_l2, 0.0);
        assert!(r.force_n_relative_l2 > 0.5, "{r:?}");
        assert!(r.mismatches[0].contains("force_n 2 N recorded, 6 N replayed"), "{r:?}");
        assert!(r.mismatches[1].contains("contact surface recorded, nodes replayed"), "{r:?}");
        assert!(r.mismatches[2].contains("depth 4 mm recorded, 3 mm replayed"), "{r:?}");
        assert_eq!(compare(&rec, &rec, 1e-4).mismatched, 0);
    }
}
