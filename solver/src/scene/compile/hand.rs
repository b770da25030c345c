//! A `[[device]]`'s simulated hand as a [`HandDecl`].

use super::decl::{HandDecl, HandPath};
use crate::scene::LoadedScene;
use std::path::PathBuf;
use toml::Spanned;

impl LoadedScene {
    pub(super) fn hand(&self, hand: Option<&Spanned<crate::scene::spec::HandSection>>) -> HandDecl {
        let Some(h) = hand.map(Spanned::get_ref) else {
            return HandDecl {
                path: HandPath::Still,
                stiffness_n_per_m: None,
                damping_n_s_per_m: None,
            };
        };
        let path = if let Some(c) = &h.circle {
            let c = c.get_ref();
            HandPath::Circle {
                radius_m: c.radius,
                hz: c.hz,
                u: c.u.get(),
                v: c.v.get(),
            }
        } else if let Some(l) = &h.line {
            HandPath::Line {
                to_m: l.get_ref().to.get(),
                seconds: l.get_ref().seconds,
            }
        } else if let Some(w) = &h.waypoints {
            HandPath::Waypoints {
                points: w.get_ref().iter().map(|p| p.get()).collect(),
            }
        } else if let Some(t) = &h.trace {
            let rel = PathBuf::from(t.get_ref());
            let path = match &self.dir {
                Some(dir) if rel.is_relative() => dir.join(rel),
                _ => rel,
            };
            HandPath::Trace {
                path,
                span: t.span(),
            }
        } else {
            HandPath::Still
        };
        HandDecl {
            path,
            stiffness_n_per_m: h.stiffness.as_ref().map(|x| *x.get_ref()),
            damping_n_s_per_m: h.damping.as_ref().map(|x| *x.get_ref()),
        }
    }
}
