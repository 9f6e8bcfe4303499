//! `tissue_sim._native`: the core's face for Python (the package `tissue_sim` wraps it: keyword
//! arguments, numpy arrays, dicts).

use std::sync::atomic::AtomicBool;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use tissue_core::mechanics::grid::Grid;
use tissue_core::prelude as core;

/// A name (`hex`, `symplectic`, ...) read as the scripts read it.
fn named<T: serde::de::DeserializeOwned>(what: &str, name: &str) -> PyResult<T> {
    serde_json::from_value(serde_json::Value::String(name.to_owned()))
        .map_err(|e| PyValueError::new_err(format!("{what} \"{name}\": {e}")))
}

/// The core's error as Python's: bad input a `ValueError`, a failed computation a `RuntimeError`.
fn py_err(e: core::Error) -> PyErr {
    match e {
        core::Error::Compute(_) | core::Error::BlowUp(_) => PyRuntimeError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// A tissue's material.
#[pyclass(module = "tissue_sim", frozen)]
#[derive(Clone)]
struct Material(core::Material);

#[pymethods]
impl Material {
    /// One of the paper's objects, "A" or "B".
    #[staticmethod]
    fn object(name: &str) -> PyResult<Self> {
        let object: core::Object = name.parse().map_err(|e| PyValueError::new_err(format!("{e}")))?;
        Ok(Self(core::Material::object(object)))
    }

    /// A material file (TOML, or JSON where the name ends in .json).
    #[staticmethod]
    fn from_file(path: std::path::PathBuf) -> PyResult<Self> {
        core::Material::from_file(&path).map(Self).map_err(|e| PyValueError::new_err(e.to_string()))
    }

    /// Its name.
    #[getter]
    fn name(&self) -> String {
        self.0.name().to_owned()
    }

    fn __repr__(&self) -> String {
        format!("Material({:?})", self.0.name())
    }
}

/// A press of the probe.
#[pyclass(module = "tissue_sim", frozen)]
#[derive(Clone)]
struct Press(core::Press);

#[pymethods]
impl Press {
    /// A sphere of `radius` pressed `depth` along the inward normal at `at` (metres).
    #[staticmethod]
    #[pyo3(signature = (at, radius, depth = 0.0))]
    fn normal(at: [f64; 3], radius: f64, depth: f64) -> Self {
        Self(core::Press::normal(at, radius).depth(depth))
    }

    /// A sphere of `radius` touching `at` and pressed `depth` along `direction`.
    #[staticmethod]
    #[pyo3(signature = (at, direction, radius, depth = 0.0))]
    fn along(at: [f64; 3], direction: [f64; 3], radius: f64, depth: f64) -> Self {
        Self(core::Press::along(at, direction, radius).depth(depth))
    }

    fn __repr__(&self) -> String {
        let p = &self.0;
        format!("Press(at={:?}, radius={}, depth={}, direction={:?})", p.at, p.radius, p.depth, p.direction())
    }
}

/// One reading of the probe.
#[pyclass(module = "tissue_sim", frozen, get_all)]
struct ProbeReading {
    /// The tissue's force on the sphere, N.
    force: (f64, f64, f64),
    /// Its component against the push, N.
    force_n: f64,
    /// The press's depth, m.
    depth_m: f64,
    /// "surface" or "nodes".
    contact: String,
    /// Simulated time, s.
    time_s: f64,
}

#[pymethods]
impl ProbeReading {
    fn __repr__(&self) -> String {
        format!("ProbeReading(force_n={:.4}, depth_m={}, contact={:?})", self.force_n, self.depth_m, self.contact)
    }
}

/// The running tissue.
#[pyclass(module = "tissue_sim", unsendable)]
struct Simulation(core::Simulation);

#[pymethods]
impl Simulation {
    #[new]
    #[pyo3(signature = (material, model = None, nodes = None, integrator = None, dt = None, damping_ratio = None, contact = None))]
    fn new(
        material: &Material,
        model: Option<&str>,
        nodes: Option<usize>,
        integrator: Option<&str>,
        dt: Option<f64>,
        damping_ratio: Option<f64>,
        contact: Option<&str>,
    ) -> PyResult<Self> {
        let mut b = core::Simulation::builder(&material.0);
        if let Some(m) = model {
            b = b.model(named("model", m)?);
        }
        if let Some(n) = nodes {
            b = b.nodes(n);
        }
        if let Some(i) = integrator {
            b = b.integrator(named("integrator", i)?);
        }
        if let Some(dt) = dt {
            b = b.dt(dt);
        }
        if let Some(z) = damping_ratio {
            b = b.damping_ratio(z);
        }
        if let Some(c) = contact {
            b = b.contact(c.parse().map_err(PyValueError::new_err)?);
        }
        // The surface compliance may take a minute the first time: let other threads run.
        let built = b.build().map_err(py_err)?;
        Ok(Self(built))
    }

    fn press(&mut self, press: &Press) {
        self.0.press(press.0);
    }

    fn drag(&mut self, node: usize, target: [f64; 3]) {
        self.0.drag(node, target);
    }

    fn release(&mut self) {
        self.0.release();
    }

    fn step(&mut self) -> PyResult<()> {
        self.0.step().map_err(py_err)
    }

    fn run_for(&mut self, seconds: f64) -> PyResult<()> {
        self.0.run_for(seconds).map_err(py_err)
    }

    fn probe(&self) -> Option<ProbeReading> {
        self.0.probe().map(|r| ProbeReading {
            force: (r.force[0], r.force[1], r.force[2]),
            force_n: r.force_n,
            depth_m: r.depth_m,
            contact: r.contact.name().to_owned(),
            time_s: r.time_s,
        })
    }

    /// Node positions, flat: x, y, z of node 0, then node 1, ...
    fn positions_flat(&mut self) -> Vec<f64> {
        self.0.positions().iter().flatten().copied().collect()
    }

    fn tool_force(&self) -> (f64, f64, f64) {
        let f = self.0.tool_force();
        (f[0], f[1], f[2])
    }

    #[getter]
    fn time_s(&self) -> f64 {
        self.0.time_s()
    }

    #[getter]
    fn dt(&self) -> f64 {
        self.0.dt()
    }

    #[getter]
    fn nodes(&self) -> usize {
        self.0.nodes()
    }
}

/// The paper's GA+SA (or GA, SA, the stiffness fit) as `tissue-sim calibrate` runs it; the result
/// as JSON (the command's file).
#[pyfunction]
#[allow(clippy::too_many_arguments, reason = "Python's keyword arguments, one per calibrate flag")]
#[pyo3(signature = (material, model = "axis", method = "hybrid", seed = 1, population = None, generations = None, cases = "paper", nodes = 8))]
fn calibrate(
    py: Python<'_>,
    material: &Material,
    model: &str,
    method: &str,
    seed: u64,
    population: Option<usize>,
    generations: Option<usize>,
    cases: &str,
    nodes: usize,
) -> PyResult<String> {
    use tissue_studies::calibrate::{GeneSpace, Problem, Settings, calibrate};
    let topology: core::Topology = named("model", model)?;
    // The command's defaults: the search the polish finishes, or the paper's.
    let (p, g) = Settings::default_search(topology, tissue_studies::calibrate::CostMode::Static);
    let (population, generations) = (population.unwrap_or(p), generations.unwrap_or(g));
    let settings = Settings { method: named("method", method)?, seed, population, generations, ..Settings::default() };
    settings.validate().map_err(PyValueError::new_err)?;
    let grid = Grid::new(nodes).map_err(|e| PyValueError::new_err(e.to_string()))?;
    let inner = material.0.as_internal().clone();
    let space = GeneSpace::new(&inner, &grid, topology);
    let cases = named("cases", cases)?;
    let result = py.detach(|| {
        let problem =
            Problem::new(inner, grid, topology).and_then(|p| p.with_cases(cases)).map_err(|e| e.to_string())?;
        calibrate(&problem, &space, &settings, &AtomicBool::new(false), &mut |_| {}).map_err(|e| e.to_string())
    });
    let result = result.map_err(PyRuntimeError::new_err)?;
    serde_json::to_string(&result).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// A palpation map of a face as `tissue-sim palpate` makes it; as JSON (its `map.json`).
#[pyfunction]
#[pyo3(signature = (material, face = "+z", radius = 0.015, depth = 0.004, grid = 11))]
fn palpate(py: Python<'_>, material: &Material, face: &str, radius: f64, depth: f64, grid: usize) -> PyResult<String> {
    use tissue_studies::study::palpate::{Face, Palpation, PalpationMap};
    let face = Face::parse(face).map_err(PyValueError::new_err)?;
    let palpation = Palpation { face, radius, depth, grid };
    palpation.check().map_err(PyValueError::new_err)?;
    let inner = material.0.as_internal().clone();
    let map = py.detach(|| -> Result<PalpationMap, String> {
        let dir = tissue_core::io::cache_dir();
        let (background, with_inclusions) =
            tissue_core::sim::material_surface::with_background(&inner, dir.as_deref(), &mut |_| true)
                .map_err(|e| format!("{e:#}"))?;
        let forces = palpation.forces(&with_inclusions, &mut || {})?;
        let without =
            if inner.inclusions.is_empty() { forces.clone() } else { palpation.forces(&background, &mut || {})? };
        Ok(PalpationMap::new(&inner, &palpation, forces, without))
    });
    let map = map.map_err(PyRuntimeError::new_err)?;
    serde_json::to_string(&map).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Material>()?;
    m.add_class::<Press>()?;
    m.add_class::<ProbeReading>()?;
    m.add_class::<Simulation>()?;
    m.add_function(wrap_pyfunction!(calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(palpate, m)?)?;
    Ok(())
}
