// One symplectic Euler step of a spring lattice or of the linear FEM, in f32 (tissue-sim's
// `gpu::explicit`). The state is the displacement from rest `u = x - X` and the velocity `v`,
// component-major: `state[c nn + p]` is u, `state[3 nn + c nn + p]` is v. A step is one
// dispatch, `*_step` (one thread a node), from `state` into `next` (the two buffers swap
// roles each step): it computes the node's force from `u` and writes
// `v' = (v + dt ((f + f_ext) / m - c v)) free` and `u' = u + dt v'`.
// Once a tick, `guard_figures` sums what the CPU's guard needs from the state into a few bytes.
// After a step, `drag_step` takes the dragging spring's split step on its node (one thread).
//
// Each state buffer holds `6 nn` values of state, then two guard figures per workgroup, then
// the held node's velocity change in the last step (3 values, for the force on the hand).

struct Family {
    // Linear node offset of a pair `(p, p + offset)`; pairs exist for `p < len`.
    offset: u32,
    len: u32,
    // Where the family's stiffness starts in `op`.
    start: u32,
    rest_length: f32,
    // The rest vector from the first node of a pair to the second (w unused).
    rest: vec4<f32>,
}

struct Params {
    nn: u32,
    n: u32,
    families: u32,
    dt: f32,
    family: array<Family, 16>,
    // The dragging spring (tissue-sim's `drag_velocity_change`): its target as a displacement
    // from the node's rest position (xyz) and its stiffness over the node's mass (w, 1/s^2).
    drag: vec4<f32>,
    // The held node (`nn` or more: none) and the spring's damping over the node's mass, 1/s.
    drag_node: u32,
    drag_damping: f32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> state: array<f32>;
@group(0) @binding(2) var<storage, read> f_ext: array<f32>;
// `1 / m` of each node, then `c / m` of each node, then free (1 or 0) per component.
@group(0) @binding(3) var<storage, read> coef: array<f32>;
// The lattice's stiffness per family and pair, or the FEM's stencil (27 classes x 27 blocks x 9).
@group(0) @binding(4) var<storage, read> op: array<f32>;
// The state after the step.
@group(0) @binding(5) var<storage, read_write> next: array<f32>;

fn displacement(p: u32) -> vec3<f32> {
    let nn = params.nn;
    return vec3<f32>(state[p], state[nn + p], state[2u * nn + p]);
}

// The force of the spring of `fam` starting at node `p` on that node.
fn pair_force(fam: Family, p: u32) -> vec3<f32> {
    let k = op[fam.start + p];
    let d = fam.rest.xyz + displacement(p + fam.offset) - displacement(p);
    let l = max(length(d), 1e-30);
    return (k - k * fam.rest_length / l) * d;
}

fn advance(q: u32, force: vec3<f32>) {
    let nn = params.nn;
    let dt = params.dt;
    let inv_m = coef[q];
    let rate = coef[nn + q];
    for (var c = 0u; c < 3u; c++) {
        let i = c * nn + q;
        let v = state[3u * nn + i];
        let vn = (v + dt * (inv_m * (force[c] + f_ext[i]) - rate * v)) * coef[2u * nn + i];
        next[3u * nn + i] = vn;
        next[i] = state[i] + dt * vn;
    }
}

@compute @workgroup_size(64)
fn lattice_step(@builtin(global_invocation_id) id: vec3<u32>) {
    let q = id.x;
    if q >= params.nn {
        return;
    }
    var f = vec3<f32>(0.0);
    for (var i = 0u; i < params.families; i++) {
        let fam = params.family[i];
        if q < fam.len {
            f += pair_force(fam, q);
        }
        if q >= fam.offset && q - fam.offset < fam.len {
            f -= pair_force(fam, q - fam.offset);
        }
    }
    advance(q, f);
}

// 0 on the low face, 2 on the high one, 1 inside.
fn side(i: u32, n: u32) -> u32 {
    if i == 0u {
        return 0u;
    }
    if i + 1u == n {
        return 2u;
    }
    return 1u;
}

@compute @workgroup_size(64)
fn stencil_step(@builtin(global_invocation_id) id: vec3<u32>) {
    let q = id.x;
    let n = params.n;
    if q >= params.nn {
        return;
    }
    let ijk = vec3<u32>(q % n, (q / n) % n, q / (n * n));
    let cls = side(ijk.x, n) + 3u * side(ijk.y, n) + 9u * side(ijk.z, n);
    var ku = vec3<f32>(0.0);
    for (var o = 0u; o < 27u; o++) {
        let d = vec3<i32>(i32(o % 3u), i32((o / 3u) % 3u), i32(o / 9u)) - vec3<i32>(1);
        let at = vec3<i32>(ijk) + d;
        if any(at < vec3<i32>(0)) || any(at >= vec3<i32>(i32(n))) {
            continue;
        }
        let u = displacement(u32(at.x) + n * (u32(at.y) + n * u32(at.z)));
        let b = (cls * 27u + o) * 9u;
        ku += vec3<f32>(
            op[b] * u.x + op[b + 1u] * u.y + op[b + 2u] * u.z,
            op[b + 3u] * u.x + op[b + 4u] * u.y + op[b + 5u] * u.z,
            op[b + 6u] * u.x + op[b + 7u] * u.y + op[b + 8u] * u.z,
        );
    }
    advance(q, -ku);
}

// Where the held node's velocity change is kept, after the state and the guard's figures.
fn drag_slot() -> u32 {
    return 6u * params.nn + 2u * ((params.nn + 63u) / 64u);
}

// Backward Euler on the held node's spring and damper after the step, in `next`:
// `dv (1 + dt c + dt^2 k) = dt (k (target - u) - c v)`, `v += dv`, `u += dt dv` (each component
// only where free); `dv` is kept for the force on the hand.
@compute @workgroup_size(1)
fn drag_step() {
    let p = params.drag_node;
    let nn = params.nn;
    if p >= nn {
        return;
    }
    let dt = params.dt;
    let k = params.drag.w;
    let c = params.drag_damping;
    let scale = dt / (1.0 + dt * c + dt * dt * k);
    for (var i = 0u; i < 3u; i++) {
        let at = i * nn + p;
        let dv = scale * (k * (params.drag[i] - next[at]) - c * next[3u * nn + at]) * coef[2u * nn + at];
        next[3u * nn + at] += dv;
        next[at] += dt * dv;
        next[drag_slot() + i] = dv;
    }
}

var<workgroup> part: array<vec2<f32>, 64>;

// The guard's figures of the state in `state` (run once a tick, not every step): for each
// workgroup of nodes, the sum of their kinetic energies (NaN where a velocity is) and their
// largest displacement component, written after the state in `next` (two values a workgroup;
// the next step overwrites only the state before them), and the held node's velocity change.
@compute @workgroup_size(64)
fn guard_figures(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) local: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    let q = id.x;
    let nn = params.nn;
    var health = vec2<f32>(0.0);
    if q < nn {
        let m = 1.0 / coef[q];
        for (var c = 0u; c < 3u; c++) {
            let v = state[3u * nn + c * nn + q];
            health = vec2<f32>(health.x + 0.5 * m * v * v, max(health.y, abs(state[c * nn + q])));
        }
    }
    part[local] = health;
    workgroupBarrier();
    for (var s = 32u; s > 0u; s >>= 1u) {
        if local < s {
            let a = part[local];
            let b = part[local + s];
            part[local] = vec2<f32>(a.x + b.x, max(a.y, b.y));
        }
        workgroupBarrier();
    }
    if local == 0u {
        let at = 6u * nn + 2u * group.x;
        next[at] = part[0].x;
        next[at + 1u] = part[0].y;
    }
    // The held node's velocity change of the step that left `state`, with the figures.
    if id.x < 3u {
        next[drag_slot() + id.x] = state[drag_slot() + id.x];
    }
}
