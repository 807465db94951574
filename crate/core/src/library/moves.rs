//! The built-in moves: leg and hip patterns, arm patterns and their combinations, at three
//! energy levels and mirrored, authored as key poses on the half count (legs) and quarter count
//! (arms) and interpolated smoothly; the moves held on the counts ([`Step::ON_COUNTS`],
//! [`Arms::ON_COUNTS`]) are keyed on the counts alone, each pose eased into the next. Secondary motion is derived, not keyed: the hips follow the
//! weight onto the supporting foot and drop on the free side, the chest counters the hips, the
//! head steadies against the chest and nods a little after each bounce, the arms trail the body
//! by a fraction of a count and the shoulders lift with the arms.

use crate::fmath;
use std::f32::consts::{FRAC_PI_2, PI, TAU};

use glam::Vec3;
use serde::{Deserialize, Serialize};

use super::pose::KeyPose;
// Smoothstep 0..1: the motion kernel's one easing curve.
use crate::motion::smoothstep as smooth01;
use crate::motion::smootherstep as smoother01;

/// A leg, hip and torso pattern (the "step").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum Step {
    StepTouch,
    Grapevine,
    BoxStep,
    KickBallChange,
    Chasse,
    PivotTurn,
    Jump,
    Bounce,
    HipSway,
    BodyRoll,
    /// The forward half of the waltz box: forward, side, close (one bar of 3).
    WaltzBoxForward,
    /// The back half of the waltz box: back, side, close (one bar of 3).
    WaltzBoxBack,
    /// Balancé: step to the side, rise onto the ball behind, step in place (one bar of 3).
    Balance,
    /// A waltz turn: step, side, close while turning half round (one bar of 3).
    WaltzTurn,
    /// Hesitation: one step taken, then held for two counts while the free foot draws in.
    Hesitation,
    /// Step-touch held on the counts: one foot steps out on each count, the other touches in.
    SideTouch,
    /// The grapevine's count steps (side, behind, side, touch), held on the counts.
    SlowGrapevine,
    /// The box step's count steps, held on the counts (no hip turn).
    SlowBox,
    /// A sway of the weight from foot to foot, on the counts, the feet in place.
    Sway,
}

impl Step {
    pub const ALL: [Step; 10] = [
        Step::StepTouch,
        Step::Grapevine,
        Step::BoxStep,
        Step::KickBallChange,
        Step::Chasse,
        Step::PivotTurn,
        Step::Jump,
        Step::Bounce,
        Step::HipSway,
        Step::BodyRoll,
    ];

    /// The steps in 3 (one bar of 3/4 each).
    pub const THREE: [Step; 5] = [Step::WaltzBoxForward, Step::WaltzBoxBack, Step::Balance, Step::WaltzTurn, Step::Hesitation];

    /// The steps in 4 held on the counts: keyed only on the counts, each count's pose eased
    /// into the next, so every joint comes to rest on the count (one kinetic beat a count at
    /// any tempo, where the steps keyed on the half count turn on the "and" when played slowly).
    pub const ON_COUNTS: [Step; 4] = [Step::SideTouch, Step::SlowGrapevine, Step::SlowBox, Step::Sway];

    /// Keyed on the counts only ([`Step::ON_COUNTS`]).
    pub fn on_counts(self) -> bool {
        Step::ON_COUNTS.contains(&self)
    }

    /// Counts of one bar of the step: 3 for the steps in 3, else 4.
    pub fn counts(self) -> usize {
        if Step::THREE.contains(&self) {
            3
        } else {
            4
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Step::WaltzBoxForward => "waltz box (forward)",
            Step::WaltzBoxBack => "waltz box (back)",
            Step::Balance => "balancé",
            Step::WaltzTurn => "waltz turn",
            Step::Hesitation => "hesitation",
            Step::StepTouch => "step-touch",
            Step::Grapevine => "grapevine",
            Step::BoxStep => "box step",
            Step::KickBallChange => "kick-ball-change",
            Step::Chasse => "chassé",
            Step::PivotTurn => "pivot turn",
            Step::Jump => "jump",
            Step::Bounce => "bounce",
            Step::HipSway => "hip sway",
            Step::BodyRoll => "body roll",
            Step::SideTouch => "side touch",
            Step::SlowGrapevine => "slow grapevine",
            Step::SlowBox => "slow box",
            Step::Sway => "sway",
        }
    }
}

/// An arm pattern.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum Arms {
    Swing,
    Waves,
    Punches,
    Claps,
    ArmRolls,
    OverheadReaches,
    ArmWave,
    /// Arms held in a ballroom frame, rising and falling with the bar (in 3).
    Frame,
    /// Port de bras: one arm sweeps from the front up overhead and opens to the side (in 3).
    PortDeBras,
    /// Both arms open from low in front to wide at shoulder height and close again (in 3).
    OpenArms,
    /// Presses held on the counts: both hands press to the front, draw to the chest, press
    /// overhead and draw to the chest again (in 4).
    Presses,
    /// Both arms close low in front and open wide on alternate counts (in 4, on the counts).
    OpenClose,
}

