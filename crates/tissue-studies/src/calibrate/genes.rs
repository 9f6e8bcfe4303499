//! The chromosome: which MSM parameters are genes, and the search box they live in.
//!
//! Genes follow the paper: `(k1, k2, k3, d)` for an orthotropic object and `(k1, k2, d)` for a
//! transversely isotropic one (`k3 = k2`); the shear model inserts one diagonal stiffness per plane
//! before `d`: `c12, c13, c23` (orthotropic) or `c12, c23` (transversely isotropic, `c13 = c12`).
//! The hex model adds the body-diagonal stiffness `b` after them.
//!
//! Default bounds come from the material and the grid. A chain of springs along axis `a` under
//! uniaxial stress `sigma` carries `sigma L^2 / n^2` and stretches `h sigma / E_a` per spring, so
//! the stiffness that matches the material's uniaxial compliance is `k_a* = E_a L^2 / (n^2 h)`;
//! likewise `c_ab* = G_ab L^2 / (n^2 h)` sets the scale of a diagonal family. The box is
//! `[k*/2, 2 k*]` for the axis lattice's springs and `[c*/100, 2 c*]` for diagonals (their best
//! value can be far below the scale). A wider box costs the paper's budget (50 x 100) its
//! convergence: see the bounds study in the `reproduce` report. In the shear and hex lattices
//! the diagonals carry part of the axial load, so their axis springs get `[k*/100, 2 k*]`, and
//! the shear lattice's diagonals `[c*/100, 4 c*]`: the polish stays in the box
//! ([`super::polish::polish_within`]), and these boxes hold the optima measured without one (the
//! shear lattice of A at 5^3: `k1 = 0.067 k*`, `c13 = 2.45 c*` on the paper's cases; at 8^3
//! `k1 = 0.078 k*` on the touch cases). For damping it is `[0, 10 d_c]`, with
//! `d_c = 2 m omega_1` the critical damping of the slowest axial mode of a spring chain at `k*`
//! (clamped at one end, `n - 1` moving masses: `omega_1 = 2 sqrt(k*/m) sin(pi / (2 (2n - 1)))`),
//! taken over the three axes.

use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmParams, Topology};

/// Names and bounds of the genes of one calibration.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct GeneSpace {
    /// Gene names, in chromosome order: `k1`, `k2`, `k3` (orthotropic only), then for the richer
    /// lattices `c12`, `c13` (orthotropic only), `c23` and `b` (hex only), and `d` last.
    pub names: Vec<String>,
    /// Lower bounds.
    pub lo: Vec<f64>,
    /// Upper bounds.
    pub hi: Vec<f64>,
    /// Whether `k3` (and `c13`) are tied to `k2` (and `c12`).
    pub transversely_isotropic: bool,
}

impl GeneSpace {
    /// The default genes and bounds for `material` on `grid` (see the module docs).
    pub fn new(material: &Material, grid: &Grid, topology: Topology) -> Self {
        let ti = material.is_transversely_isotropic();
        let c = &material.constants;
        let n = grid.n() as f64;
        let scale = CUBE_SIDE_M * CUBE_SIDE_M / (n * n * grid.h());
        let k_star = [c.e1, c.e2, c.e3].map(|e| e * scale);
        let c_star = [c.g12, c.g13, c.g23].map(|g| g * scale);
        let mass = material.density * CUBE_SIDE_M.powi(3) / grid.num_nodes() as f64;
        let d_crit = k_star
            .iter()
            .map(|k| {
                let omega = 2.0 * (k / mass).sqrt() * (std::f64::consts::PI / (2.0 * (2.0 * n - 1.0))).sin();
                2.0 * mass * omega
            })
            .fold(0.0, f64::max);
        let mut names = Vec::new();
        let mut lo = Vec::new();
        let mut hi = Vec::new();
        let mut push = |name: &str, l: f64, h: f64| {
            names.push(name.to_owned());
            lo.push(l);
            hi.push(h);
        };
        let axes: &[usize] = if ti { &[0, 1] } else { &[0, 1, 2] };
        // In the shear and hex models the diagonals carry part of the axial load, so their axis
        // springs can be far softer than the chain scale (see the module docs).
        let k_lo = if topology == Topology::Axis { 2.0 } else { 100.0 };
        let c_hi = if topology == Topology::Shear { 4.0 } else { 2.0 };
        for &a in axes {
            push(["k1", "k2", "k3"][a], k_star[a] / k_lo, k_star[a] * 2.0);
        }
        if topology != Topology::Axis {
            let planes: &[usize] = if ti { &[0, 2] } else { &[0, 1, 2] };
            for &p in planes {
                push(["c12", "c13", "c23"][p], c_star[p] / 100.0, c_star[p] * c_hi);
            }
        }
        if topology == Topology::Hex {
            let lo = k_star.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = k_star.iter().copied().fold(0.0, f64::max);
            push("b", lo / 100.0, 2.0 * hi);
        }
        push("d", 0.0, 10.0 * d_crit);
        Self { names, lo, hi, transversely_isotropic: ti }
    }

