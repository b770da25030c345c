//! Built-in scenes (embedded, so `haptloop run four-bar` works from any
//! directory), generated ones (`lattice-8x32`: [`generated`]) and resolution
//! of a `SCENE|FILE` argument into a checked scene. [`catalog`] says which
//! paper and figure each built-in scene shows.

pub mod catalog;
pub mod generated;

use haptloop_devices::{HandTrace, KNOWN_MODELS, PhantomModel, VIRTUAL_MODEL};
use haptloop_solver::scene::{self, CompiledScene, HandPath, LoadedScene, SceneError};
use std::path::Path;

/// A scene shipped inside the binary.
pub struct Builtin {
    /// Name on the command line.
    pub name: &'static str,
    /// The TOML text (also in `scenes/<name>.toml`).
    pub text: &'static str,
}

/// The built-in scenes, default first.
pub const BUILTIN: &[Builtin] = &[
    Builtin {
        name: "four-bar",
        text: include_str!("../scenes/four-bar.toml"),
    },
    Builtin {
        name: "stewart",
        text: include_str!("../scenes/stewart.toml"),
    },
    Builtin {
        name: "peaucellier",
        text: include_str!("../scenes/peaucellier.toml"),
    },
    Builtin {
        name: "sphere-toy",
        text: include_str!("../scenes/sphere-toy.toml"),
    },
    Builtin {
        name: "sphere-toy-400",
        text: include_str!("../scenes/sphere-toy-400.toml"),
    },
    Builtin {
        name: "grasp-2",
        text: include_str!("../scenes/grasp-2.toml"),
    },
    Builtin {
        name: "grasp-3",
        text: include_str!("../scenes/grasp-3.toml"),
    },
    Builtin {
        name: "pyramid-tilt",
        text: include_str!("../scenes/pyramid-tilt.toml"),
    },
    Builtin {
        name: "box-slide",
        text: include_str!("../scenes/box-slide.toml"),
    },
    Builtin {
        name: "stack",
        text: include_str!("../scenes/stack.toml"),
    },
    Builtin {
        name: "peg-in-hole",
        text: include_str!("../scenes/peg-in-hole.toml"),
    },
    Builtin {
        name: "pinch-lift",
        text: include_str!("../scenes/pinch-lift.toml"),
    },
    Builtin {
        name: "room",
        text: include_str!("../scenes/room.toml"),
    },
    Builtin {
        name: "board-wall",
        text: include_str!("../scenes/board-wall.toml"),
    },
    Builtin {
        name: "grasp-3-contact",
        text: include_str!("../scenes/grasp-3-contact.toml"),
    },
    Builtin {
        name: "cluttered",
        text: include_str!("../scenes/cluttered.toml"),
    },
    Builtin {
        name: "door",
        text: include_str!("../scenes/door.toml"),
    },
    Builtin {
        name: "pendulum-wall",
        text: include_str!("../scenes/pendulum-wall.toml"),
    },
    Builtin {
        name: "arm-push",
        text: include_str!("../scenes/arm-push.toml"),
    },
    Builtin {
        name: "sit-on-chair",
        text: include_str!("../scenes/sit-on-chair.toml"),
    },
    Builtin {
        name: "four-bar-design",
        text: include_str!("../scenes/four-bar-design.toml"),
    },
    Builtin {
        name: "peaucellier-design",
        text: include_str!("../scenes/peaucellier-design.toml"),
    },
    Builtin {
        name: "stewart-feet",
        text: include_str!("../scenes/stewart-feet.toml"),
    },
    Builtin {
        name: "dexterity-arm",
        text: include_str!("../scenes/dexterity-arm.toml"),
    },
    Builtin {
        name: "dodge",
        text: include_str!("../scenes/dodge.toml"),
    },
    Builtin {
        name: "stewart-3rsu",
        text: include_str!("../scenes/stewart-3rsu.toml"),
    },
    Builtin {
        name: "quarter-torus",
        text: include_str!("../scenes/quarter-torus.toml"),
    },
    Builtin {
        name: "four-bar-cardan",
        text: include_str!("../scenes/four-bar-cardan.toml"),
    },
    Builtin {
        name: "piston",
        text: include_str!("../scenes/piston.toml"),
    },
    Builtin {
        name: "bennett",
        text: include_str!("../scenes/bennett.toml"),
    },
    Builtin {
        name: "lattice",
        text: include_str!("../scenes/lattice.toml"),
    },
    Builtin {
        name: "chain",
        text: include_str!("../scenes/chain.toml"),
    },
    Builtin {
        name: "flexible-ik",
        text: include_str!("../scenes/flexible-ik.toml"),
    },
    Builtin {
        name: "dodge-belly",
        text: include_str!("../scenes/dodge-belly.toml"),
    },
    Builtin {
        name: "ball-bowl",
        text: include_str!("../scenes/ball-bowl.toml"),
    },
];