impl Arms {
    pub const ALL: [Arms; 7] = [Arms::Swing, Arms::Waves, Arms::Punches, Arms::Claps, Arms::ArmRolls, Arms::OverheadReaches, Arms::ArmWave];

    /// The arm patterns of the steps in 3 (each one bar of 3 counts, ending where it began).
    pub const THREE: [Arms; 3] = [Arms::Frame, Arms::PortDeBras, Arms::OpenArms];

    /// The arm patterns of the steps held on the counts (one bar of 4, a pose on each count).
    pub const ON_COUNTS: [Arms; 2] = [Arms::Presses, Arms::OpenClose];

    pub fn name(self) -> &'static str {
        match self {
            Arms::Frame => "waltz frame",
            Arms::PortDeBras => "port de bras",
            Arms::OpenArms => "open arms",
            Arms::Presses => "presses",
            Arms::OpenClose => "open and close",
            Arms::Swing => "arm swing",
            Arms::Waves => "waves",
            Arms::Punches => "punches",
            Arms::Claps => "claps",
            Arms::ArmRolls => "arm rolls",
            Arms::OverheadReaches => "overhead reaches",
            Arms::ArmWave => "arm wave",
        }
    }
}

/// Energy level: how big, deep and sharp the move is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum Energy {
    Low,
    Medium,
    High,
}

impl Energy {
    pub const ALL: [Energy; 3] = [Energy::Low, Energy::Medium, Energy::High];

    /// Amplitude factor.
    pub fn amplitude(self) -> f32 {
        match self {
            Energy::Low => 0.6,
            Energy::Medium => 1.0,
            Energy::High => 1.35,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Energy::Low => "low",
            Energy::Medium => "medium",
            Energy::High => "high",
        }
    }
}

/// One leg key: ankle targets (x, lift, z), weight on the left foot (0..1), hips drop, hips yaw,
/// and torso bends for the moves that key them.
#[derive(Clone, Copy, Debug, Default)]
struct LegKey {
    l: Vec3,
    r: Vec3,
    w_left: f32,
    drop: f32,
    yaw: f32,
    torso: [f32; 4], // hips pitch, spine pitch, chest pitch, hips x push
}

fn lk(l: [f32; 3], r: [f32; 3], w_left: f32, drop: f32) -> LegKey {
    LegKey { l: Vec3::from(l), r: Vec3::from(r), w_left, drop, yaw: 0.0, torso: [0.0; 4] }
}

/// Half-count keys (2 per count and the next bar's one: 9 for a step in 4, 7 for one in 3), or
/// count keys (5) for a step held on the counts, of each step, for the figure's right side leading (mirroring gives the left-leading version).
fn leg_keys(step: Step) -> Vec<LegKey> {
    if step.on_counts() {
        leg_keys_on_counts(step)
    } else if step.counts() == 3 {
        leg_keys_in_three(step)
    } else {
        leg_keys_in_four(step)
    }
}

