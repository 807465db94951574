//! The MMD readers against an implementation no one here wrote: `mmd-anim-format` (MIT, the
//! parser behind yohawing's three-mmd-loader and unity-mmd-loader), used only as a test
//! reference. On the real files, key by key and bone by bone: VMD bone keys (name, frame,
//! translation, rotation, the interpolation parameter row) and morph keys; PMX and PMD bones
//! (name, parent, position, grant, IK target, loops, links and limits), the triangle list,
//! vertex positions and skins, material texture paths, morph and rigid body names.

use odori_core::import::mmd_model::{self, BoneTail, MmdModel, Toon};
use odori_core::import::vmd;
use odori_tests::read;

fn ours(rel: &str) -> MmdModel {
    mmd_model::read_model(rel, &read(rel)).unwrap_or_else(|e| panic!("{e}"))
}

fn opt(i: i32) -> Option<usize> {
    usize::try_from(i).ok()
}

#[test]
fn vmd_keys_agree_with_mmd_anim_format() {
    for rel in ["mmd/motion/wavefile_v2.vmd", "mmd/motion/tokino_kakera.vmd", "mmd/motion/tokino_kakera_cam.vmd"] {
        let bytes = read(rel);
        let a = vmd::read(rel, &bytes).unwrap();
        let b = mmd_anim_format::parse_vmd_animation(&bytes).unwrap_or_else(|e| panic!("{rel}: reference: {e}"));
        assert_eq!(a.model_name, b.metadata.model_name);
        assert_eq!(a.bone_keys.len(), b.bone_frames.len(), "{rel}");
        for (x, y) in a.bone_keys.iter().zip(&b.bone_frames) {
            assert_eq!((x.name.as_str(), x.frame), (y.bone_name.as_str(), y.frame), "{rel}");
            assert_eq!(x.translation.to_array(), y.translation);
            assert_eq!(x.rotation.to_array(), y.rotation);
            assert_eq!(&x.curves.to_block()[..16], &y.interpolation[..16], "{rel}: {} frame {}", x.name, x.frame);
        }
        assert_eq!(a.morph_keys.len(), b.morph_frames.len());
        for (x, y) in a.morph_keys.iter().zip(&b.morph_frames) {
            assert_eq!((x.name.as_str(), x.frame, x.weight), (y.morph_name.as_str(), y.frame, y.weight));
        }
        assert_eq!(a.camera_keys.len(), b.camera_frames.len());
        for (x, y) in a.camera_keys.iter().zip(&b.camera_frames) {
            assert_eq!((x.frame, x.distance, x.fov_deg), (y.frame, y.distance, y.fov));
            assert_eq!((x.target.to_array(), x.rotation_rad.to_array()), (y.position, y.rotation));
        }
    }
}

