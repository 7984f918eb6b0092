//! The trust radius of the sqp backend's steps (see the module
//! documentation of `sqp`, "Globalization").

/// The trust radius after a step accepted at `t` (the fraction of the QP
/// step taken), of radius `radius` (m), which cut the step if `cut`: twice
/// as large after a full step it cut (the linearization held over the whole
/// radius), up to the robot's length `len`; after a backtracked step the
/// step's own length, at least a quarter of the radius and never below the
/// start `start` (`max_observation_jump_m`); unchanged otherwise.
pub(super) fn next_radius(radius: f64, t: f64, cut: bool, start: f64, len: f64) -> f64 {
    if t == 1.0 {
        if cut {
            (2.0 * radius).min(len.max(start))
        } else {
            radius
        }
    } else {
        (radius * t.max(0.25)).max(start)
    }
}

#[cfg(test)]
mod tests {
    use super::next_radius;

    /// From the start (2 cm on a 24 cm robot): a full step the radius cut
    /// doubles it, up to the robot's length; a full step it did not cut
    /// leaves it; a backtracked step shrinks it to the step taken (at
    /// least a quarter of it), never below the start.
    #[test]
    fn radius_grows_after_full_cut_steps_and_shrinks_after_backtracking() {
        let (start, len) = (0.02, 0.24);
        let mut r = start;
        for expected in [0.04, 0.08, 0.16, 0.24, 0.24] {
            r = next_radius(r, 1.0, true, start, len);
            assert!((r - expected).abs() < 1e-15, "{r} != {expected}");
        }
        assert_eq!(next_radius(0.16, 1.0, false, start, len), 0.16);
        assert!((next_radius(0.16, 0.5, true, start, len) - 0.08).abs() < 1e-15);
        assert!((next_radius(0.16, 0.01, true, start, len) - 0.04).abs() < 1e-15);
        assert_eq!(next_radius(0.03, 0.125, true, start, len), start);
        // a robot shorter than the start keeps the start
        assert_eq!(next_radius(start, 1.0, true, start, 0.01), start);
    }
}