/// Half-count keys (9: counts 1, &, 2, &, 3, &, 4, &, next 1) of each step in 4.
fn leg_keys_in_four(step: Step) -> Vec<LegKey> {
    match step {
        Step::WaltzBoxForward | Step::WaltzBoxBack | Step::Balance | Step::WaltzTurn | Step::Hesitation => leg_keys_in_three(step),
        Step::SideTouch | Step::SlowGrapevine | Step::SlowBox | Step::Sway => leg_keys_on_counts(step),
        Step::StepTouch => vec![
            lk([0.25, 0.0, 0.0], [-0.25, 0.0, 0.0], 0.3, -0.07),
            lk([0.09, 0.07, 0.0], [-0.25, 0.0, 0.0], 0.0, -0.02),
            lk([-0.07, 0.0, 0.03], [-0.25, 0.0, 0.0], 0.0, -0.08),
            lk([0.09, 0.07, 0.0], [-0.25, 0.0, 0.0], 0.0, -0.02),
            lk([0.25, 0.0, 0.0], [-0.25, 0.0, 0.0], 0.7, -0.07),
            lk([0.25, 0.0, 0.0], [-0.09, 0.07, 0.0], 1.0, -0.02),
            lk([0.25, 0.0, 0.0], [0.07, 0.0, 0.03], 1.0, -0.08),
            lk([0.25, 0.0, 0.0], [-0.09, 0.07, 0.0], 1.0, -0.02),
            lk([0.25, 0.0, 0.0], [-0.25, 0.0, 0.0], 0.3, -0.07),
        ],
        Step::Grapevine => vec![
            lk([0.12, 0.0, 0.0], [-0.3, 0.0, 0.0], 0.3, -0.06),
            lk([-0.1, 0.06, -0.1], [-0.3, 0.0, 0.0], 0.0, -0.02),
            lk([-0.42, 0.0, -0.14], [-0.3, 0.0, 0.0], 0.7, -0.07),
            lk([-0.42, 0.0, -0.14], [-0.56, 0.07, 0.0], 1.0, -0.02),
            lk([-0.42, 0.0, -0.14], [-0.72, 0.0, 0.0], 0.3, -0.07),
            lk([-0.5, 0.07, -0.02], [-0.72, 0.0, 0.0], 0.0, -0.02),
            lk([-0.52, 0.0, 0.03], [-0.72, 0.0, 0.0], 0.0, -0.09),
            lk([-0.5, 0.03, 0.02], [-0.72, 0.0, 0.0], 0.1, -0.03),
            lk([-0.48, 0.0, 0.0], [-0.72, 0.0, 0.0], 0.4, -0.05),
        ],
        Step::BoxStep => {
            let mut k = vec![
                lk([0.12, 0.0, 0.0], [0.06, 0.0, 0.22], 0.3, -0.06),
                lk([0.14, 0.06, -0.1], [0.06, 0.0, 0.22], 0.0, -0.02),
                lk([0.16, 0.0, -0.2], [0.06, 0.0, 0.22], 0.7, -0.07),
                lk([0.16, 0.0, -0.2], [-0.06, 0.06, -0.02], 1.0, -0.02),
                lk([0.16, 0.0, -0.2], [-0.22, 0.0, -0.15], 0.3, -0.07),
                lk([0.15, 0.06, -0.05], [-0.22, 0.0, -0.15], 0.0, -0.02),
                lk([0.13, 0.0, 0.08], [-0.22, 0.0, -0.15], 0.6, -0.07),
                lk([0.13, 0.0, 0.08], [-0.05, 0.06, 0.1], 1.0, -0.02),
                lk([0.12, 0.0, 0.0], [0.06, 0.0, 0.22], 0.3, -0.06),
            ];
            for (key, yaw) in k.iter_mut().zip([-0.25, -0.15, 0.0, 0.1, 0.2, 0.1, 0.0, -0.15, -0.25]) {
                key.yaw = yaw;
            }
            k
        }
        Step::KickBallChange => {
            let kick = lk([0.12, 0.0, 0.0], [-0.1, 0.3, 0.45], 1.0, -0.02);
            let ball = lk([0.12, 0.0, 0.0], [-0.14, 0.0, -0.12], 0.25, -0.05);
            let change = lk([0.12, 0.0, 0.0], [-0.14, 0.0, -0.12], 0.85, -0.09);
            let chamber = lk([0.12, 0.0, 0.0], [-0.12, 0.16, 0.12], 1.0, -0.04);
            vec![kick, ball, change, chamber, kick, ball, change, chamber, kick]
        }
        Step::Chasse => vec![
            lk([0.1, 0.0, 0.0], [-0.28, 0.0, 0.0], 0.3, -0.06),
            lk([-0.1, 0.0, 0.0], [-0.28, 0.02, 0.0], 0.8, -0.03),
            lk([-0.1, 0.0, 0.0], [-0.5, 0.0, 0.0], 0.2, -0.08),
            lk([-0.22, 0.06, 0.0], [-0.5, 0.0, 0.0], 0.0, -0.02),
            lk([-0.12, 0.0, 0.0], [-0.5, 0.0, 0.0], 0.7, -0.07),
            lk([-0.12, 0.0, 0.0], [-0.3, 0.02, 0.0], 0.3, -0.03),
            lk([0.1, 0.0, 0.0], [-0.3, 0.0, 0.0], 0.8, -0.08),
            lk([0.1, 0.0, 0.0], [-0.2, 0.06, 0.0], 1.0, -0.02),
            lk([0.1, 0.0, 0.0], [-0.28, 0.0, 0.0], 0.3, -0.06),
        ],
        Step::PivotTurn => {
            let mut k = vec![
                lk([0.1, 0.0, -0.05], [-0.1, 0.0, 0.2], 0.4, -0.06),
                lk([0.1, 0.0, -0.05], [-0.1, 0.02, 0.2], 0.6, -0.02),
                lk([0.1, 0.0, -0.05], [-0.1, 0.0, 0.2], 0.85, -0.05),
                lk([0.1, 0.0, -0.05], [0.12, 0.06, -0.1], 1.0, -0.02),
                lk([0.1, 0.0, -0.05], [0.2, 0.0, -0.3], 0.4, -0.06),
                lk([0.1, 0.0, -0.05], [0.2, 0.02, -0.3], 0.6, -0.02),
                lk([0.1, 0.0, -0.05], [0.2, 0.0, -0.3], 0.85, -0.05),
                lk([0.1, 0.0, -0.05], [0.0, 0.06, 0.05], 1.0, -0.02),
                lk([0.1, 0.0, -0.05], [-0.1, 0.0, 0.2], 0.4, -0.06),
            ];
            for (i, key) in k.iter_mut().enumerate() {
                // Half a turn over counts 1-2, the other half over 3-4, to the left (yaw +).
                let turn = match i {
                    0 => 0.0,
                    1 => 0.35,
                    2 | 3 => 1.0,
                    4 => 1.0,
                    5 => 1.35,
                    _ => 2.0,
                };
                key.yaw = turn * PI;
            }
            k
        }
        Step::Jump => vec![
            lk([0.15, 0.0, 0.0], [-0.15, 0.0, 0.0], 0.5, -0.16),
            lk([0.15, 0.0, 0.0], [-0.15, 0.0, 0.0], 0.5, -0.04),
            lk([0.16, 0.12, 0.02], [-0.16, 0.12, 0.02], 0.5, 0.12),
            lk([0.15, 0.0, 0.0], [-0.15, 0.0, 0.0], 0.5, -0.05),
            lk([0.15, 0.0, 0.0], [-0.15, 0.0, 0.0], 0.5, -0.19),
            lk([0.15, 0.0, 0.0], [-0.15, 0.0, 0.0], 0.5, -0.05),
            lk([0.15, 0.0, 0.0], [-0.15, 0.0, 0.0], 0.45, -0.11),
            lk([0.15, 0.0, 0.0], [-0.15, 0.0, 0.0], 0.5, -0.03),
            lk([0.15, 0.0, 0.0], [-0.15, 0.0, 0.0], 0.5, -0.16),
        ],
        Step::Bounce => (0..9)
            .map(|i| {
                let on = i % 2 == 0;
                let w = if (i / 2) % 2 == 0 { 0.42 } else { 0.58 };
                lk([0.14, 0.0, 0.0], [-0.14, 0.0, 0.0], w, if on { -0.11 } else { -0.01 })
            })
            .collect(),
        Step::HipSway => (0..9)
            .map(|i| {
                let w = 0.5 + 0.5 * fmath::sin(i as f32 * FRAC_PI_2 + FRAC_PI_2);
                let mut key = lk([0.17, 0.0, 0.0], [-0.17, 0.0, 0.0], w, if i % 2 == 0 { -0.07 } else { -0.04 });
                key.torso[3] = (w - 0.5) * 0.1;
                key
            })
            .collect(),
        Step::BodyRoll => (0..9)
            .map(|i| {
                // Two rolls per bar: chest leads forward, then the spine, then the hips push
                // through as the knees bend, and the body rises back.
                let ph = i as f32 / 4.0 * TAU;
                let mut key = lk([0.16, 0.0, 0.0], [-0.16, 0.0, 0.0], 0.5, -0.08 + 0.07 * fmath::cos(ph - 1.6));
                key.torso = [0.18 * fmath::sin(ph - 1.9), 0.2 * fmath::sin(ph - 0.9), 0.3 * fmath::sin(ph), 0.0];
                key.l.z = 0.02;
                key
            })
            .collect(),
    }
}

