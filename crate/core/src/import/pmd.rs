//! PMD 1.0 reader: MikuMikuDance's original model format (the bundled 初音ミク Ver2 is one),
//! with the optional English-name, toon-texture, rigid-body and joint extensions when present.
//!
//! The result is the [`MmdModel`] PMX also gives, so the rig and the renderer see one model
//! type. Where PMD means something PMX says differently, the reader brings it to PMX's meaning
//! and says so on the field: bone types become flags and grants, morphs index the model's
//! vertices (not the base morph's list), rigid bodies are placed in model space, and knee links
//! (ひざ) get the one-way limit MMD applies to PMD knees.

use glam::Vec3;

use super::mmd_bytes::{check_index, CountWidth, MmdError, Reader};
use super::mmd_model::*;

/// "Pmd" then a little-endian f32 version (1.0).
pub const MAGIC: &[u8] = b"Pmd";

const VERTEX_BYTES: usize = 38;
const MATERIAL_BYTES: usize = 70;
const BONE_BYTES: usize = 39;
const IK_MIN_BYTES: usize = 11;
const MORPH_MIN_BYTES: usize = 25;
const RIGID_BYTES: usize = 83;
const JOINT_BYTES: usize = 124;
/// PMD's "no bone" index.
const NONE16: u16 = 0xFFFF;

