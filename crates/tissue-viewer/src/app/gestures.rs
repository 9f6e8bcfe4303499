//! Mouse tools and gestures on the 3D view: orbit and zoom the camera, drag a picked node, press
//! and slide the probe (palpation). Gestures turn into [`Request`]s; nothing here talks to the
//! physics thread.
//!
//! The probe: the left button touches the surface under the cursor, where the sphere starts
//! tangent to the undeformed surface ([`crate::sim::press::centre`]); moving down pushes it in
//! along the inward normal there (or along the view ray, where the panel says so), 0.1 mm per
//! pixel, the wheel too (0.25 mm a notch), at most as deep as its contact resolves
//! ([`crate::sim::press::max_depth`]); with Shift held the touch point follows the cursor across
//! the surface at the depth reached (in the plane through the first touch, across the push
//! direction): pressing, holding and sliding, as a hand palpates. The clamped bottom is not
//! pressed.

use glam::Vec3;

use crate::app::recording::Press;
use crate::app::state::{Request, ToolKind};
use crate::render::camera::OrbitCamera;
use crate::render::mesh::SurfaceMesh;
use crate::sim::Tool;

/// How far a tool reaches into or away from the tissue, metres (half the cube's side).
const MAX_REACH_M: f32 = 0.05;

/// The mouse gesture in progress.
#[derive(Debug, Clone, Copy, Default)]
pub enum Gesture {
    /// Nothing held.
    #[default]
    None,
    /// Rotating the camera.
    Orbit,
    /// Pulling `node` in the camera-facing plane through `plane_point`.
    Drag {
        /// The held node.
        node: usize,
        /// A point of the drag plane.
        plane_point: Vec3,
    },
    /// Pressing the probe along `dir` at `contact`, `depth` deep.
    Probe {
        /// The touched point (moves when sliding).
        contact: Vec3,
        /// Push direction (the view ray at the first touch).
        dir: Vec3,
        /// Pointer height at the last event, pixels.
        last_y: f32,
        /// Depth, metres.
        depth: f32,
    },
}

/// What a gesture reads of the scene.
pub struct Scene<'a> {
    /// The surface, for picking.
    pub mesh: &'a SurfaceMesh,
    /// Node positions now.
    pub positions: &'a [[f32; 3]],
    /// The left-button tool.
    pub tool: ToolKind,
    /// Probe radius, mm.
    pub probe_radius_mm: f64,
    /// Push the probe along the view ray (else along the inward normal at the touch).
    pub probe_along_view: bool,
}

/// The probe's first touch at `hit` (the view ray `ray`, the pointer at height `y`): on the
/// undeformed surface nearest it, pushed along its inward normal there (or the view ray); none on
/// the clamped bottom, where the support, not the material, would push back.
fn probe_start(hit: Vec3, ray: Vec3, y: f32, scene: &Scene<'_>, requests: &mut Vec<Request>) -> Gesture {
    let (at, n) = crate::sim::press::touch(hit.as_dvec3().to_array());
    if n.z < -0.5 {
        return Gesture::None;
    }
    requests.push(Request::ProbeStarted);
    let dir = if scene.probe_along_view { ray } else { -n.as_vec3() };
    Gesture::Probe { contact: glam::DVec3::from(at).as_vec3(), dir, last_y: y, depth: 0.0 }
}