/// Half-count keys (7: counts 1, &, 2, &, 3, &, next 1) of each step in 3, right side leading.
/// Waltz style: down on the one, rising through two and three; each count lands a foot (a
/// dip of the body's speed on the count). A foot on the floor keeps its place from key to key;
/// a foot travels lifted.
fn leg_keys_in_three(step: Step) -> Vec<LegKey> {
    match step {
        Step::WaltzBoxForward => vec![
            lk([0.1, 0.0, 0.0], [-0.1, 0.0, 0.0], 0.5, -0.08),
            lk([0.1, 0.0, 0.0], [-0.1, 0.1, 0.16], 1.0, -0.04),
            lk([0.1, 0.0, 0.0], [-0.1, 0.0, 0.3], 0.25, -0.02),
            lk([0.2, 0.1, 0.22], [-0.1, 0.0, 0.3], 0.0, 0.0),
            lk([0.3, 0.0, 0.3], [-0.1, 0.0, 0.3], 0.7, 0.01),
            lk([0.3, 0.0, 0.3], [0.0, 0.1, 0.3], 1.0, -0.01),
            lk([0.3, 0.0, 0.3], [0.1, 0.0, 0.3], 0.5, -0.08),
        ],
        Step::WaltzBoxBack => vec![
            lk([0.1, 0.0, 0.0], [-0.1, 0.0, 0.0], 0.5, -0.08),
            lk([0.1, 0.1, -0.16], [-0.1, 0.0, 0.0], 0.0, -0.04),
            lk([0.1, 0.0, -0.3], [-0.1, 0.0, 0.0], 0.75, -0.02),
            lk([0.1, 0.0, -0.3], [-0.2, 0.1, -0.22], 1.0, 0.0),
            lk([0.1, 0.0, -0.3], [-0.3, 0.0, -0.3], 0.3, 0.01),
            lk([0.0, 0.1, -0.3], [-0.3, 0.0, -0.3], 0.0, -0.01),
            lk([-0.1, 0.0, -0.3], [-0.3, 0.0, -0.3], 0.5, -0.08),
        ],
        Step::Balance => vec![
            lk([0.1, 0.0, 0.0], [-0.1, 0.0, 0.0], 0.5, -0.06),
            lk([0.1, 0.0, 0.0], [-0.22, 0.1, 0.0], 1.0, -0.03),
            lk([0.1, 0.0, 0.0], [-0.34, 0.0, 0.0], 0.2, -0.09),
            lk([0.02, 0.1, -0.06], [-0.34, 0.0, 0.0], 0.0, -0.02),
            lk([-0.12, 0.0, -0.1], [-0.34, 0.0, 0.0], 0.6, 0.02),
            lk([-0.12, 0.0, -0.1], [-0.34, 0.1, 0.0], 1.0, -0.02),
            lk([-0.12, 0.0, -0.1], [-0.34, 0.0, 0.0], 0.3, -0.07),
        ],
        Step::WaltzTurn => {
            let mut k = vec![
                lk([0.1, 0.0, 0.0], [-0.1, 0.0, 0.0], 0.5, -0.08),
                lk([0.1, 0.0, 0.0], [-0.08, 0.1, 0.14], 1.0, -0.04),
                lk([0.1, 0.0, 0.0], [-0.05, 0.0, 0.25], 0.2, -0.02),
                lk([0.15, 0.1, 0.15], [-0.05, 0.0, 0.25], 0.0, 0.0),
                lk([0.2, 0.0, 0.25], [-0.05, 0.0, 0.25], 0.7, 0.01),
                lk([0.2, 0.0, 0.25], [0.02, 0.1, 0.26], 1.0, -0.01),
                lk([0.2, 0.0, 0.25], [0.0, 0.0, 0.27], 0.5, -0.08),
            ];
            // A half turn to the left (yaw +) over the bar, most of it on the rise.
            for (key, turn) in k.iter_mut().zip([0.0, 0.1, 0.3, 0.55, 0.8, 0.95, 1.0]) {
                key.yaw = turn * PI;
            }
            k
        }
        Step::Hesitation => vec![
            lk([0.1, 0.0, 0.0], [-0.1, 0.0, 0.0], 0.5, -0.08),
            lk([0.24, 0.1, 0.05], [-0.1, 0.0, 0.0], 0.0, -0.04),
            lk([0.34, 0.0, 0.08], [-0.1, 0.0, 0.0], 0.8, -0.03),
            lk([0.34, 0.0, 0.08], [-0.1, 0.0, 0.0], 1.0, 0.0),
            lk([0.34, 0.0, 0.08], [0.02, 0.1, 0.06], 1.0, 0.01),
            lk([0.34, 0.0, 0.08], [0.1, 0.1, 0.08], 1.0, -0.02),
            lk([0.34, 0.0, 0.08], [0.14, 0.0, 0.08], 0.5, -0.08),
        ],
        // The steps in 4 have no keys in 3.
        _ => leg_keys_in_four(step),
    }
}

