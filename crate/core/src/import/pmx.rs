//! PMX 2.0 / 2.1 reader: the model format of PMX Editor and current MMD.
//!
//! Reads every section into the [`MmdModel`] PMD also gives: the header globals (text encoding
//! UTF-16LE or UTF-8, additional UV count, the byte size 1/2/4 of each kind of index), vertices
//! with BDEF1/BDEF2/BDEF4/SDEF/QDEF skins, faces, texture paths, materials, bones (grant, fixed
//! axis, local axes, external parent, IK with link limits), morphs (vertex, UV, bone, material,
//! group, and 2.1's flip and impulse), display frames, rigid bodies, joints and 2.1's soft
//! bodies (kept in outline). Every index is checked against what it points into; an index
//! of −1 is "none" only where PMX allows it.

use super::mmd_bytes::{check_index, check_optional_index, printable_start, CountWidth, MmdError, Reader, TextEncoding};
use super::mmd_model::*;
use super::pmd::{rigid_mode, rigid_shape, validate_geometry};

/// "PMX " then a little-endian f32 version.
pub const MAGIC: &[u8] = b"PMX ";

/// The header globals: how the rest of the file is laid out.
#[derive(Clone, Copy, Debug)]
struct Globals {
    encoding: TextEncoding,
    additional_uvs: usize,
    vertex: usize,
    texture: usize,
    material: usize,
    bone: usize,
    morph: usize,
    rigid: usize,
}

impl Reader<'_> {
    /// A vertex index: unsigned for sizes 1 and 2, signed for 4 (as PMX stores them).
    fn vertex_index(&mut self, size: usize) -> Result<i64, MmdError> {
        Ok(match size {
            1 => i64::from(self.u8()?),
            2 => i64::from(self.u16()?),
            _ => i64::from(self.i32()?),
        })
    }
    /// Any other index: signed, −1 meaning none.
    fn index(&mut self, size: usize) -> Result<i64, MmdError> {
        Ok(match size {
            1 => i64::from(self.i8()?),
            2 => i64::from(self.i16()?),
            _ => i64::from(self.i32()?),
        })
    }
}

