// The uniforms every render shader shares (the Rust side: `render::gpu::Globals`). The renderer
// puts this file in front of `surface.wgsl` and `lines.wgsl`.

struct Globals {
    view_proj: mat4x4<f32>,
    // xyz: direction towards the light (world space).
    light_dir: vec4<f32>,
    // x: 1.0 = colour map on, y: opacity, z: 1.0 = encode to sRGB here (non-sRGB target), w: unused.
    mode: vec4<f32>,
    // Base colour when the colour map is off.
    base_colour: vec4<f32>,
    // The colour map's four stops (xyz, linear RGB) at 0, 1/3, 2/3 and 1: `render::gpu::RAMP`.
    ramp: array<vec4<f32>, 4>,
};

@group(0) @binding(0) var<uniform> globals: Globals;
