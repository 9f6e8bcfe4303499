//! What is drawn over the tissue, computed once per frame: the colour scalar (displacement, or
//! distance to the FEM answer) and its range, the spring, node and fixed-face lines, and the
//! legend. Reuses its buffers: no allocation per frame.

use std::fmt::Write as _;

use glam::Vec3;

use crate::app::face_map::FaceMap;
use crate::mechanics::grid::{CUBE_SIDE_M, Grid};
use crate::render::gpu::LineVertex;
use crate::render::scene::ColourMode;
use crate::render::{fixed_outline, lattice_edges, normalise, push_edges};
use crate::sim::Tool;

/// What the overlays show.
#[derive(Debug, Clone, Copy)]
pub struct Show {
    /// Colour map.
    pub colour: ColourMode,
    /// Springs (lattice edges).
    pub springs: bool,
    /// Node markers.
    pub nodes: bool,
    /// With a palpation map: its contrast, not its force.
    pub map_contrast: bool,
    /// Fixed-face outline.
    pub fixed: bool,
    /// The tool held: the probe sphere, or the dragged node's handle and force arrow.
    pub tool: Tool,
    /// The tissue's force on the tool, newtons.
    pub tool_force: [f64; 3],
    /// A revealed lump of Find the lump: its centre and radius (metres) and the person's mark on
    /// the top face (x, y).
    pub lump: Option<([f64; 3], f64, [f64; 2])>,
}

/// Length of the drag force arrow per newton, metres.
pub const ARROW_M_PER_N: f32 = 0.005;
/// Line segments of each of the probe sphere's three circles.
const CIRCLE_SEGMENTS: usize = 48;
/// Latitude bands and longitude segments of a revealed lump's translucent sphere.
const SPHERE_BANDS: usize = 12;
/// Longitude segments of the translucent sphere.
const SPHERE_SEGMENTS: usize = 24;
/// Vertices of the translucent sphere (two triangles a cell).
const SPHERE_VERTICES: usize = 6 * SPHERE_BANDS * SPHERE_SEGMENTS;

/// The overlay buffers.
pub struct Overlay {
    /// Lines to draw (springs, nodes, fixed face), then the see-through triangles.
    pub lines: Vec<LineVertex>,
    /// How many vertices at the end of `lines` are triangles seen through the surface (a revealed
    /// lump's translucent sphere), not lines.
    pub see_through: usize,
    /// The colour scalar per node, in [0, 1].
    pub scalar: Vec<f32>,
    /// In the displacement colour map, the scalar per metre of displacement (the dent's vertices
    /// are coloured by it).
    pub per_metre: Option<f32>,
    /// The legend's range text.
    pub range: String,
    /// The legend's title.
    pub title: &'static str,
    /// The legend's labels at its top and bottom.
    pub ends: [String; 2],
    edges: Vec<(usize, usize)>,
    rest: Vec<[f32; 3]>,
}

impl Overlay {
    /// Buffers for `grid`.
    pub fn new(grid: &Grid) -> Self {
        Self {
            lines: Vec::with_capacity(2 * 6000 + SPHERE_VERTICES),
            see_through: 0,
            per_metre: None,
            scalar: vec![0.0; grid.num_nodes()],
            range: String::with_capacity(64),
            title: "",
            ends: [String::with_capacity(16), String::with_capacity(16)],
            edges: lattice_edges(grid),
            rest: grid.positions().iter().map(|p| p.map(|c| c as f32)).collect(),
        }
    }

    /// Rest positions, f32.
    pub fn rest(&self) -> &[[f32; 3]] {
        &self.rest
    }