/// Reads a PMD file.
pub fn read(file: &str, bytes: &[u8]) -> Result<MmdModel, MmdError> {
    let mut r = Reader::new(file, bytes);
    if !bytes.starts_with(MAGIC) {
        return Err(MmdError::BadMagic { file: file.to_string(), expected: "PMD model", found: super::mmd_bytes::printable_start(bytes, 8) });
    }
    r.skip(3)?;
    let version = r.f32()?;
    if version != 1.0 {
        return Err(MmdError::BadVersion { file: file.to_string(), format: "PMD", version: version.to_string(), supported: "1.0" });
    }
    let name = r.sjis(20)?;
    let comment = r.sjis(256)?;

    r.section("vertices");
    let n = r.count(CountWidth::U32, VERTEX_BYTES)?;
    let mut vertices = Vec::with_capacity(n);
    for _ in 0..n {
        let position = r.vec3()?;
        let normal = r.vec3()?;
        let uv = r.vec2()?;
        let b0 = r.u16()?;
        let b1 = r.u16()?;
        let w = f32::from(r.u8()?) / 100.0;
        let edge_off = r.u8()? != 0;
        vertices.push(MmdVertex {
            position,
            normal,
            uv,
            skin: Skin { kind: SkinKind::Bdef2, bones: [u32::from(b0), u32::from(b1), 0, 0], weights: [w, 1.0 - w, 0.0, 0.0], sdef: None },
            edge_scale: if edge_off { 0.0 } else { 1.0 },
        });
    }

    r.section("faces");
    let n = r.count(CountWidth::U32, 2)?;
    let mut indices = Vec::with_capacity(n);
    for _ in 0..n {
        indices.push(u32::from(r.u16()?));
    }

    r.section("materials");
    let n = r.count(CountWidth::U32, MATERIAL_BYTES)?;
    let mut textures: Vec<String> = Vec::new();
    let mut materials = Vec::with_capacity(n);
    let mut toon_indices = Vec::with_capacity(n);
    for i in 0..n {
        let diffuse = r.vec3()?.extend(r.f32()?);
        let specular_power = r.f32()?;
        let specular = r.vec3()?;
        let ambient = r.vec3()?;
        toon_indices.push(r.u8()?);
        let edge = r.u8()? != 0;
        let index_count = r.u32()?;
        let tex_field = r.sjis(20)?;
        let (mut texture, mut sphere, mut sphere_mode) = (None, None, SphereMode::None);
        for part in tex_field.split('*').map(str::trim).filter(|p| !p.is_empty()) {
            let lower = part.to_lowercase();
            let idx = intern(&mut textures, part);
            if lower.ends_with(".sph") {
                (sphere, sphere_mode) = (Some(idx), SphereMode::Multiply);
            } else if lower.ends_with(".spa") {
                (sphere, sphere_mode) = (Some(idx), SphereMode::Add);
            } else {
                texture = Some(idx);
            }
        }
        use material_flags::*;
        let mut flags = GROUND_SHADOW | CASTS_SELF_SHADOW | RECEIVES_SELF_SHADOW;
        if edge {
            flags |= EDGE;
        }
        if diffuse.w < 1.0 {
            flags |= DOUBLE_SIDED;
        }
        materials.push(MmdMaterial {
            name: format!("material {i}"),
            name_en: String::new(),
            diffuse,
            specular,
            specular_power,
            ambient,
            flags,
            edge_colour: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
            edge_size: 1.0,
            texture,
            sphere,
            sphere_mode,
            toon: Toon::None,
            memo: String::new(),
            index_count,
        });
    }

    r.section("bones");
    let n_bones = r.count(CountWidth::U16, BONE_BYTES)?;
    let mut bones = Vec::with_capacity(n_bones);
    let mut raw_links = Vec::with_capacity(n_bones);
    for _ in 0..n_bones {
        let name = r.sjis(20)?;
        let parent = r.u16()?;
        let tail = r.u16()?;
        let at = r.pos();
        let kind = r.u8()?;
        if kind > 9 {
            return Err(r.bad_value(at, "bone type", i64::from(kind), "0–9"));
        }
        let ik_field = r.u16()?;
        let position = r.vec3()?;
        raw_links.push((parent, tail, ik_field));
        bones.push(MmdBone {
            name,
            name_en: String::new(),
            position,
            parent: None,
            layer: 0,
            flags: 0,
            tail: BoneTail::Bone(None),
            grant: None,
            fixed_axis: None,
            local_axes: None,
            external_parent_key: None,
            ik: None,
            pmd_type: Some(kind),
        });
    }
    // Links, flags and grants, now that every bone is known.
    for i in 0..n_bones {
        let (parent, tail, ik_field) = raw_links[i];
        let kind = bones[i].pmd_type.unwrap_or(0);
        let opt = |v: u16, what: &'static str| -> Result<Option<usize>, MmdError> {
            if v == NONE16 {
                Ok(None)
            } else {
                check_index(file, "bone", i, what, i64::from(v), n_bones).map(Some)
            }
        };
        let parent = opt(parent, "parent")?;
        use bone_flags::*;
        let mut flags = ROTATABLE | VISIBLE | ENABLED | TAIL_IS_BONE;
        // Type 9 (回転連動) keeps its grant parent where the tail index would be and its ratio
        // (signed percent) in the IK field; a tail of 0 (the root) means none.
        let tail = if kind == 9 || tail == 0 { None } else { opt(tail, "tail")? };
        let mut grant = None;
        let mut fixed_axis = None;
        match kind {
            1 => flags |= TRANSLATABLE,
            2 => flags |= TRANSLATABLE,
            5 | 9 => {
                // Type 5 (回転影響下): the whole rotation of the bone in the IK field.
                let (source, ratio) = if kind == 5 { (ik_field, 1.0) } else { (raw_links[i].1, f32::from(ik_field as i16) / 100.0) };
                let parent = check_index(file, "bone", i, "grant parent", i64::from(source), n_bones)?;
                grant = Some(Grant { parent, ratio, rotation: true, translation: false, local: false });
                flags |= GRANT_ROTATION;
                if kind == 9 {
                    flags &= !VISIBLE;
                }
            }
            6 | 7 => flags &= !VISIBLE,
            8 => {
                flags |= FIXED_AXIS;
                let axis = tail.map(|t| bones[t].position - bones[i].position).and_then(|d| d.try_normalize());
                fixed_axis = Some(axis.unwrap_or(Vec3::X));
            }
            _ => {}
        }
        let b = &mut bones[i];
        b.parent = parent;
        b.flags = flags;
        b.tail = BoneTail::Bone(tail);
        b.grant = grant;
        b.fixed_axis = fixed_axis;
    }

    r.section("IK chains");
    let n = r.count(CountWidth::U16, IK_MIN_BYTES)?;
    for e in 0..n {
        let ik_bone = check_index(file, "IK chain", e, "IK bone", i64::from(r.u16()?), n_bones)?;
        let target = check_index(file, "IK chain", e, "target", i64::from(r.u16()?), n_bones)?;
        let len = r.u8()?;
        let loop_count = u32::from(r.u16()?);
        // PMD stores the per-step limit in units of 4 radians (three.js and MMD multiply by 4).
        let limit_angle_rad = r.f32()? * 4.0;
        let mut links = Vec::with_capacity(usize::from(len));
        for _ in 0..len {
            let bone = check_index(file, "IK chain", e, "link", i64::from(r.u16()?), n_bones)?;
            // MMD bends PMD knees one way only: about X, between −180° and −0.5° (the
            // limits PMX Editor writes when it converts a PMD).
            let limits = bones[bone].name.contains("ひざ").then(|| (Vec3::new(-std::f32::consts::PI, 0.0, 0.0), Vec3::new(-0.5f32.to_radians(), 0.0, 0.0)));
            links.push(IkLink { bone, limits });
        }
        bones[ik_bone].flags |= bone_flags::IK | bone_flags::TRANSLATABLE;
        bones[ik_bone].ik = Some(Ik { target, loop_count, limit_angle_rad, links });
    }

    r.section("morphs");
    let n_skins = r.count(CountWidth::U16, MORPH_MIN_BYTES)?;
    let mut base: Option<Vec<usize>> = None;
    let mut morphs = Vec::with_capacity(n_skins);
    // PMD skin index → morph index (the base is not a morph).
    let mut skin_to_morph = Vec::with_capacity(n_skins);
    for e in 0..n_skins {
        let name = r.sjis(20)?;
        let count = r.count(CountWidth::U32, 0)?;
        let at = r.pos();
        let panel = r.u8()?;
        if panel > 4 {
            return Err(r.bad_value(at, "morph panel", i64::from(panel), "0–4"));
        }
        let count = {
            // 16 bytes per offset must fit.
            if count.checked_mul(16).is_none_or(|b| b > r.remaining()) {
                return Err(MmdError::CountTooLarge {
                    file: file.to_string(),
                    section: "morphs".into(),
                    offset: at - 4,
                    count: count as i64,
                    min_entry_bytes: 16,
                    available: r.remaining(),
                });
            }
            count
        };
        let mut list = Vec::with_capacity(count);
        for _ in 0..count {
            list.push((r.u32()?, r.vec3()?));
        }
        if panel == 0 {
            let mut verts = Vec::with_capacity(count);
            for &(v, _) in &list {
                verts.push(check_index(file, "morph", e, "base vertex", i64::from(v), vertices.len())?);
            }
            base = Some(verts);
            skin_to_morph.push(None);
            continue;
        }
        let base_list = base.as_deref().unwrap_or(&[]);
        let mut offsets = Vec::with_capacity(count);
        for (i, d) in list {
            let b = check_index(file, "morph", e, "base entry", i64::from(i), base_list.len())?;
            offsets.push((base_list[b], d));
        }
        skin_to_morph.push(Some(morphs.len()));
        morphs.push(MmdMorph { name, name_en: String::new(), panel, data: MorphData::Vertex(offsets) });
    }

    r.section("morph display list");
    let n = r.count(CountWidth::U8, 2)?;
    let mut morph_frame = DisplayFrame { name: "表情".into(), name_en: "Exp".into(), special: true, items: Vec::new() };
    for _ in 0..n {
        let s = check_index(file, "display frame", 0, "morph", i64::from(r.u16()?), n_skins)?;
        if let Some(m) = skin_to_morph[s] {
            morph_frame.items.push(DisplayItem::Morph(m));
        }
    }
    r.section("bone display frame names");
    let n_frames = r.count(CountWidth::U8, 50)?;
    let mut frames = vec![morph_frame];
    for _ in 0..n_frames {
        let name = r.sjis(50)?.trim_end().to_string();
        frames.push(DisplayFrame { name, name_en: String::new(), special: false, items: Vec::new() });
    }
    r.section("bone display list");
    let n = r.count(CountWidth::U32, 3)?;
    for e in 0..n {
        let bone = check_index(file, "bone display entry", e, "bone", i64::from(r.u16()?), n_bones)?;
        let f = check_index(file, "bone display entry", e, "frame", i64::from(r.u8()?), n_frames + 1)?;
        if f == 0 {
            return Err(MmdError::IndexOutOfRange { file: file.to_string(), section: "bone display entry", entry: e, what: "frame", index: 0, count: n_frames + 1 });
        }
        frames[f].items.push(DisplayItem::Bone(bone));
    }

    let mut model = MmdModel {
        format: ModelFormat::Pmd,
        name,
        name_en: String::new(),
        comment,
        comment_en: String::new(),
        vertices,
        additional_uv_count: 0,
        additional_uvs: Vec::new(),
        indices,
        textures,
        materials,
        bones,
        morphs,
        display_frames: frames,
        rigid_bodies: Vec::new(),
        joints: Vec::new(),
        soft_bodies: Vec::new(),
    };

    // Extensions: each present only if the file goes on.
    r.section("English names");
    if !r.at_end() {
        if r.u8()? != 0 {
            model.name_en = r.sjis(20)?;
            model.comment_en = r.sjis(256)?;
            for b in &mut model.bones {
                b.name_en = r.sjis(20)?;
            }
            for m in &mut model.morphs {
                m.name_en = r.sjis(20)?;
            }
            for f in model.display_frames.iter_mut().skip(1) {
                f.name_en = r.sjis(50)?.trim_end().to_string();
            }
        }
    }
    r.section("toon textures");
    let mut toon_names: Option<Vec<String>> = None;
    if !r.at_end() {
        let mut names = Vec::with_capacity(10);
        for _ in 0..10 {
            names.push(r.sjis(100)?);
        }
        toon_names = Some(names);
    }
    for (m, &t) in model.materials.iter_mut().zip(&toon_indices) {
        m.toon = match t {
            0..=9 => {
                let default = format!("toon{:02}.bmp", t + 1);
                match toon_names.as_ref().map(|n| n[usize::from(t)].trim()) {
                    Some(name) if !name.is_empty() && !name.eq_ignore_ascii_case(&default) => Toon::Texture(intern(&mut model.textures, name)),
                    _ => Toon::Shared(t),
                }
            }
            _ => Toon::None,
        };
    }

    r.section("rigid bodies");
    if !r.at_end() {
        let n = r.count(CountWidth::U32, RIGID_BYTES)?;
        model.rigid_bodies.reserve_exact(n);
        for e in 0..n {
            // Some files pad these names with a newline (miku_v2's rigid bodies start with one).
            let name = r.sjis(20)?.trim().to_string();
            let bone_raw = r.u16()?;
            let bone = if bone_raw == NONE16 { None } else { Some(check_index(file, "rigid body", e, "bone", i64::from(bone_raw), n_bones)?) };
            let group = r.u8()?;
            let no_collision_mask = r.u16()?;
            let shape = rigid_shape(&mut r)?;
            let size = r.vec3()?;
            // Relative to its bone in PMD (bone 0 when it names none, as MMD does).
            let relative = r.vec3()?;
            let origin = bone.or((!model.bones.is_empty()).then_some(0)).map_or(Vec3::ZERO, |b| model.bones[b].position);
            let rotation_rad = r.vec3()?;
            let mass = r.f32()?;
            let linear_damping = r.f32()?;
            let angular_damping = r.f32()?;
            let restitution = r.f32()?;
            let friction = r.f32()?;
            let mode = rigid_mode(&mut r)?;
            model.rigid_bodies.push(MmdRigidBody {
                name,
                name_en: String::new(),
                bone,
                group,
                no_collision_mask,
                shape,
                size,
                position: origin + relative,
                rotation_rad,
                mass,
                linear_damping,
                angular_damping,
                restitution,
                friction,
                mode,
            });
        }
    }
    r.section("joints");
    if !r.at_end() {
        let n = r.count(CountWidth::U32, JOINT_BYTES)?;
        let n_rigid = model.rigid_bodies.len();
        model.joints.reserve_exact(n);
        for e in 0..n {
            let name = r.sjis(20)?.trim().to_string();
            let rigid_a = check_index(file, "joint", e, "rigid body A", i64::from(r.u32()?), n_rigid)?;
            let rigid_b = check_index(file, "joint", e, "rigid body B", i64::from(r.u32()?), n_rigid)?;
            model.joints.push(r.joint_tail(name, String::new(), 0, rigid_a, rigid_b)?);
        }
    }
    validate_geometry(file, &mut model)?;
    Ok(model)
}

