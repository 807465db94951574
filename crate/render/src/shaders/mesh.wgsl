// Skinned characters, skinned by skin.wgsl's palette (group 1), lit by common.wgsl's `shade`.
// The part's base-colour texture (white 1×1 when it has none), multiplying its colour.
@group(2) @binding(0) var base_tex: texture_2d<f32>;
@group(2) @binding(1) var base_sampler: sampler;

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
    let world = skin_position(skin, p, morph);
    o.pos = cam.view_proj * world;
    o.normal = normalize((skin * vec4<f32>(n, 0.0)).xyz);
    o.color = color;
    o.uv = uv;
    return o;
}

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    let base = i.color.rgb * textureSample(base_tex, base_sampler, i.uv).rgb * tint.rgb;
    return vec4<f32>(shade(normalize(i.normal), base), 1.0);
}
