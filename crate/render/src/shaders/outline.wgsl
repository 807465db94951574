// MMD outlines by the inverted hull: the skinned mesh pushed out along its normals by the
// part's edge width (times the vertex's edge scale, folded into `edge_width` on upload) times
// its distance from the camera (so the line keeps its width on screen),
// drawn with front faces culled so only the rim outside the model shows, in the edge colour.

// The part's material morphs at the drawn time (`Look`, look.wgsl; the edge colour × mul +
// add, the width × scale).
@group(2) @binding(0) var<uniform> look: Look;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) color: vec4<f32>,
};

@vertex
fn vs_main(
    @location(0) p: vec3<f32>,
    @location(1) n: vec3<f32>,
    @location(2) joints: vec4<u32>,
    @location(3) weights: vec4<f32>,
    @location(6) edge: vec4<f32>,
    @location(7) edge_width: f32,
    @location(8) morph: vec3<f32>,
) -> VOut {
    let skin = skin_matrix(joints, weights);
    let world = skin_position(skin, p, morph).xyz;
    let normal = normalize((skin * vec4<f32>(n, 0.0)).xyz);
    let distance = max(length(cam.eye.xyz - world), 0.1);
    var o: VOut;
    o.pos = cam.view_proj * vec4<f32>(world + normal * edge_width * max(look.edge_width_scale.x, 0.0) * distance, 1.0);
    o.color = clamp(edge * look.edge_mul + look.edge_add, vec4<f32>(0.0), vec4<f32>(1.0));
    return o;
}

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    return vec4<f32>(i.color.rgb * tint.rgb, 1.0);
}