    /// Number of genes.
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Always false: a chromosome has at least `k1`, `k2` and `d`.
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    /// Overrides the bounds of a gene by name; checks `0 <= lo < hi`, finite.
    pub fn set_bound(&mut self, name: &str, lo: f64, hi: f64) -> Result<(), String> {
        let i = self
            .names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| format!("no gene {name:?}; the genes are {}", self.names.join(", ")))?;
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
            return Err(format!(
                "bounds of {name} must satisfy 0 <= lo < hi, got {}:{}",
                crate::io::num(lo),
                crate::io::num(hi)
            ));
        }
        if name.starts_with('k') && lo <= 0.0 {
            return Err(format!("the lower bound of {name} must be positive (an axis spring needs stiffness)"));
        }
        let (min, max) = crate::mechanics::msm::model::STIFFNESS_RANGE;
        if name == "d" {
            if hi > max {
                return Err(format!(
                    "bounds of d must lie within 0 to {max:e} N s/m, got {}:{}",
                    crate::io::num(lo),
                    crate::io::num(hi)
                ));
            }
        } else if (lo != 0.0 && lo < min) || hi > max {
            return Err(format!(
                "bounds of {name} must lie within {min:e} to {max:e} N/m (or start at 0), got {}:{}",
                crate::io::num(lo),
                crate::io::num(hi)
            ));
        }
        self.lo[i] = lo;
        self.hi[i] = hi;
        Ok(())
    }

    /// The value of gene `name` in `params`, if it has one.
    pub fn value(params: &MsmParams, name: &str) -> Option<f64> {
        match name {
            "k1" => Some(params.k1),
            "k2" => Some(params.k2),
            "k3" => Some(params.k3),
            "d" => Some(params.d),
            "c12" => params.c12,
            "c13" => params.c13,
            "c23" => params.c23,
            "b" => params.b,
            _ => None,
        }
    }

    /// The genes of `params` on a bound of the box (within 0.1 % of its width): each name, its
    /// value and `"lower"` or `"upper"`. A gene there may want a wider box.
    pub fn on_bounds(&self, params: &MsmParams) -> Vec<(String, f64, &'static str)> {
        self.names
            .iter()
            .enumerate()
            .filter_map(|(i, name)| {
                let v = Self::value(params, name)?;
                let tol = 1e-3 * (self.hi[i] - self.lo[i]).abs();
                if (v - self.lo[i]).abs() <= tol {
                    Some((name.clone(), v, "lower"))
                } else if (v - self.hi[i]).abs() <= tol {
                    Some((name.clone(), v, "upper"))
                } else {
                    None
                }
            })
            .collect()
    }

    /// The MSM parameters a chromosome stands for.
    pub fn params(&self, genes: &[f64]) -> MsmParams {
        let get = |name: &str| self.names.iter().position(|n| n == name).map(|i| genes[i]);
        let k2 = get("k2").unwrap_or(0.0);
        let mut p = MsmParams::axis(get("k1").unwrap_or(0.0), k2, get("k3").unwrap_or(k2), get("d").unwrap_or(0.0));
        if let Some(c12) = get("c12") {
            p.c12 = Some(c12);
            p.c13 = Some(get("c13").unwrap_or(c12));
            p.c23 = get("c23");
        }
        p.b = get("b");
        p
    }
}
