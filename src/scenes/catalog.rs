//! Which paper, and which figure or section of it, each built-in scene shows:
//! `haptloop scenes` prints the built-ins grouped by it, and `docs/papers.md`
//! is the same map from the papers' side. A scene of our own (a stress case,
//! a classic linkage the papers do not draw) is listed under
//! [`Source::Own`]. Every built-in scene is in [`CATALOG`] exactly once (the
//! unit test below): a new scene is not done until it says where it comes from.

/// Where a scene comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Source {
    /// Nelson & Cohen, "Interactive Mechanical Design Variation for Haptics and CAD" (Eurographics 1999).
    NelsonCohen,
    /// Choi & Cremer, "Geometrically-Aware Interactive Object Manipulation".
    ChoiCremer,
    /// Gösele & Stuerzlinger, "Semantic Constraints for Scene Manipulation".
    GoseleStuerzlinger,
    /// Not a figure of any of the three papers.
    Own,
}

impl Source {
    /// Every source, in the order `haptloop scenes` prints them.
    pub const ALL: [Source; 4] = [
        Source::NelsonCohen,
        Source::ChoiCremer,
        Source::GoseleStuerzlinger,
        Source::Own,
    ];

    /// The group's heading.
    pub fn title(self) -> &'static str {
        match self {
            Source::NelsonCohen => {
                "Nelson & Cohen, Interactive Mechanical Design Variation for Haptics and CAD"
            }
            Source::ChoiCremer => {
                "Choi & Cremer, Geometrically-Aware Interactive Object Manipulation"
            }
            Source::GoseleStuerzlinger => {
                "Gösele & Stuerzlinger, Semantic Constraints for Scene Manipulation"
            }
            Source::Own => "haptloop's own",
        }
    }
}

/// One built-in scene's place in the papers.
pub struct Entry {
    /// The built-in scene's name.
    pub scene: &'static str,
    /// The paper it comes from.
    pub source: Source,
    /// The figure, section or equation it shows (what it is, for our own).
    pub item: &'static str,
}

const fn entry(scene: &'static str, source: Source, item: &'static str) -> Entry {
    Entry {
        scene,
        source,
        item,
    }
}

use Source::{ChoiCremer, GoseleStuerzlinger, NelsonCohen, Own};

/// Every built-in scene, grouped by source and in the papers' order within one.
pub const CATALOG: &[Entry] = &[
    entry("sphere-toy", NelsonCohen, "Fig. 1"),
    entry("stewart-3rsu", NelsonCohen, "Figs. 2/3 (3R-3S-3U platform)"),
    entry("quarter-torus", NelsonCohen, "Figs. 6/7 (closed loop)"),
    entry("grasp-2", NelsonCohen, "§5.3, Fig. 8 (two hands)"),
    entry("grasp-3", NelsonCohen, "§5.3 (rigid and point fingers)"),
    entry("flexible-ik", NelsonCohen, "Fig. 9, §4 Eq. 4"),
    entry("peaucellier", NelsonCohen, "Fig. 10 (the linkage)"),
    entry(
        "four-bar-cardan",
        NelsonCohen,
        "Fig. 11 (four-bar and U-joint)",
    ),
    entry("piston", NelsonCohen, "Fig. 12 (gears, slider-cranks)"),
    entry("peaucellier-design", NelsonCohen, "Fig. 10 (the objective)"),
    entry("dodge", NelsonCohen, "App. D Eq. 15 (Fig. 13's bullet)"),
    entry("dodge-belly", NelsonCohen, "Fig. 13"),
    entry("four-bar", NelsonCohen, "Fig. 14 (the linkage)"),
    entry("four-bar-design", NelsonCohen, "Fig. 14 (joint location)"),
    entry("stewart", NelsonCohen, "Fig. 15 (the platform)"),
    entry("stewart-feet", NelsonCohen, "Fig. 15 (the feet)"),
    entry("dexterity-arm", NelsonCohen, "App. C Eq. 12–14"),
    entry("ball-bowl", NelsonCohen, "App. E Eq. 16"),
    entry("cluttered", ChoiCremer, "§1 (cluttered scenes)"),
    entry("pyramid-tilt", ChoiCremer, "§3.2.1, Fig. 6"),
    entry("box-slide", ChoiCremer, "§3.1–3.2 (witness changes)"),
    entry("sit-on-chair", ChoiCremer, "Fig. 1 (a figure onto a chair)"),
    entry("room", GoseleStuerzlinger, "Fig. 1, 3, 4 (§3–5)"),
    entry(
        "board-wall",
        GoseleStuerzlinger,
        "Fig. 5/6 (undirected cycle); §3.3 add/remove, §6 modes",
    ),
    entry("sphere-toy-400", Own, "Fig. 1's toy at 400 bodies"),
    entry("bennett", Own, "overconstrained loop"),
    entry("lattice", Own, "64 loops"),
    entry("chain", Own, "a 64-link closed chain"),
    entry("door", Own, "inertial motion: a hinge against a stop"),
    entry("pendulum-wall", Own, "inertial motion: a swing, a bounce"),
    entry("arm-push", Own, "a jointed arm pushing a box"),
    entry("stack", Own, "friction between bodies"),
    entry("peg-in-hole", Own, "tight clearance"),
    entry("pinch-lift", Own, "friction grasp"),
    entry("grasp-3-contact", Own, "friction grasp, three arms"),
];

/// The catalogue entry of the built-in scene `name`, if it has one.
pub fn find(name: &str) -> Option<&'static Entry> {
    CATALOG.iter().find(|e| e.scene == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenes::BUILTIN;

    #[test]
    fn every_builtin_scene_is_catalogued_exactly_once_and_nothing_else_is() {
        for b in BUILTIN {
            let n = CATALOG.iter().filter(|e| e.scene == b.name).count();
            assert_eq!(
                n, 1,
                "built-in scene `{}` is in src/scenes/catalog.rs {n} times (want once)",
                b.name
            );
        }
        for e in CATALOG {
            assert!(
                BUILTIN.iter().any(|b| b.name == e.scene),
                "src/scenes/catalog.rs names `{}`, which is no built-in scene",
                e.scene
            );
            assert!(!e.item.is_empty(), "`{}` has no item", e.scene);
        }
    }
}