    /// Recomputes the scalar, its range text and the lines for `positions` (the largest
    /// displacement of the dent under the probe, `dented` metres, counted in the colour map's
    /// range); with `map`, the scalar is the palpation map's force on its face. The surface mesh
    /// takes the scalar after ([`crate::render::mesh::SurfaceMesh::update_dented`] with
    /// [`Overlay::per_metre`]).
    pub fn update(
        &mut self,
        show: Show,
        positions: &[[f32; 3]],
        fixed: &[bool],
        fem: Option<&[[f64; 3]]>,
        map: Option<&FaceMap>,
        dented: f32,
    ) {
        let mut max = None;
        self.per_metre = None;
        self.range.clear();
        self.ends.iter_mut().for_each(String::clear);
        self.title = match show.colour {
            ColourMode::Displacement => "displacement",
            ColourMode::Error => "MSM-FEM error",
            ColourMode::None => "",
        };
        self.ends[0].push_str("max");
        self.ends[1].push('0');
        match (show.colour, fem) {
            (_, _) if let Some(m) = map => {
                let (values, [low, high]) =
                    if show.map_contrast { (&m.contrast_per_node, m.contrast_range) } else { (&m.per_node, m.range) };
                for (s, v) in self.scalar.iter_mut().zip(values) {
                    *s = if v.is_finite() { (v - low) / (high - low).max(1e-6) } else { 0.0 };
                }
                max = Some(1.0);
                self.ends.iter_mut().for_each(String::clear);
                if show.map_contrast {
                    self.title = "contrast: force over the force without inclusions (palpation map)";
                    let _ = write!(self.ends[0], "{:+.1} %", 100.0 * high);
                    let _ = write!(self.ends[1], "{:+.1} %", 100.0 * low);
                } else {
                    self.title = "probe force (palpation map)";
                    let _ = write!(self.ends[0], "{high:.2} N");
                    let _ = write!(self.ends[1], "{low:.2} N");
                }
                self.range.push_str("pressed 4 mm, 21 x 21 points");
            }
            (ColourMode::None, _) => self.scalar.fill(0.0),
            (ColourMode::Displacement, _) => {
                for (s, (p, r)) in self.scalar.iter_mut().zip(positions.iter().zip(&self.rest)) {
                    *s = Vec3::from(*p).distance(Vec3::from(*r));
                }
                // The dent under the probe counts: the material's displacement there.
                let m = 0.002f32.max(self.scalar.iter().copied().fold(dented, f32::max));
                max = Some(m);
                self.per_metre = Some(1.0 / m);
                let _ = write!(self.range, "0 .. {:.2} mm", m * 1e3);
            }
            (ColourMode::Error, Some(fem)) => {
                for (i, s) in self.scalar.iter_mut().enumerate() {
                    let target =
                        Vec3::from(self.rest[i]) + Vec3::new(fem[i][0] as f32, fem[i][1] as f32, fem[i][2] as f32);
                    *s = Vec3::from(positions[i]).distance(target);
                }
                self.range.push_str("0 .. max |x_msm - x_fem|");
            }
            (ColourMode::Error, None) => {
                self.scalar.fill(0.0);
                self.range.push_str("apply a load case for the FEM answer");
            }
        }
        normalise(&mut self.scalar, max);
        self.lines.clear();
        if show.fixed {
            fixed_outline(&self.edges, positions, fixed, [0.2, 0.9, 0.3, 1.0], &mut self.lines);
        }
        if show.nodes {
            for p in positions {
                for axis in 0..3 {
                    if self.lines.len() + 2 > self.lines.capacity() {
                        break;
                    }
                    let (mut a, mut b) = (*p, *p);
                    a[axis] -= 0.0015;
                    b[axis] += 0.0015;
                    self.lines.push(LineVertex { position: a, colour: [1.0, 1.0, 0.6, 0.9] });
                    self.lines.push(LineVertex { position: b, colour: [1.0, 1.0, 0.6, 0.9] });
                }
            }
        }
        if show.springs {
            push_edges(&self.edges, positions, [0.9, 0.9, 0.9, 0.35], |_, _| true, &mut self.lines);
        }
        self.push_tool(show, positions);
        self.push_lump(show);
        // Last: the triangles the renderer draws through the surface.
        self.see_through = self.push_lump_sphere(show);
    }