/// Reads a PMX file (2.0 or 2.1).
pub fn read(file: &str, bytes: &[u8]) -> Result<MmdModel, MmdError> {
    if !bytes.starts_with(MAGIC) {
        return Err(MmdError::BadMagic { file: file.to_string(), expected: "PMX model", found: printable_start(bytes, 8) });
    }
    let mut r = Reader::new(file, bytes);
    r.skip(4)?;
    let version = r.f32()?;
    if version != 2.0 && version != 2.1 {
        return Err(MmdError::BadVersion { file: file.to_string(), format: "PMX", version: version.to_string(), supported: "2.0, 2.1" });
    }
    let at = r.pos();
    let n_globals = r.u8()?;
    if n_globals < 8 {
        return Err(r.bad_value(at, "header globals count", i64::from(n_globals), "8 or more"));
    }
    let g = r.bytes(usize::from(n_globals))?;
    let size = |i: usize, what: &'static str| -> Result<usize, MmdError> {
        match g[i] {
            1 | 2 | 4 => Ok(usize::from(g[i])),
            v => Err(r.bad_value(at + 1 + i, what, i64::from(v), "1, 2 or 4 bytes")),
        }
    };
    let encoding = match g[0] {
        0 => TextEncoding::Utf16Le,
        1 => TextEncoding::Utf8,
        v => return Err(r.bad_value(at + 1, "text encoding", i64::from(v), "0 UTF-16LE, 1 UTF-8")),
    };
    if g[1] > 4 {
        return Err(r.bad_value(at + 2, "additional UV count", i64::from(g[1]), "0–4"));
    }
    let gl = Globals {
        encoding,
        additional_uvs: usize::from(g[1]),
        vertex: size(2, "vertex index size")?,
        texture: size(3, "texture index size")?,
        material: size(4, "material index size")?,
        bone: size(5, "bone index size")?,
        morph: size(6, "morph index size")?,
        rigid: size(7, "rigid body index size")?,
    };
    let e = gl.encoding;
    let name = r.pmx_text(e)?;
    let name_en = r.pmx_text(e)?;
    let comment = r.pmx_text(e)?;
    let comment_en = r.pmx_text(e)?;

    // ---- vertices ----
    r.section("vertices");
    let n_vertices = r.count(CountWidth::I32, 32 + 16 * gl.additional_uvs + 1 + gl.bone + 4)?;
    let mut vertices = Vec::with_capacity(n_vertices);
    let mut additional_uvs = Vec::with_capacity(n_vertices * gl.additional_uvs);
    // A bone slot: −1 (none) and other negatives become u32::MAX, which validate_geometry
    // refuses if weighted and sets to bone 0 if not.
    let bone_slot = |i: i64| if i >= 0 && i <= i64::from(u32::MAX - 1) { i as u32 } else { u32::MAX };
    for _ in 0..n_vertices {
        let position = r.vec3()?;
        let normal = r.vec3()?;
        let uv = r.vec2()?;
        for _ in 0..gl.additional_uvs {
            additional_uvs.push(r.vec4()?);
        }
        let at = r.pos();
        let skin = match r.u8()? {
            0 => Skin { kind: SkinKind::Bdef1, bones: [bone_slot(r.index(gl.bone)?), 0, 0, 0], weights: [1.0, 0.0, 0.0, 0.0], sdef: None },
            1 => {
                let (b0, b1) = (bone_slot(r.index(gl.bone)?), bone_slot(r.index(gl.bone)?));
                let w = r.f32()?;
                Skin { kind: SkinKind::Bdef2, bones: [b0, b1, 0, 0], weights: [w, 1.0 - w, 0.0, 0.0], sdef: None }
            }
            k @ (2 | 4) => {
                let mut bones = [0u32; 4];
                for b in &mut bones {
                    *b = bone_slot(r.index(gl.bone)?);
                }
                let weights = [r.f32()?, r.f32()?, r.f32()?, r.f32()?];
                Skin { kind: if k == 2 { SkinKind::Bdef4 } else { SkinKind::Qdef }, bones, weights, sdef: None }
            }
            3 => {
                let (b0, b1) = (bone_slot(r.index(gl.bone)?), bone_slot(r.index(gl.bone)?));
                let w = r.f32()?;
                let sdef = Sdef { c: r.vec3()?, r0: r.vec3()?, r1: r.vec3()? };
                Skin { kind: SkinKind::Sdef, bones: [b0, b1, 0, 0], weights: [w, 1.0 - w, 0.0, 0.0], sdef: Some(sdef) }
            }
            v => return Err(r.bad_value(at, "weight type", i64::from(v), "0 BDEF1, 1 BDEF2, 2 BDEF4, 3 SDEF, 4 QDEF")),
        };
        let edge_scale = r.f32()?;
        vertices.push(MmdVertex { position, normal, uv, skin, edge_scale });
    }

    // ---- faces ----
    r.section("faces");
    let n = r.count(CountWidth::I32, gl.vertex)?;
    let mut indices = Vec::with_capacity(n);
    for i in 0..n {
        let v = r.vertex_index(gl.vertex)?;
        indices.push(check_index(file, "face index", i, "vertex", v, n_vertices)? as u32);
    }

    // ---- textures ----
    r.section("textures");
    let n_textures = r.count(CountWidth::I32, 4)?;
    let mut textures = Vec::with_capacity(n_textures);
    for _ in 0..n_textures {
        textures.push(r.pmx_text(e)?);
    }

    // ---- materials ----
    r.section("materials");
    let n_materials = r.count(CountWidth::I32, 84 + 2 * gl.texture)?;
    let mut materials = Vec::with_capacity(n_materials);
    for i in 0..n_materials {
        let name = r.pmx_text(e)?;
        let name_en = r.pmx_text(e)?;
        let diffuse = r.vec4()?;
        let specular = r.vec3()?;
        let specular_power = r.f32()?;
        let ambient = r.vec3()?;
        let flags = r.u8()?;
        let edge_colour = r.vec4()?;
        let edge_size = r.f32()?;
        let texture = check_optional_index(file, "material", i, "texture", r.index(gl.texture)?, n_textures)?;
        let sphere = check_optional_index(file, "material", i, "sphere texture", r.index(gl.texture)?, n_textures)?;
        let at = r.pos();
        let sphere_mode = match r.u8()? {
            0 => SphereMode::None,
            1 => SphereMode::Multiply,
            2 => SphereMode::Add,
            3 => SphereMode::SubTexture,
            v => return Err(r.bad_value(at, "sphere mode", i64::from(v), "0–3")),
        };
        let at = r.pos();
        let toon = match r.u8()? {
            0 => match check_optional_index(file, "material", i, "toon texture", r.index(gl.texture)?, n_textures)? {
                Some(t) => Toon::Texture(t),
                None => Toon::None,
            },
            1 => {
                let at = r.pos();
                match r.u8()? {
                    t @ 0..=9 => Toon::Shared(t),
                    v => return Err(r.bad_value(at, "shared toon", i64::from(v), "0–9 (toon01–toon10)")),
                }
            }
            v => return Err(r.bad_value(at, "toon flag", i64::from(v), "0 own texture, 1 shared")),
        };
        let memo = r.pmx_text(e)?;
        let at = r.pos();
        let count = r.i32()?;
        if count < 0 {
            return Err(r.bad_value(at, "material index count", i64::from(count), "0 or more"));
        }
        materials.push(MmdMaterial {
            name,
            name_en,
            diffuse,
            specular,
            specular_power,
            ambient,
            flags,
            edge_colour,
            edge_size,
            texture,
            sphere,
            sphere_mode,
            toon,
            memo,
            index_count: count as u32,
        });
    }

    // ---- bones ----
    r.section("bones");
    let n_bones = r.count(CountWidth::I32, 26 + 2 * gl.bone)?;
    let mut bones = Vec::with_capacity(n_bones);
    // Raw indices checked once every bone is known (parents may come later in the list).
    struct RawBone {
        parent: i64,
        tail: Option<i64>,
        grant: Option<i64>,
        ik_target: Option<i64>,
        links: Vec<i64>,
    }
    let mut raw = Vec::with_capacity(n_bones);
    for _ in 0..n_bones {
        use bone_flags::*;
        let name = r.pmx_text(e)?;
        let name_en = r.pmx_text(e)?;
        let position = r.vec3()?;
        let parent = r.index(gl.bone)?;
        let layer = r.i32()?;
        let flags = r.u16()?;
        let mut rb = RawBone { parent, tail: None, grant: None, ik_target: None, links: Vec::new() };
        let tail = if flags & TAIL_IS_BONE != 0 {
            rb.tail = Some(r.index(gl.bone)?);
            BoneTail::Bone(None)
        } else {
            BoneTail::Offset(r.vec3()?)
        };
        let mut grant = None;
        if flags & (GRANT_ROTATION | GRANT_TRANSLATION) != 0 {
            rb.grant = Some(r.index(gl.bone)?);
            let ratio = r.f32()?;
            grant = Some(Grant {
                parent: 0,
                ratio,
                rotation: flags & GRANT_ROTATION != 0,
                translation: flags & GRANT_TRANSLATION != 0,
                local: flags & LOCAL_GRANT != 0,
            });
        }
        let fixed_axis = if flags & FIXED_AXIS != 0 { Some(r.vec3()?) } else { None };
        let local_axes = if flags & LOCAL_AXES != 0 { Some((r.vec3()?, r.vec3()?)) } else { None };
        let external_parent_key = if flags & EXTERNAL_PARENT != 0 { Some(r.i32()?) } else { None };
        let mut ik = None;
        if flags & IK != 0 {
            rb.ik_target = Some(r.index(gl.bone)?);
            let at = r.pos();
            let loop_count = r.i32()?;
            if loop_count < 0 {
                return Err(r.bad_value(at, "IK loop count", i64::from(loop_count), "0 or more"));
            }
            let limit_angle_rad = r.f32()?;
            let n_links = r.count(CountWidth::I32, gl.bone + 1)?;
            let mut links = Vec::with_capacity(n_links);
            for _ in 0..n_links {
                rb.links.push(r.index(gl.bone)?);
                let at = r.pos();
                let limits = match r.u8()? {
                    0 => None,
                    1 => Some((r.vec3()?, r.vec3()?)),
                    v => return Err(r.bad_value(at, "IK link limit flag", i64::from(v), "0 or 1")),
                };
                links.push(IkLink { bone: 0, limits });
            }
            ik = Some(Ik { target: 0, loop_count: loop_count as u32, limit_angle_rad, links });
        }
        raw.push(rb);
        bones.push(MmdBone {
            name,
            name_en,
            position,
            parent: None,
            layer,
            flags,
            tail,
            grant,
            fixed_axis,
            local_axes,
            external_parent_key,
            ik,
            pmd_type: None,
        });
    }
    for (i, (b, rb)) in bones.iter_mut().zip(&raw).enumerate() {
        b.parent = check_optional_index(file, "bone", i, "parent", rb.parent, n_bones)?;
        if let Some(t) = rb.tail {
            b.tail = BoneTail::Bone(check_optional_index(file, "bone", i, "tail", t, n_bones)?);
        }
        if let (Some(g), Some(p)) = (&mut b.grant, rb.grant) {
            match check_optional_index(file, "bone", i, "grant parent", p, n_bones)? {
                Some(p) => g.parent = p,
                // A grant flag with parent −1: PMX Editor writes it; it grants nothing.
                None => b.grant = None,
            }
        }
        if let (Some(ik), Some(t)) = (&mut b.ik, rb.ik_target) {
            ik.target = check_index(file, "bone", i, "IK target", t, n_bones)?;
            for (l, &li) in ik.links.iter_mut().zip(&rb.links) {
                l.bone = check_index(file, "bone", i, "IK link", li, n_bones)?;
            }
        }
    }

    // ---- morphs ----
    r.section("morphs");
    let n_morphs = r.count(CountWidth::I32, 14)?;
    let mut morphs = Vec::with_capacity(n_morphs);
    // Impulse morphs name rigid bodies, which come later: (morph, offset, rigid index).
    let mut impulse_refs: Vec<(usize, i64)> = Vec::new();
    for m in 0..n_morphs {
        let name = r.pmx_text(e)?;
        let name_en = r.pmx_text(e)?;
        let panel = r.u8()?;
        let at = r.pos();
        let kind = r.u8()?;
        let min = match kind {
            0 | 9 => gl.morph + 4,
            1 => gl.vertex + 12,
            2 => gl.bone + 28,
            3..=7 => gl.vertex + 16,
            8 => gl.material + 113,
            10 => gl.rigid + 25,
            v => return Err(r.bad_value(at, "morph type", i64::from(v), "0–10")),
        };
        let n = r.count(CountWidth::I32, min)?;
        let data = match kind {
            0 | 9 => {
                let mut v = Vec::with_capacity(n);
                for _ in 0..n {
                    v.push((check_index(file, "morph", m, "morph", r.index(gl.morph)?, n_morphs)?, r.f32()?));
                }
                if kind == 0 {
                    MorphData::Group(v)
                } else {
                    MorphData::Flip(v)
                }
            }
            1 => {
                let mut v = Vec::with_capacity(n);
                for _ in 0..n {
                    v.push((check_index(file, "morph", m, "vertex", r.vertex_index(gl.vertex)?, n_vertices)?, r.vec3()?));
                }
                MorphData::Vertex(v)
            }
            2 => {
                let mut v = Vec::with_capacity(n);
                for _ in 0..n {
                    v.push((check_index(file, "morph", m, "bone", r.index(gl.bone)?, n_bones)?, r.vec3()?, r.quat()?));
                }
                MorphData::Bone(v)
            }
            3..=7 => {
                let mut v = Vec::with_capacity(n);
                for _ in 0..n {
                    v.push((check_index(file, "morph", m, "vertex", r.vertex_index(gl.vertex)?, n_vertices)?, r.vec4()?));
                }
                MorphData::Uv { channel: kind - 3, offsets: v }
            }
            8 => {
                let mut v = Vec::with_capacity(n);
                for _ in 0..n {
                    let material = check_optional_index(file, "morph", m, "material", r.index(gl.material)?, n_materials)?;
                    v.push(MaterialMorphOffset {
                        material,
                        operation: r.u8()?,
                        diffuse: r.vec4()?,
                        specular: r.vec3()?,
                        specular_power: r.f32()?,
                        ambient: r.vec3()?,
                        edge_colour: r.vec4()?,
                        edge_size: r.f32()?,
                        texture_tint: r.vec4()?,
                        sphere_tint: r.vec4()?,
                        toon_tint: r.vec4()?,
                    });
                }
                MorphData::Material(v)
            }
            _ => {
                let mut v = Vec::with_capacity(n);
                for _ in 0..n {
                    impulse_refs.push((m, r.index(gl.rigid)?));
                    v.push(ImpulseMorphOffset { rigid_body: 0, local: r.u8()? != 0, velocity: r.vec3()?, torque: r.vec3()? });
                }
                MorphData::Impulse(v)
            }
        };
        morphs.push(MmdMorph { name, name_en, panel, data });
    }

    // ---- display frames ----
    r.section("display frames");
    let n = r.count(CountWidth::I32, 13)?;
    let mut display_frames = Vec::with_capacity(n);
    for f in 0..n {
        let name = r.pmx_text(e)?;
        let name_en = r.pmx_text(e)?;
        let special = r.u8()? != 0;
        let k = r.count(CountWidth::I32, 2)?;
        let mut items = Vec::with_capacity(k);
        for _ in 0..k {
            let at = r.pos();
            items.push(match r.u8()? {
                0 => DisplayItem::Bone(check_index(file, "display frame", f, "bone", r.index(gl.bone)?, n_bones)?),
                1 => DisplayItem::Morph(check_index(file, "display frame", f, "morph", r.index(gl.morph)?, n_morphs)?),
                v => return Err(r.bad_value(at, "display item type", i64::from(v), "0 bone, 1 morph")),
            });
        }
        display_frames.push(DisplayFrame { name, name_en, special, items });
    }

    // ---- rigid bodies ----
    r.section("rigid bodies");
    let n_rigid = r.count(CountWidth::I32, 69 + gl.bone)?;
    let mut rigid_bodies = Vec::with_capacity(n_rigid);
    for b in 0..n_rigid {
        let name = r.pmx_text(e)?;
        let name_en = r.pmx_text(e)?;
        let bone = check_optional_index(file, "rigid body", b, "bone", r.index(gl.bone)?, n_bones)?;
        rigid_bodies.push(MmdRigidBody {
            name,
            name_en,
            bone,
            group: r.u8()?,
            no_collision_mask: r.u16()?,
            shape: rigid_shape(&mut r)?,
            size: r.vec3()?,
            position: r.vec3()?,
            rotation_rad: r.vec3()?,
            mass: r.f32()?,
            linear_damping: r.f32()?,
            angular_damping: r.f32()?,
            restitution: r.f32()?,
            friction: r.f32()?,
            mode: rigid_mode(&mut r)?,
        });
    }
    let mut impulses = impulse_refs.into_iter();
    for (m, morph) in morphs.iter_mut().enumerate() {
        if let MorphData::Impulse(v) = &mut morph.data {
            for o in v {
                let (_, idx) = impulses.next().unwrap_or((m, -1));
                o.rigid_body = check_index(file, "morph", m, "rigid body", idx, n_rigid)?;
            }
        }
    }

    // ---- joints ----
    r.section("joints");
    let n = r.count(CountWidth::I32, 105 + 2 * gl.rigid)?;
    let mut joints = Vec::with_capacity(n);
    for j in 0..n {
        let name = r.pmx_text(e)?;
        let name_en = r.pmx_text(e)?;
        let at = r.pos();
        let kind = r.u8()?;
        if kind > 5 {
            return Err(r.bad_value(at, "joint type", i64::from(kind), "0–5"));
        }
        let rigid_a = check_index(file, "joint", j, "rigid body A", r.index(gl.rigid)?, n_rigid)?;
        let rigid_b = check_index(file, "joint", j, "rigid body B", r.index(gl.rigid)?, n_rigid)?;
        joints.push(r.joint_tail(name, name_en, kind, rigid_a, rigid_b)?);
    }

    // ---- soft bodies (2.1) ----
    let mut soft_bodies = Vec::new();
    r.section("soft bodies");
    if version == 2.1 && !r.at_end() {
        let n = r.count(CountWidth::I32, 141 + gl.material)?;
        soft_bodies.reserve_exact(n);
        for s in 0..n {
            let name = r.pmx_text(e)?;
            let name_en = r.pmx_text(e)?;
            let shape = r.u8()?;
            let material = check_optional_index(file, "soft body", s, "material", r.index(gl.material)?, n_materials)?;
            // group, mask, flags, B-link distance, clusters, mass, margin, aero model,
            // 12 config, 6 cluster, 4 iteration, 3 material values: 133 bytes.
            r.skip(1 + 2 + 1 + 4 + 4 + 4 + 4 + 4 + 48 + 24 + 16 + 12)?;
            let anchors = r.count(CountWidth::I32, gl.rigid + gl.vertex + 1)?;
            for _ in 0..anchors {
                check_index(file, "soft body", s, "anchor rigid body", r.index(gl.rigid)?, n_rigid)?;
                check_index(file, "soft body", s, "anchor vertex", r.vertex_index(gl.vertex)?, n_vertices)?;
                r.u8()?;
            }
            let pinned_vertices = r.count(CountWidth::I32, gl.vertex)?;
            for _ in 0..pinned_vertices {
                check_index(file, "soft body", s, "pinned vertex", r.vertex_index(gl.vertex)?, n_vertices)?;
            }
            soft_bodies.push(MmdSoftBody { name, name_en, shape, material, anchors, pinned_vertices });
        }
    }

    let mut model = MmdModel {
        format: ModelFormat::Pmx { version },
        name,
        name_en,
        comment,
        comment_en,
        vertices,
        additional_uv_count: gl.additional_uvs,
        additional_uvs,
        indices,
        textures,
        materials,
        bones,
        morphs,
        display_frames,
        rigid_bodies,
        joints,
        soft_bodies,
    };
    validate_geometry(file, &mut model)?;
    Ok(model)
}
