// The tissue cube's surface: Lambert + ambient shading, optional colour map of a per-vertex scalar.

// Globals: shaders/globals.wgsl, put in front of this file.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) scalar: f32,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) scalar: f32,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = globals.view_proj * vec4<f32>(v.position, 1.0);
    out.normal = v.normal;
    out.scalar = v.scalar;
    return out;
}

// The colour map for t in [0, 1]: linear between the globals' four stops (`render::gpu::RAMP`).
fn colour_map(t: f32) -> vec3<f32> {
    let s = clamp(t, 0.0, 1.0) * 3.0;
    let i = min(u32(floor(s)), 2u);
    let f = s - f32(i);
    return mix(globals.ramp[i].xyz, globals.ramp[i + 1u].xyz, f);
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    let n = normalize(in.normal);
    let diffuse = abs(dot(n, normalize(globals.light_dir.xyz)));
    var base = globals.base_colour.rgb;
    if globals.mode.x > 0.5 {
        base = colour_map(in.scalar);
    }
    let shade = 0.3 + 0.7 * diffuse;
    var colour = base * shade;
    if globals.mode.z > 0.5 {
        colour = pow(colour, vec3<f32>(1.0 / 2.2));
    }
    return vec4<f32>(colour, globals.mode.y);
}
