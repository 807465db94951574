// Stick figures: every bone and joint is one instanced capsule (a == b for a joint),
// drawn as a camera-facing quad and cut to the capsule's outline in the fragment shader,
// with sphere-like shading.
struct Inst {
    @location(0) a: vec4<f32>,   // xyz, radius
    @location(1) b: vec4<f32>,   // xyz, unused
    @location(2) color: vec4<f32>,
};

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) a: vec3<f32>,
    @location(2) b: vec3<f32>,
    @location(3) r: f32,
    @location(4) color: vec4<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, inst: Inst) -> VOut {
    let a = inst.a.xyz;
    let b = inst.b.xyz;
    let r = inst.a.w;
    let mid = 0.5 * (a + b);
    let view = normalize(cam.eye.xyz - mid);
    var axis = b - a;
    let len = length(axis);
    var side: vec3<f32>;
    if (len < 1e-5) {
        // A joint: any axis perpendicular to the view.
        var up = vec3<f32>(0.0, 1.0, 0.0);
        if (abs(view.y) > 0.9) { up = vec3<f32>(1.0, 0.0, 0.0); }
        side = normalize(cross(up, view));
        axis = normalize(cross(view, side));
    } else {
        axis = axis / len;
        let c = cross(axis, view);
        if (length(c) < 1e-4) {
            var up = vec3<f32>(0.0, 1.0, 0.0);
            if (abs(axis.y) > 0.9) { up = vec3<f32>(1.0, 0.0, 0.0); }
            side = normalize(cross(axis, up));
        } else {
            side = normalize(c);
        }
    }
    // Corners: (0,0) (1,0) (0,1) / (0,1) (1,0) (1,1); along: 0 = a end, 1 = b end.
    var corner = array<vec2<f32>, 6>(
        vec2<f32>(0.0, -1.0), vec2<f32>(1.0, -1.0), vec2<f32>(0.0, 1.0),
        vec2<f32>(0.0, 1.0), vec2<f32>(1.0, -1.0), vec2<f32>(1.0, 1.0));
    let k = corner[vi];
    let end = select(a - axis * r, b + axis * r, k.x > 0.5);
    // Pull the quad a radius towards the camera so it is not cut by what it wraps.
    let world = end + side * (k.y * r) + view * r;
    var o: VOut;
    o.pos = cam.view_proj * vec4<f32>(world, 1.0);
    o.world = world - view * r;
    o.a = a;
    o.b = b;
    o.r = r;
    o.color = inst.color;
    return o;
}

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    let ab = i.b - i.a;
    let t = clamp(dot(i.world - i.a, ab) / max(dot(ab, ab), 1e-10), 0.0, 1.0);
    let c = i.a + ab * t;
    let d = i.world - c;
    let view = normalize(cam.eye.xyz - c);
    // Distance measured in the plane facing the camera.
    let dp = d - view * dot(d, view);
    let q = length(dp) / i.r;
    if (q > 1.0) { discard; }
    let n = normalize(dp / i.r + view * sqrt(max(1.0 - q * q, 0.0)));
    return vec4<f32>(shade(n, i.color.rgb), 1.0);
}