    /// A revealed lump as a translucent sphere seen through the tissue: triangles of a latitude
    /// and longitude sphere, lit from above so that it reads as round; how many vertices.
    fn push_lump_sphere(&mut self, show: Show) -> usize {
        let Some((centre, radius, _)) = show.lump else { return 0 };
        if self.lines.len() + SPHERE_VERTICES > self.lines.capacity() {
            return 0;
        }
        let (c, r) = (Vec3::from(centre.map(|v| v as f32)), radius as f32);
        let point = |i: usize, j: usize| {
            let (theta, phi) = (
                std::f32::consts::PI * i as f32 / SPHERE_BANDS as f32,
                std::f32::consts::TAU * j as f32 / SPHERE_SEGMENTS as f32,
            );
            Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
        };
        let vertex = |n: Vec3| {
            let light = 0.55 + 0.45 * n.dot(Vec3::new(0.3, -0.4, 0.87).normalize()).max(0.0);
            LineVertex { position: (c + r * n).to_array(), colour: [light, 0.35 * light, 0.8 * light, 0.28] }
        };
        for i in 0..SPHERE_BANDS {
            for j in 0..SPHERE_SEGMENTS {
                let (a, b, d, e) = (point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1));
                for n in [a, b, d, a, d, e] {
                    self.lines.push(vertex(n));
                }
            }
        }
        SPHERE_VERTICES
    }

    /// A circle of `radius` about `centre` in the plane of `u` and `v`.
    fn push_circle(&mut self, centre: Vec3, radius: f32, (u, v): (Vec3, Vec3), colour: [f32; 4]) {
        for i in 0..CIRCLE_SEGMENTS {
            let t = |k: usize| k as f32 / CIRCLE_SEGMENTS as f32 * std::f32::consts::TAU;
            let p = |k: usize| centre + radius * (u * t(k).cos() + v * t(k).sin());
            self.push_line(p(i), p(i + 1), colour);
        }
    }

    /// A revealed lump: three great circles of its sphere, its outline on the top face (just above
    /// it, where the sphere would show through) and the person's mark as a cross there (its
    /// translucent sphere: [`Overlay::push_lump_sphere`]).
    fn push_lump(&mut self, show: Show) {
        let Some((centre, radius, mark)) = show.lump else { return };
        let (c, r) = (Vec3::from(centre.map(|v| v as f32)), radius as f32);
        let colour = [1.0, 0.35, 0.8, 0.9];
        for plane in [(Vec3::X, Vec3::Y), (Vec3::X, Vec3::Z), (Vec3::Y, Vec3::Z)] {
            self.push_circle(c, r, plane, colour);
        }
        let top = CUBE_SIDE_M as f32 + 0.0005;
        self.push_circle(Vec3::new(c.x, c.y, top), r, (Vec3::X, Vec3::Y), colour);
        let m = Vec3::new(mark[0] as f32, mark[1] as f32, top);
        let (a, b) = (Vec3::new(0.004, 0.004, 0.0), Vec3::new(0.004, -0.004, 0.0));
        let yellow = [1.0, 0.9, 0.2, 1.0];
        self.push_line(m - a, m + a, yellow);
        self.push_line(m - b, m + b, yellow);
    }

    fn push_line(&mut self, a: Vec3, b: Vec3, colour: [f32; 4]) {
        if self.lines.len() + 2 <= self.lines.capacity() {
            self.lines.push(LineVertex { position: a.to_array(), colour });
            self.lines.push(LineVertex { position: b.to_array(), colour });
        }
    }

    /// The probe as three great circles; the dragged node as a small cube-corner handle, a line
    /// to the mouse's target and an arrow of the force on the tissue ([`ARROW_M_PER_N`]).
    fn push_tool(&mut self, show: Show, positions: &[[f32; 3]]) {
        match show.tool {
            Tool::None => {}
            Tool::Probe { centre, radius } => {
                let c = Vec3::from(centre.map(|v| v as f32));
                for plane in [(Vec3::X, Vec3::Y), (Vec3::X, Vec3::Z), (Vec3::Y, Vec3::Z)] {
                    self.push_circle(c, radius as f32, plane, [0.95, 0.95, 1.0, 0.9]);
                }
            }
            Tool::Drag { node, target } => {
                let Some(p) = positions.get(node).map(|p| Vec3::from(*p)) else { return };
                let handle = [1.0, 0.55, 0.1, 1.0];
                for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
                    self.push_line(p - 0.003 * axis, p + 0.003 * axis, handle);
                }
                let t = Vec3::from(target.map(|v| v as f32));
                self.push_line(p, t, [0.7, 0.7, 0.7, 0.6]);
                // The force the tool puts on the tissue is minus the tissue's force on the tool.
                let f = -Vec3::from(show.tool_force.map(|v| v as f32));
                if f.length() > 1e-6 {
                    let tip = p + f * ARROW_M_PER_N;
                    let arrow = [1.0, 0.3, 0.3, 1.0];
                    self.push_line(p, tip, arrow);
                    let back = (p - tip).normalize() * (0.25 * (tip - p).length()).min(0.008);
                    let side = back.any_orthonormal_vector() * back.length() * 0.5;
                    self.push_line(tip, tip + back + side, arrow);
                    self.push_line(tip, tip + back - side, arrow);
                }
            }
        }
    }
}

