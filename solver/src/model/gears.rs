//! `[[gear]]` entries ([`GearSpec`]): couplings between two already compiled
//! joints, a gear pair (revolute to revolute, `constraint::gear`) or a rack
//! and pinion (revolute to prismatic, `constraint::rack_pinion`). Compiled
//! after the joints, before the fingers.

use std::fmt;

use super::assembler::Assembler;
use super::compiler::Compiler;
use super::error::{BuildError, Owner};
use crate::BodyId;
use crate::constraint::block::{Ctx, Pair, Param3};
use crate::constraint::gear::{Ends, Gear};
use crate::constraint::prismatic::Prismatic;
use crate::constraint::rack_pinion::RackPinion;
use crate::constraint::{ConstraintInfo, ConstraintKind, Geometry};

/// The largest tooth count (denominator) a gear ratio is read with.
pub const MAX_GEAR_TEETH: u64 = 10_000;

/// What a `[[gear]]` couples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum GearKind {
    /// Two revolute joints: θ_j = ratio · θ_i (ratio a ratio of whole
    /// numbers, like tooth counts).
    Gear,
    /// A revolute (pinion) and a prismatic (rack): s − s₀ = ratio · θ
    /// (ratio in m/rad).
    RackPinion,
}

impl GearKind {
    /// Every kind.
    pub const ALL: &'static [Self] = &[Self::Gear, Self::RackPinion];

    /// The scene-file spelling.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Gear => "gear",
            Self::RackPinion => "rack_pinion",
        }
    }
}

impl fmt::Display for GearKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A `[[gear]]` entry.
#[derive(Debug, Clone, PartialEq)]
pub struct GearSpec {
    /// Unique among joints and gears.
    pub name: String,
    /// Gear pair or rack and pinion.
    pub kind: GearKind,
    /// Joint names `[i, j]`: `[driver, driven]` for a gear, `[pinion, rack]`
    /// for a rack and pinion.
    pub joints: [String; 2],
    /// Joint j's coordinate per unit of joint i's: rad/rad (a ratio of whole
    /// numbers up to [`MAX_GEAR_TEETH`]) or m/rad; non-zero.
    pub ratio: f64,
}

impl GearSpec {
    /// A gear pair `driver` → `driven` at `ratio`.
    pub fn gear(name: &str, driver: &str, driven: &str, ratio: f64) -> Self {
        Self {
            name: name.into(),
            kind: GearKind::Gear,
            joints: [driver.into(), driven.into()],
            ratio,
        }
    }

    /// A rack and pinion: `rack` slides `ratio_m_per_rad` per radian of
    /// `pinion`.
    pub fn rack_pinion(name: &str, pinion: &str, rack: &str, ratio_m_per_rad: f64) -> Self {
        Self {
            name: name.into(),
            kind: GearKind::RackPinion,
            joints: [pinion.into(), rack.into()],
            ratio: ratio_m_per_rad,
        }
    }
}

/// `x` as p/q (q ≤ `max_den`, lowest terms) within 1e-9 relative, by
/// continued fractions; `None` if no such fraction is that close.
pub(crate) fn as_fraction(x: f64, max_den: u64) -> Option<(i64, u64)> {
    if !x.is_finite() || x.abs() > max_den as f64 {
        return None;
    }
    let tol = 1e-9 * x.abs().max(1.0);
    let (sign, mut y) = (x.signum(), x.abs());
    let (mut h0, mut h1) = (0u64, 1u64);
    let (mut k0, mut k1) = (1u64, 0u64);
    for _ in 0..64 {
        let a = y.floor();
        let (h, k) = (a as u64 * h1 + h0, a as u64 * k1 + k0);
        if k > max_den {
            return None;
        }
        if (x.abs() - h as f64 / k as f64).abs() <= tol {
            return Some((sign as i64 * h as i64, k));
        }
        (h0, h1, k0, k1) = (h1, h, k1, k);
        let frac = y - a;
        if frac <= 0.0 {
            return None;
        }
        y = 1.0 / frac;
    }
    None
}

