//! A small reader of the PMD bone and IK records and VMD bone keys the MMD rig tests and bench
//! need, standing in until the project's own PMD/PMX/VMD readers (branch s10-mmd-parse) land.
//! Names are Shift-JIS (cp932), decoded with encoding_rs.

use glam::{Quat, Vec3};
use odori_core::mmd::{BoneKeys, MmdMotion, PmdBoneRecord, PmdIkRecord, VmdBoneKey};

struct Cursor<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], String> {
        let s = self.b.get(self.at..self.at + n).ok_or_else(|| format!("file ends at byte {} (wanted {n} more)", self.at))?;
        self.at += n;
        Ok(s)
    }
    fn u8(&mut self) -> Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u16(&mut self) -> Result<u16, String> {
        let s = self.take(2)?;
        Ok(u16::from_le_bytes([s[0], s[1]]))
    }
    fn u32(&mut self) -> Result<u32, String> {
        let s = self.take(4)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
    fn f32(&mut self) -> Result<f32, String> {
        Ok(f32::from_bits(self.u32()?))
    }
    fn vec3(&mut self) -> Result<Vec3, String> {
        Ok(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
    fn name(&mut self, n: usize) -> Result<String, String> {
        let s = self.take(n)?;
        let end = s.iter().position(|&c| c == 0).unwrap_or(n);
        Ok(encoding_rs::SHIFT_JIS.decode_without_bom_handling(&s[..end]).0.into_owned())
    }
    fn skip(&mut self, n: usize) -> Result<(), String> {
        self.take(n).map(|_| ())
    }
}

/// PMD: model name, bones and IK records.
pub fn read_pmd(bytes: &[u8]) -> Result<(String, Vec<PmdBoneRecord>, Vec<PmdIkRecord>), String> {
    let mut c = Cursor { b: bytes, at: 0 };
    if c.take(3)? != b"Pmd" {
        return Err("not a PMD file".into());
    }
    c.skip(4)?;
    let name = c.name(20)?;
    c.skip(256)?;
    let vertices = c.u32()? as usize;
    c.skip(vertices * 38)?;
    let faces = c.u32()? as usize;
    c.skip(faces * 2)?;
    let materials = c.u32()? as usize;
    c.skip(materials * 70)?;
    let nb = c.u16()? as usize;
    let mut bones = Vec::with_capacity(nb);
    for _ in 0..nb {
        let name = c.name(20)?;
        let parent = c.u16()?;
        c.skip(2 + 1 + 2)?;
        let position = c.vec3()?;
        bones.push(PmdBoneRecord { name, parent: (parent != 0xFFFF).then_some(parent as usize), position });
    }
    let ni = c.u16()? as usize;
    let mut iks = Vec::with_capacity(ni);
    for _ in 0..ni {
        let ik_bone = c.u16()? as usize;
        let effector = c.u16()? as usize;
        let len = c.u8()? as usize;
        let iterations = c.u16()?;
        let control_weight = c.f32()?;
        let links = (0..len).map(|_| c.u16().map(|v| v as usize)).collect::<Result<Vec<_>, _>>()?;
        iks.push(PmdIkRecord { ik_bone, effector, iterations, control_weight, links });
    }
    Ok((name, bones, iks))
}

/// VMD: model name and bone keys, grouped by bone in file order.
pub fn read_vmd(bytes: &[u8]) -> Result<MmdMotion, String> {
    let mut c = Cursor { b: bytes, at: 0 };
    let header = c.take(30)?;
    let model_name = if header.starts_with(b"Vocaloid Motion Data 0002") {
        c.name(20)?
    } else if header.starts_with(b"Vocaloid Motion Data file") {
        c.name(10)?
    } else {
        return Err("not a VMD file".into());
    };
    let n = c.u32()? as usize;
    let mut bones: Vec<BoneKeys> = Vec::new();
    let mut index = std::collections::HashMap::new();
    for _ in 0..n {
        let name = c.name(15)?;
        let frame = c.u32()?;
        let translation = c.vec3()?;
        let rotation = Quat::from_xyzw(c.f32()?, c.f32()?, c.f32()?, c.f32()?);
        let mut block = [0u8; 64];
        block.copy_from_slice(c.take(64)?);
        let key = VmdBoneKey { frame, translation, rotation, curves: VmdBoneKey::curves_from_vmd(&block) };
        let at = *index.entry(name.clone()).or_insert_with(|| {
            bones.push(BoneKeys { bone: name, keys: Vec::new() });
            bones.len() - 1
        });
        bones[at].keys.push(key);
    }
    Ok(MmdMotion { model_name, bones })
}