/// A texture name's index in `textures`, added if new (PMD names textures per material).
fn intern(textures: &mut Vec<String>, name: &str) -> usize {
    match textures.iter().position(|t| t == name) {
        Some(i) => i,
        None => {
            textures.push(name.to_string());
            textures.len() - 1
        }
    }
}

pub(crate) fn rigid_shape(r: &mut Reader) -> Result<RigidShape, MmdError> {
    let at = r.pos();
    Ok(match r.u8()? {
        0 => RigidShape::Sphere,
        1 => RigidShape::Box,
        2 => RigidShape::Capsule,
        v => return Err(r.bad_value(at, "rigid body shape", i64::from(v), "0 sphere, 1 box, 2 capsule")),
    })
}

pub(crate) fn rigid_mode(r: &mut Reader) -> Result<RigidMode, MmdError> {
    let at = r.pos();
    Ok(match r.u8()? {
        0 => RigidMode::FollowBone,
        1 => RigidMode::Physics,
        2 => RigidMode::PhysicsWithBone,
        v => return Err(r.bad_value(at, "rigid body mode", i64::from(v), "0 bone, 1 physics, 2 physics + bone")),
    })
}

/// Checks shared by PMD and PMX once everything is read: triangle indices name vertices,
/// vertex skins name bones, the materials' index runs fit in the index list. A skin slot of
/// weight 0 that names no bone (PMD files write garbage there) is set to bone 0, so every
/// bone index a consumer meets is in range.
pub(crate) fn validate_geometry(file: &str, m: &mut MmdModel) -> Result<(), MmdError> {
    let nv = m.vertices.len();
    if let Some((i, &v)) = m.indices.iter().enumerate().find(|(_, &v)| v as usize >= nv) {
        return Err(MmdError::IndexOutOfRange { file: file.to_string(), section: "face index", entry: i, what: "vertex", index: i64::from(v), count: nv });
    }
    let nb = m.bones.len();
    for (i, v) in m.vertices.iter_mut().enumerate() {
        for (b, &w) in v.skin.bones.iter_mut().zip(&v.skin.weights) {
            if *b as usize >= nb {
                if w != 0.0 {
                    return Err(MmdError::IndexOutOfRange { file: file.to_string(), section: "vertex", entry: i, what: "bone", index: i64::from(*b), count: nb });
                }
                *b = 0;
            }
        }
    }
    if m.indices.len() % 3 != 0 {
        return Err(MmdError::BadValue {
            file: file.to_string(),
            section: "faces".into(),
            offset: 0,
            what: "number of face indices",
            value: m.indices.len() as i64,
            allowed: "a multiple of 3 (triangles)",
        });
    }
    let total: u64 = m.materials.iter().map(|x| u64::from(x.index_count)).sum();
    if total > m.indices.len() as u64 {
        return Err(MmdError::BadValue {
            file: file.to_string(),
            section: "materials".into(),
            offset: 0,
            what: "sum of the materials' index counts",
            value: total as i64,
            allowed: "at most the number of face indices",
        });
    }
    Ok(())
}
