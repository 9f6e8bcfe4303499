// Overlays: springs, the fixed face, the tools, as coloured line segments.

// Globals: shaders/globals.wgsl, put in front of this file.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) colour: vec4<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) colour: vec4<f32>,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = globals.view_proj * vec4<f32>(v.position, 1.0);
    // Pull lines slightly towards the viewer so that they sit on top of the surface they lie on.
    out.clip.z = out.clip.z - 0.0005 * out.clip.w;
    out.colour = v.colour;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    if globals.mode.z > 0.5 {
        return vec4<f32>(pow(in.colour.rgb, vec3<f32>(1.0 / 2.2)), in.colour.a);
    }
    return in.colour;
}
