//! `[[schedule]]` tables: semantic operations at given times of a run
//! (Gösele & Stuerzlinger §3.3 and §6): an object added to the scene or
//! removed from it, and the interaction mode switched between constrained
//! and unconstrained. A body whose first entry adds it is absent from the
//! start (declared, but not in the scene until then).

use serde::Deserialize;
use toml::Spanned;

use super::validate::list;
use super::{LoadedScene, SceneError};
use crate::{BodyId, Model};

/// `[[schedule]]`: at `at` seconds, one of `add`, `remove`, `mode`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduleSection {
    /// Session time, s, ≥ 0.
    pub at: Spanned<f64>,
    /// A body put into the scene (at the valid place nearest its declared
    /// pose).
    pub add: Option<Spanned<String>>,
    /// A body taken out of the scene.
    pub remove: Option<Spanned<String>>,
    /// The interaction mode from then on.
    pub mode: Option<Spanned<SemanticMode>>,
}

/// The interaction modes of §6.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum SemanticMode {
    /// Semantic constraints act on a held object (the default).
    #[default]
    Constrained,
    /// A held object's semantic constraints are off: its bindings are
    /// neither kept nor snapped while the hand holds it.
    Unconstrained,
}

impl SemanticMode {
    /// The name in scene files and reports.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Constrained => "constrained",
            Self::Unconstrained => "unconstrained",
        }
    }
}

/// What a schedule entry does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ScheduleAction {
    /// Put the body into the scene.
    Add(BodyId),
    /// Take it out.
    Remove(BodyId),
    /// Switch the mode.
    Mode(SemanticMode),
}

/// One compiled `[[schedule]]` entry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScheduleDecl {
    /// Session time, s.
    pub at_s: f64,
    /// What happens.
    pub action: ScheduleAction,
}

impl LoadedScene {
    /// The file's schedule against the compiled `model`, sorted by time
    /// (file order kept among equal times), and the bodies absent at the
    /// start. `areas`: the scene declares offer or binding areas.
    pub(super) fn compile_schedule(
        &self,
        model: &Model,
        areas: bool,
    ) -> Result<(Vec<ScheduleDecl>, Vec<BodyId>), SceneError> {
        let s = &self.spec;
        let mut out = Vec::new();
        for e in &s.schedule {
            let at = *e.at.get_ref();
            if !(at.is_finite() && at >= 0.0) {
                return Err(self.error_at(
                    e.at.span(),
                    format!("`at` is {at}; expected a session time in seconds, finite and ≥ 0"),
                ));
            }
            if !areas {
                return Err(self.error_at(
                    e.at.span(),
                    "`[[schedule]]` belongs to scenes with semantic areas (`[[body.offer]]`, \
                     `[[body.binding]]`)",
                ));
            }
            let action = match (&e.add, &e.remove, &e.mode) {
                (Some(b), None, None) => ScheduleAction::Add(self.scheduled_body(model, b)?),
                (None, Some(b), None) => ScheduleAction::Remove(self.scheduled_body(model, b)?),
                (None, None, Some(m)) => ScheduleAction::Mode(*m.get_ref()),
                _ => {
                    return Err(self.error_at(
                        e.at.span(),
                        "a schedule entry does one thing: give exactly one of `add`, `remove`, \
                         `mode`",
                    ));
                }
            };
            out.push((ScheduleDecl { at_s: at, action }, e));
        }
        out.sort_by(|a, b| a.0.at_s.total_cmp(&b.0.at_s));
        let absent = self.check_sequence(model, &out)?;
        Ok((out.into_iter().map(|(d, _)| d).collect(), absent))
    }

    /// Adds and removes alternate per body; returns the bodies added first.
    fn check_sequence(
        &self,
        model: &Model,
        entries: &[(ScheduleDecl, &ScheduleSection)],
    ) -> Result<Vec<BodyId>, SceneError> {
        let mut present: Vec<Option<bool>> = vec![None; model.bodies().len()];
        let mut absent = Vec::new();
        for (d, e) in entries {
            let (b, adds, span) = match d.action {
                ScheduleAction::Add(b) => (b, true, e.add.as_ref().map(Spanned::span)),
                ScheduleAction::Remove(b) => (b, false, e.remove.as_ref().map(Spanned::span)),
                ScheduleAction::Mode(_) => continue,
            };
            let now = present[b.index()].unwrap_or_else(|| {
                if adds {
                    absent.push(b);
                }
                !adds
            });
            if now == adds {
                let name = &model.bodies()[b.index()].name;
                return Err(self.error_at(
                    span.unwrap_or(e.at.span()),
                    format!(
                        "`{name}` is {} at {} s: a body's entries alternate `add` and `remove`",
                        if adds {
                            "already in the scene"
                        } else {
                            "not in the scene"
                        },
                        d.at_s
                    ),
                ));
            }
            present[b.index()] = Some(adds);
        }
        Ok(absent)
    }

    /// The body a schedule entry names: a known moving body, on no joint,
    /// held by no point or rigid finger, and not in a scene with dynamics.
    fn scheduled_body(&self, model: &Model, name: &Spanned<String>) -> Result<BodyId, SceneError> {
        let s = &self.spec;
        let n = name.get_ref();
        let err = |m: String| Err(self.error_at(name.span(), m));
        let Some(b) = s.bodies.iter().find(|b| b.name.get_ref() == n) else {
            let names: Vec<&str> = s.bodies.iter().map(|b| b.name.get_ref().as_str()).collect();
            return err(format!("unknown body `{n}` (bodies: {})", list(&names)));
        };
        if b.fixed {
            return err(format!(
                "`{n}` is fixed: only moving bodies are added and removed"
            ));
        }
        let jointed = s
            .joints
            .iter()
            .any(|j| j.bodies.get_ref().0.iter().any(|x| x.get_ref() == n));
        let held = s
            .fingers
            .iter()
            .any(|f| f.body.as_ref().is_some_and(|x| x.get_ref() == n));
        if jointed || held {
            return err(format!(
                "`{n}` is {}: only free objects are added and removed",
                if jointed {
                    "on a joint"
                } else {
                    "held by a point or rigid finger"
                }
            ));
        }
        let dynamics = s.solver.dynamics.as_ref().map_or_else(
            || crate::dynamics::inertial_by_default(model),
            |d| *d.get_ref(),
        );
        if dynamics {
            return err(format!(
                "`{n}`: adding and removing bodies needs a scene without dynamics (an absent body \
                 would fall)"
            ));
        }
        Ok(model.body_id(n).expect("a declared body is in the model"))
    }
}