/// Compiles the `k`-th gear against the joints already in `out` (joint
/// `ConstraintId(j)` is the j-th `[[joint]]`, `n_joints` of them), with the
/// fixed bodies' freed positions `origin_cols`.
pub(super) fn compile_gear(
    s: &GearSpec,
    out: &Assembler,
    n_joints: usize,
    cx: &Compiler,
    origin_cols: &[Option<usize>],
) -> Result<(ConstraintInfo, Geometry), BuildError> {
    let owner = || Owner::Gear(s.name.clone());
    if s.name.is_empty() {
        return Err(BuildError::EmptyName { owner: owner() });
    }
    let ids = joint_ids(s, out, n_joints, &owner)?;
    let pairs = ids.map(|j| *joint_pair(&out.geometry[j]));
    let (pair, ends, bodies) = coupling(&pairs, cx, &owner)?;
    if !(s.ratio.is_finite() && s.ratio != 0.0) {
        return Err(BuildError::GearRatio {
            owner: owner(),
            ratio: s.ratio,
            why: "a finite, non-zero number",
        });
    }
    let geometry = match (out.geometry[ids[0]], out.geometry[ids[1]]) {
        (Geometry::Revolute(a), Geometry::Revolute(b)) => {
            let (num, den) = tooth_ratio(s, &owner)?;
            Geometry::Gear(Gear {
                pair,
                joints: [a, b],
                ends,
                num: num as f64,
                den: den as f64,
            })
        }
        (Geometry::Revolute(pinion), Geometry::Prismatic(rack)) => {
            let s0_m = rack_start(s, &rack, cx, origin_cols, &owner)?;
            Geometry::RackPinion(RackPinion {
                pair,
                pinion,
                rack,
                ends,
                ratio_m: s.ratio,
                s0_m,
            })
        }
        _ => unreachable!("kinds checked above"),
    };
    let kind = match s.kind {
        GearKind::Gear => ConstraintKind::Gear,
        GearKind::RackPinion => ConstraintKind::RackPinion,
    };
    let info = ConstraintInfo {
        name: s.name.clone(),
        kind,
        rows: 0..0,
        bodies,
        finger: None,
        limits: None,
    };
    Ok((info, geometry))
}

/// The two joints `s` couples (by name among the first `n_joints` of
/// `out`): distinct, and of the kinds its kind couples.
fn joint_ids(
    s: &GearSpec,
    out: &Assembler,
    n_joints: usize,
    owner: &dyn Fn() -> Owner,
) -> Result<[usize; 2], BuildError> {
    let find = |name: &str| {
        (0..n_joints)
            .find(|&j| out.infos[j].name == name)
            .ok_or_else(|| BuildError::UnknownJoint {
                owner: owner(),
                joint: name.to_owned(),
            })
    };
    let ids = [find(&s.joints[0])?, find(&s.joints[1])?];
    if ids[0] == ids[1] {
        return Err(BuildError::GearJoint {
            owner: owner(),
            joint: s.joints[1].clone(),
            kind: out.infos[ids[1]].kind,
            want: "two different joints",
        });
    }
    let want = match s.kind {
        GearKind::Gear => [ConstraintKind::Revolute, ConstraintKind::Revolute],
        GearKind::RackPinion => [ConstraintKind::Revolute, ConstraintKind::Prismatic],
    };
    for k in 0..2 {
        if out.infos[ids[k]].kind != want[k] {
            return Err(BuildError::GearJoint {
                owner: owner(),
                joint: s.joints[k].clone(),
                kind: out.infos[ids[k]].kind,
                want: match (s.kind, k) {
                    (GearKind::Gear, _) => "a gear couples two revolute joints",
                    (GearKind::RackPinion, 0) => {
                        "a rack_pinion's first joint is the pinion's revolute"
                    }
                    _ => "a rack_pinion's second joint is the rack's prismatic",
                },
            });
        }
    }
    Ok(ids)
}

/// A gear's ratio as tooth counts (num, den).
fn tooth_ratio(s: &GearSpec, owner: &dyn Fn() -> Owner) -> Result<(i64, u64), BuildError> {
    as_fraction(s.ratio, MAX_GEAR_TEETH).ok_or_else(|| BuildError::GearRatio {
        owner: owner(),
        ratio: s.ratio,
        why: "a ratio of whole numbers (tooth counts) with a denominator up to 10000: \
              gears repeat after whole turns",
    })
}