/// The scene `haptloop` runs with no arguments.
pub const DEFAULT_SCENE: &str = "four-bar";

/// A scene ready for a session: the file, its compiled model, and the hand
/// traces it references, loaded and checked.
pub struct Scene {
    /// The parsed file (kept for error messages).
    pub loaded: LoadedScene,
    /// What it compiles to.
    pub compiled: CompiledScene,
    /// One entry per device: its hand trace, if the hand follows one.
    pub traces: Vec<Option<HandTrace>>,
}

impl Scene {
    /// The scene with every device replaced by `model` (`--device`): a
    /// known model, else an error listing them. A virtual device drops its
    /// scripted hand (the live page moves it).
    pub fn with_device_model(mut self, model: &str) -> Result<Scene, String> {
        if model != VIRTUAL_MODEL && PhantomModel::by_name(model).is_err() {
            return Err(format!(
                "--device: unknown device model `{model}`; known models: {}, {VIRTUAL_MODEL}",
                KNOWN_MODELS.join(", ")
            ));
        }
        for (d, trace) in self.compiled.devices.iter_mut().zip(&mut self.traces) {
            d.model = model.to_owned();
            if model == VIRTUAL_MODEL {
                d.hand.path = HandPath::Still;
                *trace = None;
            }
        }
        Ok(self)
    }
}

/// Resolves `arg` (a built-in name, a path, or a generated name such as
/// `lattice-8x32`), then parses, validates and compiles it, checks device
/// models and loads hand traces. Every error names the file, line and column.
pub fn resolve(arg: &str) -> Result<Scene, SceneError> {
    check_loaded(load(arg)?)
}

/// Resolves `arg` as [`resolve`] does, up to the parsed file.
pub fn load(arg: &str) -> Result<LoadedScene, SceneError> {
    let builtin = |name: &str| BUILTIN.iter().find(|b| b.name == name);
    if let Some(b) = builtin(arg) {
        return scene::parse(
            &format!("scenes/{}.toml", b.name),
            b.text,
            Some(Path::new("scenes")),
        );
    }
    if Path::new(arg).exists() {
        return scene::load(Path::new(arg));
    }
    if let Some((family, size)) = generated::family_of(arg) {
        let base = builtin(family.prefix).expect("every generated family has a built-in");
        let text = generated::text(family, size, base.text).map_err(|e| {
            SceneError::whole_file(arg, format!("generated `{}` scene: {e}", family.prefix))
        })?;
        return scene::parse(
            &format!("scenes/{arg}.toml"),
            &text,
            Some(Path::new("scenes")),
        );
    }
    let names: Vec<&str> = BUILTIN.iter().map(|b| b.name).collect();
    let families: Vec<String> = generated::FAMILIES
        .iter()
        .map(|f| format!("{}-SIZE", f.prefix))
        .collect();
    Err(SceneError::whole_file(
        arg,
        format!(
            "no such file, and not a built-in scene ({}) or a generated one ({})",
            names.join(", "),
            families.join(", ")
        ),
    ))
}

/// Compiles a loaded scene and checks what only the device crate knows.
pub fn check_loaded(loaded: LoadedScene) -> Result<Scene, SceneError> {
    let compiled = loaded.compile()?;
    let mut traces = Vec::with_capacity(compiled.devices.len());
    for d in &compiled.devices {
        if d.model != VIRTUAL_MODEL && PhantomModel::by_name(&d.model).is_err() {
            return Err(loaded.error_at(
                d.model_span.clone(),
                format!(
                    "unknown device model `{}`; known models: {}, {VIRTUAL_MODEL}",
                    d.model,
                    KNOWN_MODELS.join(", ")
                ),
            ));
        }
        if d.model == VIRTUAL_MODEL && d.hand.path != HandPath::Still {
            return Err(loaded.error_at(
                d.model_span.clone(),
                format!(
                    "device `{}` is virtual: the live page's mouse moves it, not a scripted `hand` (remove `hand`, or use a PHANToM model)",
                    d.name
                ),
            ));
        }
        traces.push(match &d.hand.path {
            HandPath::Trace { path, span } => Some(
                HandTrace::load(path)
                    .map_err(|e| loaded.error_at(span.clone(), format!("hand trace: {e}")))?,
            ),
            _ => None,
        });
    }
    Ok(Scene {
        loaded,
        compiled,
        traces,
    })
}