/// Average and largest distance between the drawn positions and the FEM answer, metres.
pub fn error_vs_fem(pos: &[[f32; 3]], rest: &[[f32; 3]], fem: &[[f64; 3]]) -> (f64, f64) {
    let mut sum = 0.0;
    let mut max = 0.0f64;
    for ((p, r), u) in pos.iter().zip(rest).zip(fem) {
        let d = (0..3).map(|c| (f64::from(p[c]) - f64::from(r[c]) - u[c]).powi(2)).sum::<f64>().sqrt();
        sum += d;
        max = max.max(d);
    }
    (sum / pos.len().max(1) as f64, max)
}

/// The colour legend at the right edge of the 3D view.
pub fn legend(ui: &mut egui::Ui, rect: egui::Rect, overlay: &Overlay) {
    let (title, range) = (overlay.title, overlay.range.as_str());
    let painter = ui.painter_at(rect);
    let x0 = rect.right() - 40.0;
    let (top, bottom) = (rect.top() + 40.0, rect.top() + 240.0);
    let steps = 32;
    for i in 0..steps {
        let t = i as f32 / steps as f32;
        let c = ramp(1.0 - t);
        let y = top + t * (bottom - top);
        painter.rect_filled(
            egui::Rect::from_min_max(egui::pos2(x0, y), egui::pos2(x0 + 16.0, y + (bottom - top) / steps as f32 + 1.0)),
            0.0,
            c,
        );
    }
    let label = |pos: egui::Pos2, align: egui::Align2, text: &str, size: f32| {
        painter.text(pos, align, text, egui::FontId::proportional(size), egui::Color32::WHITE);
    };
    label(egui::pos2(x0 + 16.0, top - 22.0), egui::Align2::RIGHT_BOTTOM, title, 13.0);
    label(egui::pos2(x0 - 6.0, top), egui::Align2::RIGHT_TOP, &overlay.ends[0], 12.0);
    label(egui::pos2(x0 - 6.0, bottom), egui::Align2::RIGHT_BOTTOM, &overlay.ends[1], 12.0);
    label(egui::pos2(x0 + 16.0, bottom + 6.0), egui::Align2::RIGHT_TOP, range, 12.0);
}

/// The surface's colour ramp, for the legend ([`crate::render::gpu::ramp_srgb8`]).
fn ramp(t: f32) -> egui::Color32 {
    let [r, g, b] = crate::render::gpu::ramp_srgb8(t);
    egui::Color32::from_rgb(r, g, b)
}

/// Samples kept by [`ForceTrace`] (a few seconds of frames).
const TRACE_LEN: usize = 240;

/// The probe's recent force, newtons, shown as a number and a small plot next to the sphere in
/// the 3D view. A ring buffer: pushing allocates nothing.
#[derive(Debug, Clone)]
pub struct ForceTrace {
    values: [f32; TRACE_LEN],
    len: usize,
    head: usize,
    /// The last sample's depth, metres, where the reading has one.
    depth_m: Option<f32>,
}

impl Default for ForceTrace {
    fn default() -> Self {
        Self { values: [0.0; TRACE_LEN], len: 0, head: 0, depth_m: None }
    }
}

impl ForceTrace {
    /// Adds a sample: the force and the depth of one reading.
    pub fn push(&mut self, force_n: f32, depth_m: Option<f32>) {
        self.depth_m = depth_m;
        self.values[self.head] = force_n;
        self.head = (self.head + 1) % TRACE_LEN;
        self.len = (self.len + 1).min(TRACE_LEN);
    }

    /// Forgets every sample.
    pub fn clear(&mut self) {
        self.len = 0;
    }

    fn sample(&self, i: usize) -> f32 {
        self.values[(self.head + TRACE_LEN - self.len + i) % TRACE_LEN]
    }

