//! Semantic checks of the parts of a scene the model builder never sees:
//! solver settings, devices and hands, which device drives which finger,
//! shapes, semantic areas and the label order. (Bodies, joints and fingers are
//! checked by [`ModelBuilder::build`](crate::ModelBuilder::build); the compiler
//! maps its errors back to spans.)
//!
//! Checks run in file order and the first failure is returned, so an error
//! always points at the first problem a reader meets.

use super::SceneError;
use super::spec::{AreaSection, Arr, DeviceSection, HandSection, SceneFile, ShapeSpec, Vec3};
use std::collections::{BTreeMap, HashMap};
use std::ops::Range;
use toml::Spanned;

pub(super) struct Checker<'a> {
    pub file: &'a str,
    pub text: &'a str,
}

type Check = Result<(), SceneError>;

impl Checker<'_> {
    pub fn err(&self, span: Range<usize>, msg: impl Into<String>) -> SceneError {
        SceneError::at(self.file, self.text, span, msg)
    }

    fn finite<const N: usize>(&self, v: &Spanned<Arr<f64, N>>, what: &str) -> Check {
        match v.get_ref().iter().find(|x| !x.is_finite()) {
            Some(x) => Err(self.err(
                v.span(),
                format!("{what} contains {x}; expected finite numbers"),
            )),
            None => Ok(()),
        }
    }

    pub(super) fn positive(&self, v: &Spanned<f64>, what: &str) -> Check {
        let x = *v.get_ref();
        if x.is_finite() && x > 0.0 {
            Ok(())
        } else {
            Err(self.err(
                v.span(),
                format!("{what} is {x}; expected a finite number > 0"),
            ))
        }
    }

    fn non_negative(&self, v: &Spanned<f64>, what: &str) -> Check {
        let x = *v.get_ref();
        if x.is_finite() && x >= 0.0 {
            Ok(())
        } else {
            Err(self.err(
                v.span(),
                format!("{what} is {x}; expected a finite number ≥ 0"),
            ))
        }
    }

    fn nonzero_vec(&self, v: Vec3, span: Range<usize>, what: &str) -> Check {
        let v = v.get();
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if !n.is_finite() {
            return Err(self.err(span, format!("{what} {v:?} is not finite")));
        }
        if n < 1e-12 {
            return Err(self.err(
                span,
                format!("{what} {v:?} has zero length; expected a direction"),
            ));
        }
        Ok(())
    }

    pub fn scene(&self, s: &SceneFile) -> Check {
        if s.scene.name.get_ref().trim().is_empty() {
            return Err(self.err(s.scene.name.span(), "scene name is empty"));
        }
        if let Some(g) = &s.scene.gravity {
            self.finite(g, "gravity")?;
        }
        self.solver(s)?;
        self.limits(s)?;
        for b in &s.bodies {
            if let Some(shape) = &b.shape {
                self.shape(shape)?;
            }
            for area in b.offer.iter().chain(&b.binding) {
                self.area(area)?;
            }
            if let Some(f) = &b.flexible
                && !(b.offer.is_empty() && b.binding.is_empty())
            {
                return Err(self.err(
                    f.span(),
                    format!(
                        "body `{}`: a flexible body cannot carry semantic areas (they would not bend)",
                        b.name.get_ref()
                    ),
                ));
            }
        }
        self.devices(s)?;
        self.finger_wiring(s)?;
        for f in &s.fingers {
            self.finger(f)?;
        }
        for o in &s.objectives {
            self.objective(o)?;
        }
        self.magnitudes(s)?;
        self.no_effect(s)?;
        self.labels(s)?;
        self.semantic(s)
    }

    /// The keys an objective's kind takes (the rest are errors at their
    /// place), the ones it needs, and `obstacle`'s either-or.
    fn objective(&self, o: &super::spec::ObjectiveSection) -> Check {
        use crate::ObjectiveKind as K;
        let kind = *o.kind.get_ref();
        let name = kind.as_str();
        let (takes, needs): (&[&str], &[&str]) = match kind {
            K::Finger => (&["weight"], &[]),
            K::LeastAstonishment => (&["weight", "design_weight"], &[]),
            K::Dexterity => (
                &[
                    "name",
                    "weight",
                    "chain",
                    "point",
                    "directions",
                    "angular_directions",
                    "closure",
                ],
                &["chain"],
            ),
            K::Obstacle => (
                &[
                    "name",
                    "weight",
                    "points",
                    "obstacle",
                    "obstacle_body",
                    "obstacle_point",
                    "distance",
                ],
                &["points", "distance"],
            ),
            K::StraightLine => (
                &["name", "weight", "body", "point", "line_point", "direction"],
                &["body", "line_point", "direction"],
            ),
            K::JointLimitDistance => (&["name", "weight", "joints"], &[]),
            K::InverseDistance => (
                &[
                    "name",
                    "weight",
                    "points",
                    "obstacle",
                    "obstacle_body",
                    "obstacle_point",
                ],
                &["points"],
            ),
            K::WorkspaceVolume => (&["name", "weight", "chain", "point"], &["chain"]),
        };
        let keys = o.keys();
        for (key, span) in &keys {
            if !takes.contains(key) {
                return Err(self.err(
                    span.clone(),
                    format!(
                        "a {name} objective has no `{key}`; it takes {}",
                        takes
                            .iter()
                            .map(|k| format!("`{k}`"))
                            .collect::<Vec<_>>()
                            .join(", ")
                    ),
                ));
            }
        }
        for need in needs {
            if !keys.iter().any(|(k, _)| k == need) {
                return Err(self.err(o.kind.span(), format!("a {name} objective needs `{need}`")));
            }
        }
        if matches!(kind, K::Obstacle | K::InverseDistance) {
            match (&o.obstacle, &o.obstacle_body) {
                (Some(_), Some(b)) => {
                    return Err(self.err(
                        b.span(),
                        "an obstacle is either a world point (`obstacle`) or a body's (`obstacle_body`), not both",
                    ));
                }
                (None, None) => {
                    return Err(self.err(
                        o.kind.span(),
                        format!("an {name} objective needs `obstacle = [x, y, z]` (a world point) or `obstacle_body` (a body's point)"),
                    ));
                }
                (Some(_), None) => {
                    if let Some(p) = &o.obstacle_point {
                        return Err(self.err(
                            p.span(),
                            "`obstacle_point` is a point of `obstacle_body`; a world `obstacle` takes none",
                        ));
                    }
                }
                (None, Some(_)) => {}
            }
        }
        for (v, what) in [
            (&o.weight, "weight"),
            (&o.design_weight, "design_weight"),
            (&o.distance, "distance"),
        ] {
            if let Some(v) = v {
                self.non_negative(v, what)?;
            }
        }
        Ok(())
    }

    /// A point or rigid finger holds a `body` (at `point`); a contact finger
    /// is a fingertip of its own that starts at `position`, with an optional
    /// `radius` and `friction`. Keys of the other kind are errors.
    fn finger(&self, f: &super::spec::FingerSection) -> Check {
        let contact = f
            .grasp
            .as_ref()
            .is_some_and(|g| *g.get_ref() == super::spec::GraspSpec::Contact);
        let name = f.name.get_ref();
        if contact {
            if let Some(b) = &f.body {
                return Err(self.err(
                    b.span(),
                    format!("finger `{name}`: a contact finger is a fingertip of its own; it takes `position`, not `body`"),
                ));
            }
            if let Some(p) = &f.point {
                return Err(self.err(
                    p.span(),
                    format!("finger `{name}`: a contact finger has no `point` (its fingertip's centre is the point)"),
                ));
            }
            let Some(p) = &f.position else {
                return Err(self.err(
                    f.name.span(),
                    format!("finger `{name}`: a contact finger needs `position` (where its fingertip starts, world frame)"),
                ));
            };
            self.finite(p, "position")?;
            if let Some(r) = &f.radius {
                self.positive(r, "radius")?;
            }
            if let Some(mu) = &f.friction {
                self.non_negative(mu, "friction")?;
            }
            return Ok(());
        }
        let what = f.grasp.as_ref().map_or("point", |g| match g.get_ref() {
            super::spec::GraspSpec::Rigid => "rigid",
            _ => "point",
        });
        for (key, span) in [
            ("position", f.position.as_ref().map(Spanned::span)),
            ("radius", f.radius.as_ref().map(Spanned::span)),
            ("friction", f.friction.as_ref().map(Spanned::span)),
        ] {
            if let Some(span) = span {
                return Err(self.err(
                    span,
                    format!("finger `{name}`: `{key}` belongs to contact fingers (grasp = \"contact\"); a {what} finger holds a `body` at a `point`"),
                ));
            }
        }
        if f.body.is_none() {
            return Err(self.err(
                f.name.span(),
                format!("finger `{name}`: a {what} finger needs `body` (the body it holds)"),
            ));
        }
        Ok(())
    }

    /// `[solver] coordinates`: one of the spellings of `Coordinates`.
    fn coordinates(&self, v: &super::spec::SolverSection) -> Check {
        if let Some(c) = &v.coordinates
            && crate::Coordinates::parse(c.get_ref()).is_none()
        {
            return Err(self.err(
                c.span(),
                format!(
                    "coordinates \"{}\" is not one of \"augmented\", \"joint\", \"auto\"",
                    c.get_ref()
                ),
            ));
        }
        Ok(())
    }

    fn solver(&self, s: &SceneFile) -> Check {
        let v = &s.solver;
        if let Some(r) = &v.rate_hz
            && !(100..=20_000).contains(r.get_ref())
        {
            return Err(self.err(
                r.span(),
                format!("rate_hz {} is outside 100–20000 Hz", r.get_ref()),
            ));
        }
        self.coordinates(v)?;
        if let Some(i) = &v.iterations
            && !(1..=10_000).contains(i.get_ref())
        {
            return Err(self.err(
                i.span(),
                format!("iterations {} is outside 1–10000", i.get_ref()),
            ));
        }
        for (x, what) in [
            (&v.step, "step"),
            (&v.gain, "gain"),
            (&v.placement_tolerance, "placement_tolerance"),
        ]
        .into_iter()
        .chain([
            (&v.violation_tolerance, "violation_tolerance"),
            (&v.contact_distance, "contact_distance"),
            (&v.penetration_tolerance, "penetration_tolerance"),
        ]) {
            if let Some(x) = x {
                self.positive(x, what)?;
            }
        }
        for (x, what) in [
            (&v.multiplier_gain, "multiplier_gain"),
            (&v.damping, "damping"),
            (&v.release_distance, "release_distance"),
            (&v.coupling_stiffness, "coupling_stiffness"),
            (&v.coupling_damping, "coupling_damping"),
            (&v.velocity_filter, "velocity_filter"),
        ] {
            if let Some(x) = x {
                self.non_negative(x, what)?;
            }
        }
        if let Some(f) = &v.velocity_filter
            && *f.get_ref() > 1.0
        {
            return Err(self.err(
                f.span(),
                format!(
                    "velocity_filter {} s is over 1 s; expected seconds, e.g. 0.01",
                    f.get_ref()
                ),
            ));
        }
        if let (Some(c), Some(r)) = (&v.contact_distance, &v.release_distance)
            && r.get_ref() < c.get_ref()
        {
            return Err(self.err(
                r.span(),
                format!(
                    "release_distance {} must not be below contact_distance {}",
                    r.get_ref(),
                    c.get_ref()
                ),
            ));
        }
        Ok(())
    }

    fn shape(&self, shape: &Spanned<ShapeSpec>) -> Check {
        let bad = |msg: String| Err(self.err(shape.span(), msg));
        let ok = |x: f64| x.is_finite() && x > 0.0;
        match shape.get_ref() {
            ShapeSpec::Box(h) if !h.iter().all(|&x| ok(x)) => bad(format!(
                "box half extents {:?} must be finite and > 0",
                h.get()
            )),
            ShapeSpec::Sphere(r) if !ok(*r) => {
                bad(format!("sphere radius {r} must be finite and > 0"))
            }
            ShapeSpec::Capsule {
                half_height,
                radius,
            } if !(ok(*radius) && half_height.is_finite() && *half_height >= 0.0) => bad(format!(
                "capsule half_height {half_height} / radius {radius} must be finite, radius > 0"
            )),
            ShapeSpec::Convex(pts) if pts.len() < 4 => bad(format!(
                "convex shape needs at least 4 points, got {}",
                pts.len()
            )),
            ShapeSpec::Convex(pts) if pts.iter().flatten().any(|x| !x.is_finite()) => {
                let k = pts
                    .iter()
                    .position(|p| p.iter().any(|x| !x.is_finite()))
                    .unwrap_or(0);
                bad(format!(
                    "convex shape point {} is {:?}; expected finite numbers",
                    k + 1,
                    pts[k].get()
                ))
            }
            _ => Ok(()),
        }
    }

    fn area(&self, a: &AreaSection) -> Check {
        if a.label.get_ref().trim().is_empty() {
            return Err(self.err(a.label.span(), "area label is empty"));
        }
        self.finite(&a.normal, "area normal")?;
        self.nonzero_vec(*a.normal.get_ref(), a.normal.span(), "area normal")?;
        super::polygon::check(
            &a.polygon
                .get_ref()
                .iter()
                .map(|p| p.get())
                .collect::<Vec<_>>(),
        )
        .map_err(|m| self.err(a.polygon.span(), m))
    }

    fn devices(&self, s: &SceneFile) -> Check {
        let mut seen: HashMap<&str, ()> = HashMap::new();
        for d in &s.devices {
            if seen.insert(d.name.get_ref(), ()).is_some() {
                return Err(self.err(
                    d.name.span(),
                    format!("device name `{}` is used twice", d.name.get_ref()),
                ));
            }
            self.device(d)?;
        }
        Ok(())
    }

    fn device(&self, d: &DeviceSection) -> Check {
        if let Some(sc) = &d.scale {
            self.positive(sc, "scale")?;
        }
        if let Some(q) = &d.orientation {
            self.finite(q, "orientation")?;
            let n = q.get_ref().iter().map(|x| x * x).sum::<f64>();
            if n < 1e-24 {
                return Err(self.err(
                    q.span(),
                    "orientation has zero length; expected a quaternion [w, x, y, z]",
                ));
            }
        }
        match &d.hand {
            Some(h) => self.hand(h),
            None => Ok(()),
        }
    }

    fn hand(&self, h: &Spanned<HandSection>) -> Check {
        // Bounds of a scripted hand: a session lasts at most a day, a hand
        // does not circle faster than 100 Hz or wider than 10 m.
        const MAX_HAND_SECONDS: f64 = 86_400.0;
        const MAX_HAND_HZ: f64 = 100.0;
        const MAX_HAND_RADIUS_M: f64 = 10.0;
        let hs = h.get_ref();
        let kinds = [
            hs.still.is_some(),
            hs.circle.is_some(),
            hs.line.is_some(),
            hs.trace.is_some(),
            hs.waypoints.is_some(),
        ];
        if kinds.iter().filter(|&&k| k).count() != 1 {
            return Err(self.err(
                h.span(),
                "hand needs exactly one of `still`, `circle`, `line`, `waypoints` or `trace`",
            ));
        }
        if let Some(w) = &hs.waypoints {
            const MAX_OFFSET_M: f64 = 10.0;
            let pts = w.get_ref();
            if pts.is_empty() {
                return Err(self.err(w.span(), "waypoints needs at least one `[t, dx, dy, dz]`"));
            }
            let mut last = f64::NEG_INFINITY;
            for (k, p) in pts.iter().enumerate() {
                let [t, dx, dy, dz] = p.get();
                if !(t.is_finite() && (0.0..=MAX_HAND_SECONDS).contains(&t)) {
                    return Err(self.err(
                        w.span(),
                        format!("waypoint {k}: time {t} s must be in [0, {MAX_HAND_SECONDS}]"),
                    ));
                }
                if t <= last {
                    return Err(self.err(
                        w.span(),
                        format!("waypoint {k}: time {t} s is not after the one before ({last} s); times must increase"),
                    ));
                }
                last = t;
                if ![dx, dy, dz]
                    .iter()
                    .all(|x| x.is_finite() && x.abs() <= MAX_OFFSET_M)
                {
                    return Err(self.err(
                        w.span(),
                        format!("waypoint {k}: offset [{dx}, {dy}, {dz}] must be finite and within ±{MAX_OFFSET_M} m"),
                    ));
                }
            }
        }
        if let Some(still) = &hs.still
            && !*still.get_ref()
        {
            return Err(self.err(
                still.span(),
                "`still = false` means nothing: write `still = true`, or give the hand a `circle`, `line` or `trace`",
            ));
        }
        if let Some(c) = &hs.circle {
            let cs = c.get_ref();
            let ok = cs.radius.is_finite()
                && (0.0..=MAX_HAND_RADIUS_M).contains(&cs.radius)
                && cs.hz.is_finite()
                && (0.0..=MAX_HAND_HZ).contains(&cs.hz);
            if !ok {
                return Err(self.err(
                    c.span(),
                    format!(
                        "circle radius {} m / hz {} must be finite, radius 0–{MAX_HAND_RADIUS_M} m, hz 0–{MAX_HAND_HZ}",
                        cs.radius, cs.hz
                    ),
                ));
            }
            self.nonzero_vec(cs.u, c.span(), "circle u")?;
            self.nonzero_vec(cs.v, c.span(), "circle v")?;
        }
        if let Some(l) = &hs.line {
            let ls = l.get_ref();
            if !(ls.to.iter().all(|x| x.is_finite())
                && ls.seconds.is_finite()
                && ls.seconds > 0.0
                && ls.seconds <= MAX_HAND_SECONDS)
            {
                return Err(self.err(
                    l.span(),
                    format!(
                        "line `to` must be finite and `seconds` in (0, {MAX_HAND_SECONDS}], got {}",
                        ls.seconds
                    ),
                ));
            }
        }
        if let Some(k) = &hs.stiffness {
            self.non_negative(k, "hand stiffness")?;
        }
        if let Some(b) = &hs.damping {
            self.non_negative(b, "hand damping")?;
        }
        Ok(())
    }

    /// Every finger names a known device, and every device drives exactly one
    /// finger (a device has one tip).
    fn finger_wiring(&self, s: &SceneFile) -> Check {
        let mut driven: HashMap<&str, &str> = HashMap::new();
        for f in &s.fingers {
            let dev = f.device.get_ref().as_str();
            if !s.devices.iter().any(|d| d.name.get_ref() == dev) {
                let known: Vec<&str> = s
                    .devices
                    .iter()
                    .map(|d| d.name.get_ref().as_str())
                    .collect();
                return Err(self.err(
                    f.device.span(),
                    format!(
                        "finger `{}` names unknown device `{dev}` (devices: {})",
                        f.name.get_ref(),
                        list(&known)
                    ),
                ));
            }
            if let Some(other) = driven.insert(dev, f.name.get_ref()) {
                return Err(self.err(
                    f.device.span(),
                    format!(
                        "device `{dev}` already drives finger `{other}`; a device drives one finger"
                    ),
                ));
            }
        }
        if let Some(d) = s
            .devices
            .iter()
            .find(|d| !driven.contains_key(d.name.get_ref().as_str()))
        {
            return Err(self.err(
                d.name.span(),
                format!("device `{}` drives no finger", d.name.get_ref()),
            ));
        }
        Ok(())
    }

    /// The label order must be a partial order: no cycles.
    fn labels(&self, s: &SceneFile) -> Check {
        let mut edges: BTreeMap<&str, Vec<(&str, Range<usize>)>> = BTreeMap::new();
        for (k, vs) in &s.labels {
            for v in vs.get_ref() {
                if v.get_ref().trim().is_empty() {
                    return Err(self.err(v.span(), "label is empty"));
                }
                edges
                    .entry(k.get_ref())
                    .or_default()
                    .push((v.get_ref(), v.span()));
            }
        }
        // Depth-first search with colours, iterative (a chain of labels is as
        // deep as it is long); report the edge that closes a cycle.
        let mut state: HashMap<&str, u8> = HashMap::new();
        let none: &[(&str, Range<usize>)] = &[];
        for &root in edges.keys() {
            if state.get(root).copied().unwrap_or(0) != 0 {
                continue;
            }
            state.insert(root, 1);
            let mut path: Vec<(&str, usize)> = vec![(root, 0)];
            while let Some(&mut (n, ref mut k)) = path.last_mut() {
                let out = edges.get(n).map_or(none, Vec::as_slice);
                let Some((m, span)) = out.get(*k) else {
                    state.insert(n, 2);
                    path.pop();
                    continue;
                };
                *k += 1;
                match state.get(m).copied().unwrap_or(0) {
                    1 => {
                        let start = path.iter().position(|(p, _)| p == m).unwrap_or(0);
                        let mut cycle: Vec<&str> = path[start..].iter().map(|(p, _)| *p).collect();
                        cycle.push(m);
                        return Err(self.err(
                            span.clone(),
                            format!("label order has a cycle: {}", cycle.join(" ≤ ")),
                        ));
                    }
                    0 => {
                        state.insert(m, 1);
                        path.push((m, 0));
                    }
                    _ => {}
                }
            }
        }
        Ok(())
    }
}

pub(super) fn list(names: &[&str]) -> String {
    if names.is_empty() {
        "none".into()
    } else {
        names.join(", ")
    }
}