/// Count keys (5: counts 1, 2, 3, 4, next 1) of each step held on the counts, right side
/// leading: the count keys of the step-touch, grapevine and box step (their "and" keys left
/// out: a travelling foot is lifted between counts by [`legs_at`]), and a sway. Every key
/// stands on both feet.
fn leg_keys_on_counts(step: Step) -> Vec<LegKey> {
    match step {
        Step::SideTouch => vec![
            lk([0.25, 0.0, 0.0], [-0.25, 0.0, 0.0], 0.3, -0.07),
            lk([-0.07, 0.0, 0.03], [-0.25, 0.0, 0.0], 0.0, -0.08),
            lk([0.25, 0.0, 0.0], [-0.25, 0.0, 0.0], 0.7, -0.07),
            lk([0.25, 0.0, 0.0], [0.07, 0.0, 0.03], 1.0, -0.08),
            lk([0.25, 0.0, 0.0], [-0.25, 0.0, 0.0], 0.3, -0.07),
        ],
        Step::SlowGrapevine => vec![
            lk([0.12, 0.0, 0.0], [-0.3, 0.0, 0.0], 0.3, -0.06),
            lk([-0.42, 0.0, -0.14], [-0.3, 0.0, 0.0], 0.7, -0.07),
            lk([-0.42, 0.0, -0.14], [-0.72, 0.0, 0.0], 0.3, -0.07),
            lk([-0.52, 0.0, 0.03], [-0.72, 0.0, 0.0], 0.0, -0.09),
            lk([-0.48, 0.0, 0.0], [-0.72, 0.0, 0.0], 0.4, -0.05),
        ],
        // The box step's hip turn is left out: with it, held feet jumped past the retargeting
        // bound on RobotExpressive (`character_retarget`).
        Step::SlowBox => vec![
            lk([0.12, 0.0, 0.0], [0.06, 0.0, 0.22], 0.3, -0.06),
            lk([0.16, 0.0, -0.2], [0.06, 0.0, 0.22], 0.7, -0.07),
            lk([0.16, 0.0, -0.2], [-0.22, 0.0, -0.15], 0.3, -0.07),
            lk([0.13, 0.0, 0.08], [-0.22, 0.0, -0.15], 0.6, -0.07),
            lk([0.12, 0.0, 0.0], [0.06, 0.0, 0.22], 0.3, -0.06),
        ],
        Step::Sway => [0.2, 0.8, 0.2, 0.8, 0.2]
            .into_iter()
            .map(|w| {
                let mut key = lk([0.17, 0.0, 0.0], [-0.17, 0.0, 0.0], w, -0.07);
                key.torso[3] = (w - 0.5) * 0.1;
                key
            })
            .collect(),
        _ => leg_keys(step),
    }
}