/// Handles the pointer on the 3D view (`response`), moving `camera` and pushing tool requests.
pub fn view_input(
    response: &egui::Response,
    ctx: &egui::Context,
    camera: &mut OrbitCamera,
    gesture: &mut Gesture,
    scene: &Scene<'_>,
    requests: &mut Vec<Request>,
) {
    let rect = response.rect;
    let aspect = rect.width() / rect.height().max(1.0);
    let ndc = |p: egui::Pos2| {
        [2.0 * (p.x - rect.left()) / rect.width() - 1.0, 1.0 - 2.0 * (p.y - rect.top()) / rect.height()]
    };
    let scroll = ctx.input(|i| i.smooth_scroll_delta.y);
    let deepest = crate::sim::press::max_depth(scene.probe_radius_mm * 1e-3) as f32;
    if let Gesture::Probe { depth, .. } = gesture {
        // While probing the wheel sets the depth: 0.25 mm a notch (50 points).
        *depth = (*depth + scroll / 50.0 * 2.5e-4).clamp(0.0, deepest);
    } else if response.hovered() && scroll != 0.0 {
        camera.zoom(scroll / 50.0);
    }
    if response.dragged_by(egui::PointerButton::Secondary)
        || (response.dragged_by(egui::PointerButton::Primary) && scene.tool == ToolKind::Orbit)
    {
        let d = response.drag_delta();
        camera.rotate(d.x, d.y);
        *gesture = Gesture::Orbit;
    }
    if response.drag_started_by(egui::PointerButton::Primary)
        && scene.tool != ToolKind::Orbit
        && let Some(now) = response.interact_pointer_pos()
    {
        // Where the button went down (a drag starts a few pixels later): the touch, and the
        // height the indentation counts from, so that it follows the mouse from the press.
        let pos = ctx.input(|i| i.pointer.press_origin()).unwrap_or(now);
        let (o, d) = camera.ray(ndc(pos), aspect);
        if let Some((hit, node)) = scene.mesh.pick(o.to_array(), d.to_array()) {
            *gesture = match scene.tool {
                ToolKind::Drag => Gesture::Drag { node, plane_point: Vec3::from(scene.positions[node]) },
                ToolKind::Probe => probe_start(Vec3::from(hit), d, pos.y, scene, requests),
                ToolKind::Orbit => Gesture::None,
            };
        }
    }
    if response.dragged_by(egui::PointerButton::Primary)
        && let Some(pos) = response.interact_pointer_pos()
    {
        match *gesture {
            Gesture::Drag { node, plane_point } => {
                let (o, d) = camera.ray(ndc(pos), aspect);
                let n = (camera.eye() - camera.target).normalize();
                let denom = d.dot(n);
                if denom.abs() > 1e-6 {
                    let t = (plane_point - o).dot(n) / denom;
                    // At most half the cube's side from where the node was picked: the drag
                    // spring then pulls at most 50 N, and the blow-up guard (one side from rest)
                    // is never the limit of a long mouse drag.
                    let target = plane_point + (o + t * d - plane_point).clamp_length_max(MAX_REACH_M);
                    requests.push(Request::Tool(Tool::Drag { node, target: target.as_dvec3().to_array() }));
                }
            }
            Gesture::Probe { mut contact, dir, last_y, mut depth } => {
                if ctx.input(|i| i.modifiers.shift) {
                    // Slide: the touch point under the cursor, in the plane through the touch
                    // across the push direction, within reach of the cube.
                    let (o, d) = camera.ray(ndc(pos), aspect);
                    let denom = d.dot(dir);
                    if denom.abs() > 1e-6 {
                        let t = (contact - o).dot(dir) / denom;
                        let side = crate::mechanics::grid::CUBE_SIDE_M as f32;
                        contact = (o + t * d).clamp(Vec3::ZERO, Vec3::splat(side));
                    }
                } else if !response.drag_started() {
                    // 0.1 mm of indentation per pixel dragged downwards, as deep as the contact
                    // resolves.
                    depth = (depth + (pos.y - last_y) * 1e-4).clamp(0.0, deepest);
                }
                // The drag starts a few pixels past the press: its first sample touches the surface
                // (depth 0) and the next one takes the pixels since the press, so that the sphere
                // glides in from the touch instead of starting inside the tissue.
                let last_y = if response.drag_started() { last_y } else { pos.y };
                *gesture = Gesture::Probe { contact, dir, last_y, depth };
                let press = Press {
                    at: contact.as_dvec3().to_array(),
                    direction: Some(dir.as_dvec3().normalize().to_array().map(|v| v + 0.0)),
                    radius: scene.probe_radius_mm * 1e-3,
                    depth: f64::from(depth),
                };
                // The force-depth plot takes the physics thread's readings, not the hand's target.
                requests.push(Request::Press(press));
            }
            _ => {}
        }
    }
    if response.drag_stopped() {
        if matches!(*gesture, Gesture::Drag { .. } | Gesture::Probe { .. }) {
            requests.push(Request::Tool(Tool::None));
        }
        *gesture = Gesture::None;
    }
}