#[test]
fn pmx_agrees_with_mmd_anim_format() {
    let rel = "mmd/gene/Gene_light.pmx";
    let a = ours(rel);
    let b = mmd_anim_format::parse_pmx_model(&read(rel)).unwrap_or_else(|e| panic!("reference: {e}"));
    assert_eq!(a.name, b.metadata.name);
    assert_eq!(a.indices, b.geometry.indices);
    assert_eq!(a.vertices.len() * 3, b.geometry.positions.len());
    for (i, v) in a.vertices.iter().enumerate() {
        assert_eq!(v.position.to_array(), b.geometry.positions[3 * i..3 * i + 3], "vertex {i}");
        assert_eq!(v.edge_scale, b.geometry.edge_scale[i]);
        // The reference keeps four bone slots per vertex; compare the weighted ones.
        for s in 0..4 {
            let w = v.skin.weights[s];
            assert!((w - b.geometry.skin_weights[4 * i + s]).abs() < 1e-6, "vertex {i} slot {s}: {w} vs {}", b.geometry.skin_weights[4 * i + s]);
            if w != 0.0 {
                assert_eq!(v.skin.bones[s], b.geometry.skin_indices[4 * i + s], "vertex {i} slot {s}");
            }
        }
    }
    assert_eq!(a.bones.len(), b.skeleton.bones.len());
    for (x, y) in a.bones.iter().zip(&b.skeleton.bones) {
        assert_eq!(x.name, y.name);
        assert_eq!(x.name_en, y.english_name);
        assert_eq!(x.parent, opt(y.parent_index), "{}", x.name);
        assert_eq!(x.position.to_array(), y.position);
        assert_eq!(x.layer, y.layer);
        match x.tail {
            BoneTail::Bone(t) => assert_eq!(t, opt(y.tail_index), "{}", x.name),
            BoneTail::Offset(o) => assert_eq!(Some(o.to_array()), y.tail_position, "{}", x.name),
        }
        assert_eq!(x.grant.map(|g| (g.parent, g.ratio)), y.append_transform.as_ref().and_then(|t| opt(t.parent_index).map(|p| (p, t.weight))), "{}", x.name);
        assert_eq!(x.fixed_axis.map(|v| v.to_array()), y.fixed_axis);
        assert_eq!(x.ik.is_some(), y.ik.is_some());
        if let (Some(p), Some(q)) = (&x.ik, &y.ik) {
            assert_eq!((Some(p.target), p.loop_count as i32, p.limit_angle_rad), (opt(q.target_index), q.loop_count, q.limit_angle));
            assert_eq!(p.links.len(), q.links.len());
            for (l, m) in p.links.iter().zip(&q.links) {
                assert_eq!(Some(l.bone), opt(m.bone_index));
                assert_eq!(l.limits.map(|(lo, hi)| (lo.to_array(), hi.to_array())), m.limits.as_ref().map(|k| (k.lower, k.upper)));
            }
        }
    }
    assert_eq!(a.materials.len(), b.materials.len());
    for (x, y) in a.materials.iter().zip(&b.materials) {
        assert_eq!(x.name, y.name);
        assert_eq!(x.texture.map(|t| a.textures[t].as_str()).unwrap_or(""), y.texture_path);
        assert_eq!(x.diffuse.to_array(), y.diffuse);
        match x.toon {
            Toon::Shared(s) => assert_eq!(Some(s), y.shared_toon_index),
            Toon::Texture(t) => assert_eq!(a.textures[t], y.toon_texture_path),
            Toon::None => assert!(y.toon_texture_path.is_empty() && y.shared_toon_index.is_none()),
        }
    }
    assert_eq!(a.morphs.iter().map(|m| m.name.as_str()).collect::<Vec<_>>(), b.morphs.iter().map(|m| m.name.as_str()).collect::<Vec<_>>());
    assert_eq!(a.rigid_bodies.iter().map(|r| (r.name.as_str(), r.bone)).collect::<Vec<_>>(), b.rigid_bodies.iter().map(|r| (r.name.as_str(), opt(r.bone_index))).collect::<Vec<_>>());
    assert_eq!(a.joints.len(), b.joints.len());
}

#[test]
fn pmd_agrees_with_mmd_anim_format() {
    for rel in ["mmd/miku_v2/miku_v2.pmd", "mmd/gene/Gene_light.pmd", "mmd/mokou/mokou_A.pmd"] {
        let a = ours(rel);
        let b = mmd_anim_format::parse_pmd_model(&read(rel)).unwrap_or_else(|e| panic!("{rel}: reference: {e}"));
        assert_eq!(a.vertices.len(), b.geometry.vertices.len());
        for (x, y) in a.vertices.iter().zip(&b.geometry.vertices) {
            assert_eq!((x.position.to_array(), x.uv.to_array()), (y.position, y.uv));
            assert_eq!(x.skin.weights[0], f32::from(y.bone_weight) / 100.0);
        }
        assert_eq!(a.indices, b.geometry.indices.iter().map(|&i| u32::from(i)).collect::<Vec<_>>(), "{rel}");
        assert_eq!(a.bones.len(), b.skeleton.bones.len());
        for (x, y) in a.bones.iter().zip(&b.skeleton.bones) {
            assert_eq!((x.name.as_str(), x.parent, x.position.to_array()), (y.name.as_str(), opt(y.parent_index), y.position), "{rel}");
            assert_eq!(x.pmd_type, Some(y.bone_type));
        }
        let ik: Vec<_> = a.ik_bones().map(|(i, ik)| (i, ik.target, ik.loop_count, ik.links.iter().map(|l| l.bone).collect::<Vec<_>>())).collect();
        let mut want: Vec<_> = b.skeleton.ik.iter().map(|k| (usize::from(k.bone_index), usize::from(k.target_bone_index), u32::from(k.loop_count), k.links.iter().map(|&l| usize::from(l)).collect::<Vec<_>>())).collect();
        want.sort_by_key(|w| w.0);
        assert_eq!(ik, want, "{rel}: IK chains");
        assert_eq!(a.rigid_bodies.iter().map(|r| r.name.as_str()).collect::<Vec<_>>(), b.rigid_bodies.iter().map(|r| r.name.as_str()).collect::<Vec<_>>());
        assert_eq!(a.joints.len(), b.joints.len());
    }
}
