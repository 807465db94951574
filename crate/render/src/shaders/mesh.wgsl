// Skinned characters: linear blend skinning with a palette of joint matrices (group 1).
const MAX_PALETTE: u32 = 256u;
struct Palette {
    m: array<mat4x4<f32>, 256>,
};
@group(1) @binding(0) var<uniform> palette: Palette;
// Multiplies the mesh's colours (white: as it is; figure colours tell candidates apart).
@group(1) @binding(1) var<uniform> tint: vec4<f32>;
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
) -> VOut {
    let skin = palette.m[min(joints.x, MAX_PALETTE - 1u)] * weights.x
             + palette.m[min(joints.y, MAX_PALETTE - 1u)] * weights.y
             + palette.m[min(joints.z, MAX_PALETTE - 1u)] * weights.z
             + palette.m[min(joints.w, MAX_PALETTE - 1u)] * weights.w;
    var o: VOut;
    let world = skin * vec4<f32>(p, 1.0);
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
