//! Offscreen rendering through the viewer's renderer on whatever adapter exists (software Vulkan,
//! Mesa lavapipe, in CI): the cube is drawn, and a deformed case differs from the rest shape.

use tissue_core::mechanics::msm::Topology;
use tissue_viewer::render::scene::{ColourMode, StaticScene};

fn decode(png: &[u8]) -> image::RgbaImage {
    image::load_from_memory(png).expect("valid PNG").to_rgba8()
}

#[test]
fn offscreen_render_shows_the_cube_and_its_deformation() {
    if tissue_viewer::render::offscreen::Headless::new().is_err() && std::env::var_os("CI").is_none() {
        eprintln!("skipped: no wgpu adapter (install mesa-vulkan-drivers for software Vulkan); CI requires one");
        return;
    }
    let rest = StaticScene::new(None, Topology::Shear, ColourMode::Displacement, 1.0).expect("scene");
    let case =
        StaticScene::new(Some("A_clamped_ax1_F10"), Topology::Shear, ColourMode::Displacement, 20.0).expect("scene");
    let (w, h) = (320, 200);
    let a = decode(&rest.render_png(w, h).expect("render").bytes);
    let b = decode(&case.render_png(w, h).expect("render").bytes);
    assert_eq!(a.dimensions(), (w, h));
    let corner = *a.get_pixel(0, 0);
    let centre = *a.get_pixel(w / 2, h / 2);
    assert_ne!(corner, centre, "the cube covers the centre of the view");
    let covered = a.pixels().filter(|p| **p != corner).count();
    assert!(covered > (w * h / 10) as usize, "cube covers {covered} pixels");
    let differing = a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count();
    assert!(differing > (w * h / 20) as usize, "deformed case differs in only {differing} pixels");
}