/// Lift of a foot that travels between two counts of a step held on the counts (metres, at
/// medium energy).
const ON_COUNTS_LIFT: f32 = 0.07;

/// The legs' key pose of a step at `t` counts: the half-count keys interpolated, or for a step
/// held on the counts, each count's key eased into the next by a smootherstep, the foot that
/// travels (the farther one where both do) lifted by a sin² bump that is flat at both counts
/// and keeps its pointing.
pub(crate) fn legs_at(step: Step, energy: Energy, legs: &[KeyPose], t: f32) -> KeyPose {
    if !step.on_counts() {
        return super::pose::interpolate(legs, 0.5, t);
    }
    let last = legs.len() - 1;
    let x = t.clamp(0.0, last as f32);
    let i = (x.floor() as usize).min(last - 1);
    let u = x - i as f32;
    let e = smoother01(u);
    let (a, b) = (&legs[i], &legs[i + 1]);
    let mut p = a.scaled(1.0 - e).add(&b.scaled(e));
    let travel = |from: Vec3, to: Vec3| Vec3::new(to.x - from.x, 0.0, to.z - from.z).length();
    let (dl, dr) = (travel(a.left_foot, b.left_foot), travel(a.right_foot, b.right_foot));
    if dl.max(dr) > 0.005 {
        let s = fmath::sin(u * PI);
        let lift = ON_COUNTS_LIFT * energy.amplitude() * s * s;
        if dl >= dr {
            p.left_foot.y += lift;
        } else {
            p.right_foot.y += lift;
        }
    }
    p
}

/// `values[k]` on count k (0..=3 over a bar in 3), eased from each count to the next.
fn through_counts(values: &[f32; 4], t: f32) -> f32 {
    let x = t.clamp(0.0, 3.0);
    let i = (x.floor() as usize).min(2);
    values[i] + (values[i + 1] - values[i]) * smooth01(x - i as f32)
}

/// [`through_counts`] for points.
fn through_points(points: &[Vec3; 4], t: f32) -> Vec3 {
    let x = t.clamp(0.0, 3.0);
    let i = (x.floor() as usize).min(2);
    points[i].lerp(points[i + 1], smooth01(x - i as f32))
}

/// `points[k]` on count k (0..=4 over a bar in 4), eased from each count to the next by a
/// smootherstep (the moves held on the counts).
fn through_counts_eased(points: &[Vec3; 5], t: f32) -> Vec3 {
    let x = t.clamp(0.0, 4.0);
    let i = (x.floor() as usize).min(3);
    points[i].lerp(points[i + 1], smoother01(x - i as f32))
}

