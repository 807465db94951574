// MMD models' toon shading: skinned as mesh.wgsl; the colour is the material's diffuse times
// its texture, times its toon ramp looked up on N·L (MMD's toon textures run from the lit
// colour at the top to the shadow colour at the bottom: v = ½(1 − N·L)), alpha blended.
// Before the ramp, the sphere map as MMD's shader applies it: looked up by the view-space
// normal (u = ½ + ½x, v = ½ − ½y, the top of the image facing up), multiplied (.sph) or added
// (.spa). Both bindings are always there: white multiplied and black added are no change.
// The diffuse colour and the texture's colour first take the part's material morphs (group 3).
@group(2) @binding(0) var base_tex: texture_2d<f32>;
@group(2) @binding(1) var base_sampler: sampler;
@group(2) @binding(2) var toon_tex: texture_2d<f32>;
@group(2) @binding(3) var toon_sampler: sampler;
@group(2) @binding(4) var sphere_mul_tex: texture_2d<f32>;
@group(2) @binding(5) var sphere_add_tex: texture_2d<f32>;
@group(2) @binding(6) var sphere_sampler: sampler;
// The part's material morphs at the drawn time (renderer `PartLook`): colour × mul + add.
struct Look {
    diffuse_mul: vec4<f32>,
    diffuse_add: vec4<f32>,
    texture_mul: vec4<f32>,
    texture_add: vec4<f32>,
    edge_mul: vec4<f32>,
    edge_add: vec4<f32>,
    edge_width_scale: vec4<f32>,
};
@group(3) @binding(0) var<uniform> look: Look;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec4<f32>,
    @location(2) uv: vec2<f32>,
};

@vertex
fn vs_main(
    @location(0) p: vec3<f32>,
    @location(1) n: vec3<f32>,
    @location(2) joints: vec4<u32>,
    @location(3) weights: vec4<f32>,
    @location(4) color: vec4<f32>,
    @location(5) uv: vec2<f32>,
    @location(8) morph: vec3<f32>,
) -> VOut {
    let skin = skin_matrix(joints, weights);
    var o: VOut;
    o.pos = cam.view_proj * skin_position(skin, p, morph);
    o.normal = normalize((skin * vec4<f32>(n, 0.0)).xyz);
    o.color = color;
    o.uv = uv;
    return o;
}

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    let tex = clamp(textureSample(base_tex, base_sampler, i.uv) * look.texture_mul + look.texture_add, vec4<f32>(0.0), vec4<f32>(1.0));
    let color = clamp(i.color * look.diffuse_mul + look.diffuse_add, vec4<f32>(0.0), vec4<f32>(1.0));
    let ndl = dot(normalize(i.normal), normalize(cam.light.xyz));
    let ramp = textureSample(toon_tex, toon_sampler, vec2<f32>(0.5, clamp(0.5 * (1.0 - ndl), 0.02, 0.98))).rgb;
    // The camera's right and up axes in the world: view_proj's first two rows are the view
    // matrix's, scaled by the projection (which does not mix x or y with other axes).
    let m = cam.view_proj;
    let right = normalize(vec3<f32>(m[0].x, m[1].x, m[2].x));
    let up = normalize(vec3<f32>(m[0].y, m[1].y, m[2].y));
    let n = normalize(i.normal);
    let suv = vec2<f32>(0.5 + 0.5 * dot(n, right), 0.5 - 0.5 * dot(n, up));
    let sphere = textureSample(sphere_mul_tex, sphere_sampler, suv).rgb;
    let sphere_add = textureSample(sphere_add_tex, sphere_sampler, suv).rgb;
    let alpha = color.a * tex.a;
    if (alpha < 0.004) {
        discard;
    }
    return vec4<f32>((color.rgb * tex.rgb * sphere + sphere_add) * tint.rgb * ramp, alpha);
}
