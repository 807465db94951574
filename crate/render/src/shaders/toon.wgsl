// MMD models' toon shading: skinned as mesh.wgsl; the colour is the material's diffuse times
// its texture, times its toon ramp looked up on N·L (MMD's toon textures run from the lit
// colour at the top to the shadow colour at the bottom: v = ½(1 − N·L)), alpha blended.
// Before the ramp, the sphere map as MMD's shader applies it: looked up by the view-space
// normal (u = ½ + ½x, v = ½ − ½y, the top of the image facing up), multiplied (.sph) or added
// (.spa); or, in PMX's sub-texture mode, sampled at the vertex's additional UV 1 (`sphere_uv`,
// its z 1) and multiplied, as MMD's shader does. Both bindings are always there: white
// multiplied and black added are no change.
// The part's material morphs (group 3, `Look` in look.wgsl) act on the diffuse colour, the
// texture's colour, the sphere map's, the toon ramp's, and add their change to MMD's ambient
// and specular terms (three r171's MMDToonShader and MMD's own: the ambient is emissive-like,
// added before the texture; the Blinn-Phong highlight, pow(N·H, power) × specular × the light's
// specular 154/255, is added after the toon ramp).
@group(2) @binding(0) var base_tex: texture_2d<f32>;
@group(2) @binding(1) var base_sampler: sampler;
@group(2) @binding(2) var toon_tex: texture_2d<f32>;
@group(2) @binding(3) var toon_sampler: sampler;
@group(2) @binding(4) var sphere_mul_tex: texture_2d<f32>;
@group(2) @binding(5) var sphere_add_tex: texture_2d<f32>;
@group(2) @binding(6) var sphere_sampler: sampler;
@group(3) @binding(0) var<uniform> look: Look;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) color: vec4<f32>,
    @location(2) uv: vec2<f32>,
    @location(3) world: vec3<f32>,
    @location(4) sphere_uv: vec3<f32>,
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
    @location(9) uv_morph: vec2<f32>,
    @location(10) sphere_uv: vec3<f32>,
) -> VOut {
    let skin = skin_matrix(joints, weights);
    var o: VOut;
    let world = skin_position(skin, p, morph);
    o.pos = cam.view_proj * world;
    o.world = world.xyz;
    o.normal = normalize((skin * vec4<f32>(n, 0.0)).xyz);
    o.color = color;
    // The UV morphs' offsets (zero without), as MMD adds them to the vertex's UV.
    o.uv = uv + uv_morph;
    o.sphere_uv = sphere_uv;
    return o;
}

@fragment
fn fs_main(i: VOut) -> @location(0) vec4<f32> {
    let t = textureSample(base_tex, base_sampler, i.uv);
    let tex = vec4<f32>(factor(1.0, t.rgb, look.texture_mul, look.texture_add), t.a);
    var color = clamp(i.color * look.diffuse_mul + look.diffuse_add, vec4<f32>(0.0), vec4<f32>(1.0));
    color = vec4<f32>(clamp(color.rgb + look.ambient_add.rgb, vec3<f32>(0.0), vec3<f32>(1.0)), color.a);
    let ndl = dot(normalize(i.normal), normalize(cam.light.xyz));
    let ramp = factor(1.0, textureSample(toon_tex, toon_sampler, vec2<f32>(0.5, clamp(0.5 * (1.0 - ndl), 0.02, 0.98))).rgb, look.toon_mul, look.toon_add);
    // The camera's right and up axes in the world: view_proj's first two rows are the view
    // matrix's, scaled by the projection (which does not mix x or y with other axes).
    let m = cam.view_proj;
    let right = normalize(vec3<f32>(m[0].x, m[1].x, m[2].x));
    let up = normalize(vec3<f32>(m[0].y, m[1].y, m[2].y));
    let n = normalize(i.normal);
    let suv = select(vec2<f32>(0.5 + 0.5 * dot(n, right), 0.5 - 0.5 * dot(n, up)), i.sphere_uv.xy, i.sphere_uv.z > 0.5);
    let sphere = factor(1.0, textureSample(sphere_mul_tex, sphere_sampler, suv).rgb, look.sph_mul, look.sph_add);
    let sphere_add = factor(0.0, textureSample(sphere_add_tex, sphere_sampler, suv).rgb, look.spa_mul, look.spa_add);
    // The change the morphs make to MMD's highlight (none without morphs).
    let h = normalize(normalize(cam.light.xyz) + normalize(cam.eye.xyz - i.world));
    let ndh = max(dot(n, h), 1e-6);
    let highlight = highlight_of(look.specular_after, ndh) - highlight_of(look.specular_before, ndh);
    let alpha = color.a * tex.a;
    if (alpha < 0.004) {
        discard;
    }
    return vec4<f32>(max((color.rgb * tex.rgb * sphere + sphere_add) * ramp + highlight, vec3<f32>(0.0)) * tint.rgb, alpha);
}

// MMD's Blinn-Phong highlight of a specular colour (rgb) and power (w) at N·H (> 0): a power
// of 0 lights everything by the colour, as pow(x, 0) = 1.
fn highlight_of(specular: vec4<f32>, ndh: f32) -> vec3<f32> {
    let shine = select(pow(ndh, specular.w), 1.0, specular.w <= 0.0);
    return shine * specular.rgb * (154.0 / 255.0);
}

// A texture, sphere or toon colour under its material-morph factors as MMD's shader applies them
// (MikuMikuEffect's full.fx): rgb × mul + add, blended from `none` (1 for a multiplied map, 0 for
// an added one) by mul.a + add.a. No morph (mul 1, add 0) leaves the colour; a factor of 0 in every
// channel, alpha too, takes the map away (a multiplied sphere ×0 leaves the plain texture, not black).
fn factor(none: f32, rgb: vec3<f32>, mul: vec4<f32>, add: vec4<f32>) -> vec3<f32> {
    return clamp(mix(vec3<f32>(none), rgb * mul.rgb + add.rgb, mul.a + add.a), vec3<f32>(0.0), vec3<f32>(1.0));
}