/// The rack's slide at the model's build (its coordinate s₀), refused when
/// a design variable moves the rack's anchors or frames.
fn rack_start(
    s: &GearSpec,
    rack: &Prismatic,
    cx: &Compiler,
    origin_cols: &[Option<usize>],
    owner: &dyn Fn() -> Owner,
) -> Result<f64, BuildError> {
    let frozen = rack
        .pair
        .anchor
        .iter()
        .any(|a| matches!(a, Param3::Free(_) | Param3::Flex(_)))
        || rack
            .pair
            .frame
            .iter()
            .any(|&f| origin_cols.get(f).copied().flatten().is_some());
    if frozen {
        return Err(BuildError::GearRackDesign {
            owner: owner(),
            joint: s.joints[1].clone(),
        });
    }
    // No flexible anchors here (refused above with design ones).
    let x = Ctx {
        q: &[],
        frames: cx.frames,
        targets: &[],
        witnesses: &[],
        flex: &[],
        surfaces: &[],
        rolling: &[],
    };
    Ok(rack.coordinate(&x).0)
}

fn joint_pair(g: &Geometry) -> &Pair {
    match g {
        Geometry::Revolute(j) => &j.pair,
        Geometry::Prismatic(j) => &j.pair,
        _ => unreachable!("gears couple revolute and prismatic joints only"),
    }
}

/// The coupling's ends: the distinct moving bodies of the two joints (at
/// most two; the world fills a missing second end), how each joint's ends
/// map onto them, and the bodies for [`ConstraintInfo::bodies`].
fn coupling(
    pairs: &[Pair; 2],
    cx: &Compiler,
    owner: &dyn Fn() -> Owner,
) -> Result<(Pair, Ends, [Option<BodyId>; 2]), BuildError> {
    let world = cx.frames.len() - 1;
    let mut moving: Vec<(usize, usize)> = Vec::new(); // (frame, column)
    let mut map = [[None; 2]; 2];
    for (p, ends) in pairs.iter().zip(map.iter_mut()) {
        for (end, slot) in ends.iter_mut().enumerate() {
            let Some(col) = p.col[end] else { continue };
            let f = p.frame[end];
            let at = match moving.iter().position(|&(g, _)| g == f) {
                Some(i) => i,
                None => {
                    moving.push((f, col));
                    moving.len() - 1
                }
            };
            *slot = Some(at as u8);
        }
    }
    if moving.len() > 2 {
        let names: Vec<String> = moving
            .iter()
            .map(|&(f, _)| format!("`{}`", cx.bodies[f].name))
            .collect();
        return Err(BuildError::GearBodies {
            owner: owner(),
            bodies: names.join(", "),
        });
    }
    let end = |i: usize| moving.get(i).copied();
    let pair = Pair {
        frame: [end(0).map_or(world, |m| m.0), end(1).map_or(world, |m| m.0)],
        col: [end(0).map(|m| m.1), end(1).map(|m| m.1)],
        anchor: [Param3::Const(nalgebra::Vector3::zeros()); 2],
    };
    let bodies = [
        end(0).map(|m| BodyId(m.0 as u32)),
        end(1).map(|m| BodyId(m.0 as u32)),
    ];
    Ok((pair, Ends { map }, bodies))
}

#[cfg(test)]
mod tests {
    use super::as_fraction;

    #[test]
    fn ratios_are_read_as_fractions_of_tooth_counts() {
        assert_eq!(as_fraction(0.5, 10_000), Some((1, 2)));
        assert_eq!(as_fraction(-2.0, 10_000), Some((-2, 1)));
        assert_eq!(as_fraction(1.0 / 3.0, 10_000), Some((1, 3)));
        assert_eq!(as_fraction(-17.0 / 43.0, 10_000), Some((-17, 43)));
        assert_eq!(as_fraction(std::f64::consts::SQRT_2, 10_000), None);
        assert_eq!(as_fraction(f64::NAN, 10_000), None);
    }
}
