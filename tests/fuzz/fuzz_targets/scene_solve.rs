//! Fuzz target: arbitrary bytes as a scene file, then everything `softrod
//! solve` does with it (parse, validate, build, solve, read markers back,
//! warm-start a second solve), every answer held to the invariants of
//! `tests/common/scene_checks.rs`.
#![no_main]

use libfuzzer_sys::fuzz_target;

#[path = "../../common/scene_checks.rs"]
mod scene_checks;

fuzz_target!(|data: &[u8]| {
    if let Some((scene, _)) = scene_checks::split_input(data) {
        scene_checks::solve_scene(scene);
    }
});
