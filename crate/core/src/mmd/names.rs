//! MMD's standard bone names (Japanese) read as the English body words the humanoid mapping
//! knows, so an MMD rig maps onto the canonical humanoid by name like a Mixamo or VRM rig.
//!
//! 下半身 (lower body, the legs hang from it) is the hips; 上半身 the spine; 上半身2 the chest
//! (rigs without it get their chest where the arms branch, 上半身); 腕捩 / 手捩 (twist bones),
//! IK bones and the D/EX bones of PMX rigs take no canonical joint.

/// The English name the humanoid mapping reads for a standard MMD bone name, if it is one.
pub fn english_alias(name: &str) -> Option<&'static str> {
    let (side, rest) = if let Some(r) = name.strip_prefix('左') {
        ("Left", r)
    } else if let Some(r) = name.strip_prefix('右') {
        ("Right", r)
    } else {
        ("", name)
    };
    let centre = match rest {
        "下半身" => Some("Hips"),
        "上半身" => Some("Spine"),
        "上半身2" | "上半身２" => Some("Chest"),
        "首" => Some("Neck"),
        "頭" => Some("Head"),
        _ => None,
    };
    if side.is_empty() {
        return centre;
    }
    let left = side == "Left";
    Some(match rest {
        "肩" => if left { "LeftShoulder" } else { "RightShoulder" },
        "腕" => if left { "LeftUpperArm" } else { "RightUpperArm" },
        "ひじ" | "肘" => if left { "LeftForeArm" } else { "RightForeArm" },
        "手首" => if left { "LeftHand" } else { "RightHand" },
        "足" => if left { "LeftUpLeg" } else { "RightUpLeg" },
        "ひざ" | "膝" => if left { "LeftLeg" } else { "RightLeg" },
        "足首" => if left { "LeftFoot" } else { "RightFoot" },
        "つま先" => if left { "LeftToeBase" } else { "RightToeBase" },
        _ => return None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_names_read_as_body_words() {
        assert_eq!(english_alias("左ひじ"), Some("LeftForeArm"));
        assert_eq!(english_alias("右足"), Some("RightUpLeg"));
        assert_eq!(english_alias("下半身"), Some("Hips"));
        assert_eq!(english_alias("左足ＩＫ"), None);
        assert_eq!(english_alias("左腕捩"), None);
        assert_eq!(english_alias("センター"), None);
        assert_eq!(english_alias("左"), None);
    }
}
