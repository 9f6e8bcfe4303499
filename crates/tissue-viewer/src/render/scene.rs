//! What the viewer and the headless commands show: the object, its calibrated tissue model, a
//! load case in static equilibrium, and its colour map.

use anyhow::Context as _;
use glam::DVec3;

use crate::mechanics::cases::parse_case_id;
use crate::mechanics::grid::Grid;
use crate::mechanics::material::Material;
use crate::mechanics::msm::{MsmModel, Topology};
use crate::render::camera::OrbitCamera;
use crate::render::gpu::{LineVertex, SurfaceStyle};
use crate::render::mesh::SurfaceMesh;
use crate::render::offscreen::{Headless, encode_png};
use crate::render::{fixed_outline, lattice_edges, normalise};

use crate::sim::shipped::tissue_params;

/// Per-node colour map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColourMode {
    /// Plain shading.
    None,
    /// Displacement magnitude.
    Displacement,
    /// Distance between the MSM and the FEM answer of the case.
    Error,
}

/// A case in static equilibrium, ready to draw.
#[derive(Debug, Clone)]
pub struct StaticScene {
    /// The grid.
    pub grid: Grid,
    /// Drawn node positions (rest + magnified displacement), metres.
    pub positions: Vec<[f32; 3]>,
    /// Colour values in [0, 1], if a colour map is on.
    pub scalar: Option<Vec<f32>>,
    /// The value colour 1.0 stands for (metres).
    pub scalar_max: f32,
    /// Fixed nodes.
    pub fixed: Vec<bool>,
}

/// A rendered image.
#[derive(Debug, Clone)]
pub struct RenderedPng {
    /// PNG bytes.
    pub bytes: Vec<u8>,
    /// The same image's pixels, 8-bit RGBA rows.
    pub rgba: Vec<u8>,
    /// Adapter name.
    pub adapter: String,
    /// Backend.
    pub backend: wgpu::Backend,
}

impl StaticScene {
    /// Object A at rest (`case` `None`) or the static MSM answer of a case id.
    pub fn new(case: Option<&str>, topology: Topology, colour: ColourMode, magnify: f64) -> anyhow::Result<Self> {
        let grid = Grid::paper();
        let rest = grid.positions();
        let Some(id) = case else {
            let positions = rest.iter().map(|p| p.map(|c| c as f32)).collect();
            let scalar = (colour != ColourMode::None).then(|| vec![0.0; grid.num_nodes()]);
            return Ok(Self { grid, positions, scalar, scalar_max: 0.0, fixed: vec![false; grid.num_nodes()] });
        };
        let (object, case) = parse_case_id(&grid, id).map_err(|e| anyhow::anyhow!(e))?;
        if case.bc != crate::mechanics::cases::Bc::Clamped {
            anyhow::bail!("case {id}: only clamped cases can be shown; the mass-spring model has no roller supports");
        }
        let material = Material::preset(&object)
            .with_context(|| format!("case {id}: unknown object {object:?} (the presets are A and B)"))?;
        let params = tissue_params(&material, topology)?;
        let model = MsmModel::new(grid, params, material.density)?;
        let u = crate::mechanics::msm::statics::equilibrium(&model, &case)?;
        if !u.iter().flatten().all(|v| v.is_finite()) {
            anyhow::bail!(
                "the static answer of case {id} is not finite (its load is beyond what floating point represents); \
                 nothing was drawn"
            );
        }
        let largest = u.iter().map(|d| DVec3::from(*d).length()).fold(0.0, f64::max);
        let side = crate::mechanics::grid::CUBE_SIDE_M;
        if magnify * largest > side {
            anyhow::bail!(
                "magnify {} would draw case {id}'s largest displacement ({:.3e} m) as {:.3e} m, beyond the cube's \
                 side ({side} m); at most {:.0} for this case",
                crate::io::num(magnify),
                largest,
                magnify * largest,
                (side / largest).floor()
            );
        }
        let positions =
            rest.iter().zip(&u).map(|(r, d)| std::array::from_fn(|c| (r[c] + magnify * d[c]) as f32)).collect();
        let mut scalar_max = 0.0;
        let scalar = match colour {
            ColourMode::None => None,
            ColourMode::Displacement => Some(u.iter().map(|d| DVec3::from(*d).length() as f32).collect()),
            ColourMode::Error => {
                let fem =
                    crate::mechanics::fem::FemModel::new(grid, &material).solve_cases(std::slice::from_ref(&case))?;
                Some(
                    u.iter()
                        .zip(&fem[0].displacements)
                        .map(|(a, b)| DVec3::from(*a).distance(DVec3::from(*b)) as f32)
                        .collect(),
                )
            }
        }
        .map(|mut v: Vec<f32>| {
            scalar_max = normalise(&mut v, None);
            v
        });
        Ok(Self { grid, positions, scalar, scalar_max, fixed: case.fixed_nodes() })
    }

    /// Renders the scene offscreen with the default camera; refuses a scene with a non-finite
    /// position or colour value (no image of nothing is written).
    pub fn render_png(&self, width: u32, height: u32) -> anyhow::Result<RenderedPng> {
        let values = self.positions.iter().flatten().chain(self.scalar.iter().flatten());
        if !values.copied().all(f32::is_finite) {
            anyhow::bail!("the scene has a non-finite position or colour value; nothing was drawn");
        }
        let headless = Headless::new()?;
        let mut mesh = SurfaceMesh::new(&self.grid);
        mesh.update(&self.positions, self.scalar.as_deref());
        let mut lines: Vec<LineVertex> = Vec::new();
        let edges = lattice_edges(&self.grid);
        lines.reserve(2 * edges.len());
        fixed_outline(&edges, &self.positions, &self.fixed, [0.2, 0.9, 0.3, 1.0], &mut lines);
        let style = SurfaceStyle { colour_map: self.scalar.is_some(), ..SurfaceStyle::default() };
        let view_proj = OrbitCamera::default().view_proj(width as f32 / height.max(1) as f32);
        let rgba = headless.render((width, height), view_proj, style, &mesh, &lines)?;
        let bytes = encode_png(width, height, &rgba)?;
        Ok(RenderedPng {
            bytes,
            rgba,
            adapter: headless.adapter_info.name.clone(),
            backend: headless.adapter_info.backend,
        })
    }
}

/// Checks a drawing magnification: a non-negative number (the message names `render`'s flag).
pub fn check_magnify(magnify: f64) -> anyhow::Result<()> {
    if !(magnify.is_finite() && magnify >= 0.0) {
        anyhow::bail!("--magnify must be a non-negative number, got {}", crate::io::num(magnify));
    }
    Ok(())
}

/// Checks an offscreen image's size: 16 to 8192 pixels a side (the message names `render`'s
/// flags).
pub fn check_image_size(width: u32, height: u32) -> anyhow::Result<()> {
    if !(16..=8192).contains(&width) || !(16..=8192).contains(&height) {
        anyhow::bail!("--width and --height must be from 16 to 8192 pixels, got {width}x{height}");
    }
    Ok(())
}