    /// The box [`ForceTrace::draw`] fills, with or without a line on the contact.
    pub fn size(with_note: bool) -> egui::Vec2 {
        egui::vec2(if with_note { 230.0 } else { 170.0 }, if with_note { 74.0 } else { 56.0 })
    }

    /// Draws the last force and the trace in a small box with its top-left corner at `at`, and
    /// under the force `note` (in orange: the force is not the material's, and why) where given.
    pub fn draw(&self, painter: &egui::Painter, at: egui::Pos2, note: Option<&str>) {
        if self.len == 0 {
            return;
        }
        let size = Self::size(note.is_some());
        let frame = egui::Rect::from_min_size(at, size);
        painter.rect_filled(frame, 4.0, egui::Color32::from_black_alpha(170));
        let last = self.sample(self.len - 1);
        painter.text(
            at + egui::vec2(6.0, 4.0),
            egui::Align2::LEFT_TOP,
            match self.depth_m {
                Some(d) => format!("{last:.2} N at {:.1} mm", 1e3 * d),
                None => format!("{last:.2} N"),
            },
            egui::FontId::proportional(16.0),
            egui::Color32::WHITE,
        );
        let at = match note {
            Some(note) => {
                painter.text(
                    at + egui::vec2(6.0, 24.0),
                    egui::Align2::LEFT_TOP,
                    note,
                    egui::FontId::proportional(12.0),
                    egui::Color32::from_rgb(255, 170, 60),
                );
                at + egui::vec2(0.0, 18.0)
            }
            None => at,
        };
        let size = egui::vec2(size.x, 56.0);
        let top = (0..self.len).map(|i| self.sample(i)).fold(1e-3f32, f32::max);
        let plot = egui::Rect::from_min_max(at + egui::vec2(6.0, 24.0), at + size - egui::vec2(6.0, 4.0));
        let points: Vec<egui::Pos2> = (0..self.len)
            .map(|i| {
                let x = plot.left() + plot.width() * i as f32 / (TRACE_LEN - 1) as f32;
                egui::pos2(x, plot.bottom() - plot.height() * (self.sample(i) / top).clamp(0.0, 1.0))
            })
            .collect();
        painter.add(egui::Shape::line(points, egui::Stroke::new(1.5, egui::Color32::from_rgb(255, 170, 60))));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn show(lump: Option<([f64; 3], f64, [f64; 2])>) -> Show {
        Show {
            colour: ColourMode::Displacement,
            springs: true,
            nodes: false,
            map_contrast: false,
            fixed: true,
            tool: Tool::Probe { centre: [0.05, 0.05, 0.114], radius: 0.015 },
            tool_force: [0.0; 3],
            lump,
        }
    }

    #[test]
    fn a_revealed_lump_is_a_translucent_sphere_after_the_lines() {
        let grid = Grid::paper();
        let mut overlay = Overlay::new(&grid);
        let positions = overlay.rest().to_vec();
        let fixed = vec![false; grid.num_nodes()];
        overlay.update(show(None), &positions, &fixed, None, None, 0.0);
        assert_eq!(overlay.see_through, 0, "nothing to see through");
        let lines = overlay.lines.len();
        let (centre, radius) = ([0.065, 0.031, 0.1 - 0.0067 - 0.0096], 0.0096);
        overlay.update(show(Some((centre, radius, [0.0585, 0.0393]))), &positions, &fixed, None, None, 0.0);
        assert_eq!(overlay.see_through, SPHERE_VERTICES);
        let sphere = &overlay.lines[overlay.lines.len() - SPHERE_VERTICES..];
        assert!(overlay.lines.len() - SPHERE_VERTICES > lines, "the outline and the mark are lines before it");
        for v in sphere {
            let d = Vec3::from(v.position).distance(Vec3::from(centre.map(|c| c as f32)));
            assert!((d - radius as f32).abs() < 1e-5, "on the lump's sphere: {d}");
            assert!(v.colour[3] > 0.0 && v.colour[3] < 0.5, "translucent: alpha {}", v.colour[3]);
        }
        // No allocation per frame: the buffer's capacity holds it.
        let capacity = overlay.lines.capacity();
        overlay.update(show(Some((centre, radius, [0.05, 0.05]))), &positions, &fixed, None, None, 0.0);
        assert_eq!(overlay.lines.capacity(), capacity);
    }
}
