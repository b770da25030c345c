//! Compiling a scene's semantic parts: the areas, label order and
//! `[semantic]` settings into a [`SemanticSpec`], the contact fingers'
//! `holds` into [`HoldDecl`]s, and the loaded scene's consistency check
//! (§3.3: "if a scene is loaded from file, it is checked for consistency
//! during loading").

use super::LoadedScene;
use super::SceneError;
use super::spec::SceneFile;
use crate::contact::jointed_pairs;
use crate::semantic::{
    AreaKind, AreaSpec, Inconsistency, SemanticScene, SemanticSettings, SemanticSpec,
};
use crate::{BodyId, FingerId, Model, SnapSettings};

/// One scheduled hold of a contact finger: from `from_s` to `until_s` the
/// fingertip holds `body` (where it touches it when the hold starts).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldDecl {
    /// The contact finger.
    pub finger: FingerId,
    /// The body held.
    pub body: BodyId,
    /// Start, s.
    pub from_s: f64,
    /// End, s.
    pub until_s: f64,
}

/// The `[semantic]` settings the file set, over the defaults; the collision
/// tolerance is the contact's penetration tolerance.
fn settings(s: &SceneFile, penetration_tolerance_m: f64) -> SemanticSettings {
    let d = SemanticSettings::default();
    let sec = s.semantic.clone().unwrap_or_default();
    let f =
        |v: &Option<toml::Spanned<f64>>, default: f64| v.as_ref().map_or(default, |x| *x.get_ref());
    SemanticSettings {
        snap_distance_m: f(&sec.snap_distance, d.snap_distance_m),
        snap_angle_rad: f(&sec.snap_angle, d.snap_angle_rad),
        break_force_n: f(&sec.break_force, d.break_force_n),
        snap: SnapSettings {
            speed_m_per_s: f(&sec.snap_speed, d.snap.speed_m_per_s),
            force_limit_n: f(&sec.snap_force, d.snap.force_limit_n),
        },
        collision_tolerance_m: penetration_tolerance_m,
        align_tolerance: d.align_tolerance,
    }
}

impl LoadedScene {
    /// The semantic spec (`None` for a scene without areas), checked: the
    /// scene at its initial configuration, its aligned bindings satisfied,
    /// must be consistent.
    pub(super) fn compile_semantic(
        &self,
        model: &Model,
        penetration_tolerance_m: f64,
        absent: &[BodyId],
    ) -> Result<Option<SemanticSpec>, SceneError> {
        let s = &self.spec;
        let mut areas = Vec::new();
        for (i, b) in s.bodies.iter().enumerate() {
            for (list, kind) in [(&b.offer, AreaKind::Offer), (&b.binding, AreaKind::Binding)] {
                for a in list {
                    areas.push(AreaSpec {
                        body: BodyId(i as u32),
                        kind,
                        label: a.label.get_ref().clone(),
                        polygon_m: a.polygon.get_ref().iter().map(|p| p.get()).collect(),
                        normal: a.normal.get_ref().get(),
                    });
                }
            }
        }
        if areas.is_empty() {
            return Ok(None);
        }
        let spec = SemanticSpec {
            areas,
            order: s
                .labels
                .iter()
                .flat_map(|(k, vs)| {
                    vs.get_ref()
                        .iter()
                        .map(|v| (k.get_ref().clone(), v.get_ref().clone()))
                })
                .collect(),
            labels: s.labels.keys().map(|k| k.get_ref().clone()).collect(),
            settings: settings(s, penetration_tolerance_m),
        };
        let at_scene = |msg: String| self.error_at(s.scene.name.span(), msg);
        let mut scene = SemanticScene::from_model(model, model.q0(), &spec)
            .map_err(|e| at_scene(e.to_string()))?;
        self.check_inclusion_rows(&scene)?;
        for &b in absent {
            scene.start_absent(b);
        }
        scene.satisfy_aligned();
        let joined: Vec<[BodyId; 2]> = jointed_pairs(model)
            .into_iter()
            .map(|[a, b]| [BodyId(a), BodyId(b)])
            .collect();
        scene.set_ignored(&joined);
        match scene.consistent() {
            Ok(()) => Ok(Some(spec)),
            Err(Inconsistency::Collision(c)) => {
                let [a, b] = c.bodies.map(|x| scene.name(x).to_owned());
                let span = s
                    .bodies
                    .get(c.bodies[1].index())
                    .map_or(s.scene.name.span(), |x| x.name.span());
                Err(self.error_at(
                    span,
                    format!(
                        "bodies `{a}` and `{b}` overlap by {:.3} mm and no satisfied constraint \
                         binds them: a loaded scene must be consistent (move one, or give them \
                         an offer and a binding that fit and touch)",
                        c.depth_m * 1e3
                    ),
                ))
            }
            Err(e) => Err(at_scene(format!("the scene is not consistent: {e}"))),
        }
    }

    /// The contact fingers' holds, in file order (validated).
    pub(super) fn compile_holds(&self, model: &Model) -> Vec<HoldDecl> {
        let mut out = Vec::new();
        for f in &self.spec.fingers {
            let Some(finger) = model.finger_id(f.name.get_ref()) else {
                continue;
            };
            for h in &f.holds {
                let h = h.get_ref();
                if let Some(body) = model.body_id(h.body.get_ref()) {
                    out.push(HoldDecl {
                        finger,
                        body,
                        from_s: *h.from.get_ref(),
                        until_s: *h.until.get_ref(),
                    });
                }
            }
        }
        out
    }
}
