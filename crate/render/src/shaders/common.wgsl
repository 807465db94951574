// Camera shared by every pipeline (group 0).
struct Camera {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    // xyz: direction the light comes from (unit); w unused.
    light: vec4<f32>,
};
@group(0) @binding(0) var<uniform> cam: Camera;

fn shade(n: vec3<f32>, base: vec3<f32>) -> vec3<f32> {
    let l = normalize(cam.light.xyz);
    let diffuse = max(dot(n, l), 0.0);
    let sky = 0.5 + 0.5 * n.y;
    return base * (0.30 + 0.25 * sky + 0.60 * diffuse);
}
