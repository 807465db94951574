// An MMD part's material morphs at the drawn time (renderer `PartLook`, the one declaration the
// toon and outline shaders share; prepended to each by `build_pipeline`, and checked field for
// field against `PartLook` by a test): each colour × mul + add (a map's factors as MMD applies them:
// rgb × mul + add, blended from no change by mul.a + add.a; toon.wgsl's `factor`). The sphere factors act on the
// sphere map of the part's mode only (`sph_*` multiplied maps, `spa_*` added ones: the viewer
// leaves the other at no change), so a part without a sphere map is not tinted. Ambient and
// specular go in as MMD's shader uses them, as the change a morph makes to MMD's terms: `ambient_add`
// is (ambient after − before), added to the colour before the texture; `specular_before` and
// `specular_after` are the specular colour (rgb) and power (w) without and with the morphs,
// and the highlight's change is added last (no morph: no change to the drawn look).
struct Look {
    diffuse_mul: vec4<f32>,
    diffuse_add: vec4<f32>,
    texture_mul: vec4<f32>,
    texture_add: vec4<f32>,
    edge_mul: vec4<f32>,
    edge_add: vec4<f32>,
    edge_width_scale: vec4<f32>,
    sph_mul: vec4<f32>,
    sph_add: vec4<f32>,
    spa_mul: vec4<f32>,
    spa_add: vec4<f32>,
    toon_mul: vec4<f32>,
    toon_add: vec4<f32>,
    ambient_add: vec4<f32>,
    specular_before: vec4<f32>,
    specular_after: vec4<f32>,
};
