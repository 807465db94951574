// Skinned meshes (mesh.wgsl, toon.wgsl, outline.wgsl; prepended to each by `build_pipeline`):
// linear blend skinning with a palette of joint matrices (group 1), and the tint that
// multiplies the mesh's colours (white: as it is; figure colours tell candidates apart).
// Each vertex also has a morph offset (vertex buffer 1, location 8: an MMD model's face morphs
// at the drawn time, zero for every other mesh), added to its rest position before skinning.
const MAX_PALETTE: u32 = 256u;
struct Palette {
    m: array<mat4x4<f32>, 256>,
};
@group(1) @binding(0) var<uniform> palette: Palette;
@group(1) @binding(1) var<uniform> tint: vec4<f32>;

// The vertex's skinning matrix: its four joints' palette matrices by weight.
fn skin_matrix(joints: vec4<u32>, weights: vec4<f32>) -> mat4x4<f32> {
    return palette.m[min(joints.x, MAX_PALETTE - 1u)] * weights.x
         + palette.m[min(joints.y, MAX_PALETTE - 1u)] * weights.y
         + palette.m[min(joints.z, MAX_PALETTE - 1u)] * weights.z
         + palette.m[min(joints.w, MAX_PALETTE - 1u)] * weights.w;
}

// The vertex's skinned position: its rest position moved by its morph offset, then skinned.
fn skin_position(skin: mat4x4<f32>, p: vec3<f32>, morph: vec3<f32>) -> vec4<f32> {
    return skin * vec4<f32>(p + morph, 1.0);
}
