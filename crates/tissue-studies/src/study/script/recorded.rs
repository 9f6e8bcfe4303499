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
}

/// Compares `recorded` samples with `replayed` ones, matched by action and step (`dt`).
pub(super) fn compare(recorded: &[PathSample], replayed: &[PathSample], dt: f64) -> Replay {
    let key = |s: &PathSample| (s.action, (s.t / dt).round() as i64);
    let replay: std::collections::HashMap<_, _> = replayed.iter().map(|s| (key(s), s)).collect();
    let (mut diff, mut norm, mut matched) = (0.0, 0.0, 0);
    for r in recorded {
        let Some(p) = replay.get(&key(r)) else { continue };
        matched += 1;
        for c in 0..3 {
            diff += (p.force[c] - r.force[c]).powi(2);
            norm += r.force[c].powi(2);
        }
    }
    let relative_l2 = if norm > 0.0 {
        (diff / norm).sqrt()
    } else if diff > 0.0 {
        1.0
    } else {
        0.0
    };
    Replay { recorded: recorded.len(), matched, relative_l2 }
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
    }
}