/// Left-hand target relative to the left shoulder (chest frame) and the right's, at time
/// `t_counts` in 0..=4, with the chest twist the pattern asks for.
fn arm_targets(arms: Arms, t: f32, amp: f32) -> (Vec3, Vec3, f32) {
    let down_l = Vec3::new(0.07, -0.49, 0.08);
    let down_r = Vec3::new(-0.07, -0.49, 0.08);
    let count = t.floor();
    let within = t - count;
    let pulse = |x: f32| fmath::sin(x * PI).max(0.0); // 0 → 1 → 0 over one count
    let sharp = |x: f32| {
        let y = (x * 2.0).min(1.0);
        y * y * (3.0 - 2.0 * y) * (1.0 - smooth01((x - 0.55) / 0.45))
    };
    match arms {
        Arms::Swing => {
            let s = fmath::sin(t * PI);
            let l = down_l + Vec3::new(0.0, 0.05 * amp * s.abs(), 0.22 * amp * s);
            let r = down_r + Vec3::new(0.0, 0.05 * amp * s.abs(), -0.22 * amp * s);
            (l + Vec3::new(0.0, 0.08, 0.05), r + Vec3::new(0.0, 0.08, 0.05), 0.12 * amp * s)
        }
        Arms::Waves => {
            let s = fmath::sin(t * FRAC_PI_2);
            let up = 0.3 + 0.15 * amp;
            let l = Vec3::new(0.12 + 0.22 * amp * s, up + 0.05 * fmath::cos(t * PI), 0.08);
            let r = Vec3::new(-0.12 + 0.22 * amp * s, up - 0.05 * fmath::cos(t * PI), 0.08);
            (l, r, 0.0)
        }
        Arms::Punches => {
            // Right punches on 1 and 3, left on 2 and 4; the other hand chambers at the chest.
            let p = sharp(within);
            let chamber_l = Vec3::new(-0.02, -0.25, 0.18);
            let chamber_r = Vec3::new(0.02, -0.25, 0.18);
            let height = -0.05 + 0.15 * (amp - 0.6);
            let right_turn = (count as i32) % 2 == 0;
            let (mut l, mut r) = (chamber_l, chamber_r);
            if right_turn {
                r = chamber_r.lerp(Vec3::new(0.1, height, 0.5), p);
            } else {
                l = chamber_l.lerp(Vec3::new(-0.1, height, 0.5), p);
            }
            (l, r, if right_turn { 0.25 * amp * p } else { -0.25 * amp * p })
        }
        Arms::Claps => {
            // Open on the count, clap on the "and" (overhead on 4 when energetic).
            let c = pulse(within);
            let overhead = count >= 3.0 && amp > 1.1;
            let (meet_y, meet_z) = if overhead { (0.45, 0.12) } else { (-0.18, 0.3) };
            let open_l = Vec3::new(0.18, -0.25, 0.22);
            let l = open_l.lerp(Vec3::new(-0.15, meet_y, meet_z), c);
            let r = Vec3::new(-open_l.x, open_l.y, open_l.z).lerp(Vec3::new(0.15, meet_y, meet_z), c);
            (l, r, 0.0)
        }
        Arms::ArmRolls => {
            let th = t * TAU * if amp > 1.1 { 1.0 } else { 0.5 };
            let rad = 0.06 + 0.03 * amp;
            let base_y = -0.18 + if count >= 2.0 { 0.12 * amp } else { 0.0 };
            let l = Vec3::new(-0.1 + rad * fmath::cos(th), base_y + rad * fmath::sin(th), 0.3);
            let r = Vec3::new(0.1 + rad * fmath::cos(th + PI), base_y + rad * fmath::sin(th + PI), 0.28);
            (l, r, 0.05 * fmath::sin(th))
        }
        Arms::OverheadReaches => {
            // Right reaches on 1, left on 3, each held through the next count.
            let reach = |start: f32| {
                let x = t - start;
                if !(0.0..2.0).contains(&x) {
                    0.0
                } else {
                    smooth01(x / 0.6) * (1.0 - smooth01((x - 1.2) / 0.8))
                }
            };
            let (rr, rl) = (reach(0.0), reach(2.0));
            let up_r = Vec3::new(-0.12, 0.5, 0.1 + 0.05 * amp);
            let up_l = Vec3::new(0.12, 0.5, 0.1 + 0.05 * amp);
            let r = down_r.lerp(up_r, rr * (0.7 + 0.3 * amp.min(1.0)));
            let l = down_l.lerp(up_l, rl * (0.7 + 0.3 * amp.min(1.0)));
            (l, r, 0.15 * (rl - rr))
        }
        // The arm patterns in 3 move between poses held on the counts (a smoothstep from each
        // count to the next), so the arms, like the feet, turn on the counts (§J's kinetic beats).
        Arms::Frame => {
            // A ballroom hold (left hand raised to the side, right hand at the partner's back),
            // rising on two and three with the body and settling on the one.
            let rise = 0.06 * amp * through_counts(&[0.0, 0.5, 1.0, 0.0], t);
            let l = Vec3::new(0.32, 0.02 + rise, 0.22);
            let r = Vec3::new(-0.12, -0.12 + rise, 0.32);
            (l, r, 0.16 * amp * through_counts(&[-0.5, 0.0, 0.5, -0.5], t))
        }
        Arms::PortDeBras => {
            // The right arm: low in front on the one, overhead on two, open to the side on
            // three, back low in front by the next one; the left answers low and open.
            let front = Vec3::new(-0.08, -0.2, 0.4);
            let over = Vec3::new(-0.1, 0.2 + 0.25 * amp.min(1.2), 0.12);
            let side = Vec3::new(-0.48, 0.02, 0.05);
            let r = through_points(&[front, over, side, front], t);
            let open_l = Vec3::new(0.3, -0.25, 0.12);
            let l = through_points(&[down_l, down_l.lerp(open_l, 0.6 * amp.min(1.2)), open_l, down_l], t);
            (l, r, 0.12 * amp * through_counts(&[0.0, -1.0, 1.0, 0.0], t))
        }
        Arms::OpenArms => {
            // Both arms open from low in front (one) to wide (two), float up (three) and close.
            let low_l = Vec3::new(-0.04, -0.35, 0.25);
            let wide_l = Vec3::new(0.42, -0.02 + 0.08 * (amp - 1.0), 0.08);
            let high_l = wide_l + Vec3::new(-0.05, 0.12 * amp, 0.05);
            let l = through_points(&[low_l, wide_l, high_l, low_l], t);
            let r = Vec3::new(-l.x, l.y, l.z);
            (l, r, 0.0)
        }
        // The arm patterns held on the counts: a pose on each count, eased into the next by a
        // smootherstep (as the legs of their steps).
        Arms::Presses => {
            let front = Vec3::new(0.06, -0.12 + 0.04 * amp, 0.28 + 0.12 * amp);
            let chest = Vec3::new(0.0, -0.24, 0.2);
            let over = Vec3::new(0.1, 0.3 + 0.12 * amp, 0.1);
            let l = through_counts_eased(&[front, chest, over, chest, front], t);
            (l, Vec3::new(-l.x, l.y, l.z), 0.0)
        }
        Arms::OpenClose => {
            let closed = Vec3::new(-0.04, -0.32, 0.27);
            let open = Vec3::new(0.4, -0.05 + 0.08 * (amp - 1.0), 0.1);
            let open_high = open + Vec3::new(-0.05, 0.12 * amp, 0.05);
            let l = through_counts_eased(&[closed, open, closed, open_high, closed], t);
            (l, Vec3::new(-l.x, l.y, l.z), 0.0)
        }
        Arms::ArmWave => {
            let ph = t * PI;
            let a = 0.1 * amp;
            let l = Vec3::new(0.4, -0.05 + a * fmath::sin(ph), 0.15 + 0.05 * fmath::cos(ph * 0.5));
            let r = Vec3::new(-0.4, -0.05 + a * fmath::sin(ph - 1.2), 0.15 + 0.05 * fmath::cos(ph * 0.5));
            (l, r, 0.0)
        }
    }
}


