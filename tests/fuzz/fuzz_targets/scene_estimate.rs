//! Fuzz target: arbitrary bytes as a scene file, optionally followed by a
//! NUL byte and a markers file, then what `softrod estimate` does with them:
//! parse, build, solve, and estimate through both backends (newton, sqp),
//! the estimator kept warm over the frames. Without a markers file the
//! markers are synthesized on the solved shape (`Observation::of_sites` at
//! the scene's markers, or the tip) with noise of the stated σ seeded by
//! the input's hash. Every answer is held to the invariants of
//! `tests/common/scene_checks.rs`; the work per input is capped there.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../../common/scene_checks.rs"]
mod scene_checks;

fuzz_target!(|data: &[u8]| {
    if let Some((scene, markers)) = scene_checks::split_input(data) {
        scene_checks::estimate_scene(scene, markers, scene_checks::seed_of(data));
    }
});
