// One mip level from the one above it: a full-screen triangle whose fragments sample the
// larger level bilinearly at their own centres, which for an even size lands between four
// texels (a 2×2 box filter). The views are sRGB, so the average is taken in linear light.
struct MipOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@group(0) @binding(0) var src: texture_2d<f32>;
@group(0) @binding(1) var src_sampler: sampler;

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> MipOut {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var o: MipOut;
    o.pos = vec4<f32>(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.0, 1.0);
    o.uv = uv;
    return o;
}

@fragment
fn fs_main(i: MipOut) -> @location(0) vec4<f32> {
    return textureSample(src, src_sampler, i.uv);
}
