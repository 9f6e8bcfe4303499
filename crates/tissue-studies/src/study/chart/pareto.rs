//! The chart's Pareto fronts and where a series of points crosses an error threshold.

use super::point::ChartPoint;

/// Marks the Pareto fronts of (cost per simulated second, average static error) and (cost per
/// simulated second, dynamic error) per object; a point without a dynamic score is on no
/// dynamic front.
pub fn mark_pareto(points: &mut [ChartPoint]) {
    let snapshot = points.to_vec();
    let dominated = |p: &ChartPoint, err: fn(&ChartPoint) -> f64| {
        snapshot.iter().any(|q| {
            q.object == p.object
                && err(q).is_finite()
                && q.cost_per_sim_s <= p.cost_per_sim_s
                && err(q) <= err(p)
                && (q.cost_per_sim_s < p.cost_per_sim_s || err(q) < err(p))
        })
    };
    for p in points.iter_mut() {
        p.pareto = !dominated(p, |q| q.avg_err_pct);
        p.pareto_dynamic = p.dyn_err_pct.is_finite() && !dominated(p, |q| q.dyn_err_pct);
    }
}

/// Where a series of points (ascending steps) crosses `threshold` percent of `err`: the step by
/// log-log interpolation between the last step below and the first above, or why not.
pub fn crossing(points: &[&ChartPoint], err: fn(&ChartPoint) -> f64, threshold: f64) -> String {
    let mut sorted: Vec<&&ChartPoint> = points.iter().filter(|p| err(p).is_finite()).collect();
    sorted.sort_by(|a, b| a.dt_s.total_cmp(&b.dt_s));
    let Some(first) = sorted.first() else { return "not measured".into() };
    if err(first) > threshold {
        return format!("above {threshold} % already at {} ms ({:.2} %)", fmt_ms(first.dt_s), err(first));
    }
    for w in sorted.windows(2) {
        let (a, b) = (w[0], w[1]);
        if err(a) <= threshold && err(b) > threshold {
            let t = (threshold.ln() - err(a).max(1e-12).ln()) / (err(b).ln() - err(a).max(1e-12).ln());
            let dt = (a.dt_s.ln() + t * (b.dt_s.ln() - a.dt_s.ln())).exp();
            return format!(
                "crosses {threshold} % at about {} ms (between {} ms: {:.2} % and {} ms: {:.2} %)",
                fmt_ms(dt),
                fmt_ms(a.dt_s),
                err(a),
                fmt_ms(b.dt_s),
                err(b)
            );
        }
    }
    let last = sorted.last().map_or(first, |l| l);
    format!("below {threshold} % up to {} ms ({:.2} %)", fmt_ms(last.dt_s), err(last))
}

fn fmt_ms(s: f64) -> String {
    format!("{:.3}", s * 1e3)
}
