//! Scene loading, validation and compilation on arbitrary bytes: whatever
//! the input, the loader returns a scene or a located error, never panics,
//! and the error prints (clipped, control characters escaped) without
//! panicking either. Seeds: `scenes/` and `tests/data/bad-scenes/`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match haptloop_solver::scene::parse("fuzz.toml", text, None) {
        Ok(loaded) => match haptloop::scenes::check_loaded(loaded) {
            Ok(scene) => {
                // Evaluate the compiled model at q0: finite inputs were
                // promised by validation.
                let m = &scene.compiled.model;
                let mut ev = m.evaluation();
                let _ = ev.evaluate(m, m.q0(), &m.initial_targets());
            }
            Err(e) => {
                let shown = e.to_string();
                assert!(!shown.chars().any(|c| c.is_control() && c != '\n'));
            }
        },
        Err(e) => {
            let shown = e.to_string();
            assert!(!shown.chars().any(|c| c.is_control() && c != '\n'));
        }
    }
});