/// The key pose of a move at `t_counts` (0..=4): leg keys interpolated ([`legs_at`]), arms
/// evaluated with a small lag (follow-through), secondary motion added.
pub(crate) fn pose_at(step: Step, arms: Arms, energy: Energy, t: f32, legs: &[KeyPose]) -> KeyPose {
    let amp = energy.amplitude();
    let mut p = legs_at(step, energy, legs, t);
    // Arms trail the body a little (follow-through); rolls and claps keep strict time.
    let lag = match arms {
        Arms::Swing | Arms::Waves | Arms::ArmWave => 0.12,
        _ => 0.04,
    };
    let (l, r, twist) = arm_targets(arms, (t - lag).max(0.0), amp);
    p.left_hand = l;
    p.right_hand = r;
    p.chest_yaw += twist;
    // Shoulders rise with the hands.
    p.left_shrug = 0.12 * smooth01((l.y + 0.1) / 0.6);
    p.right_shrug = 0.12 * smooth01((r.y + 0.1) / 0.6);
    // The head steadies against the chest and nods a fraction after the bounce.
    let later_drop = if step.on_counts() {
        legs_at(step, energy, legs, (t - 0.15).max(0.0)).hips.y
    } else {
        super::pose::interpolate_channel(legs, 0.5, (t - 0.15).max(0.0), |k| k.hips.y)
    };
    p.head_roll = -0.5 * p.chest_roll - 0.3 * p.hips_roll;
    p.head_pitch += -0.6 * later_drop - 0.3 * p.chest_pitch;
    p.head_yaw = -0.4 * p.chest_yaw;
    p
}

/// Leg keys of a step turned into key poses with the weight shift and hip/chest reactions.
pub(crate) fn leg_poses(step: Step, energy: Energy) -> Vec<KeyPose> {
    let amp = energy.amplitude();
    leg_keys(step)
        .into_iter()
        .map(|k| {
            // Travel and lifts scale with energy (a little); depth of the knees too.
            let scale_foot = |v: Vec3| Vec3::new(v.x * (0.85 + 0.15 * amp), v.y * amp, v.z * (0.85 + 0.15 * amp));
            let (l, r) = (scale_foot(k.l), scale_foot(k.r));
            let w = k.w_left.clamp(0.0, 1.0);
            // Weight shift: the hips travel over the supporting foot.
            let support = r.lerp(l, w);
            let centre = (l + r) * 0.5;
            let hips_xz = centre.lerp(support, 0.6);
            let lean = (w - 0.5) * 2.0; // +1 all on the left
            KeyPose {
                hips: Vec3::new(hips_xz.x + k.torso[3] * amp, k.drop * amp, hips_xz.z),
                hips_yaw: k.yaw,
                hips_pitch: k.torso[0] * amp,
                // The hip of the supporting side pushes out and up: the pelvis tilts towards the
                // free side.
                hips_roll: -0.09 * amp * lean,
                spine_pitch: 0.04 + k.torso[1] * amp,
                spine_roll: 0.05 * amp * lean,
                chest_pitch: k.torso[2] * amp - 0.6 * k.drop * amp,
                chest_roll: 0.04 * amp * lean,
                chest_yaw: 0.0,
                left_foot: l,
                right_foot: r,
                left_point: if l.y > 0.01 { 0.6 } else { (1.0 - w) * 0.45 },
                right_point: if r.y > 0.01 { 0.6 } else { w * 0.45 },
                feet_yaw: 0.12,
                ..Default::default()
            }
        })
        .collect()
}
