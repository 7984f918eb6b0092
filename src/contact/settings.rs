//! The contact solver's settings.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_at_most, check_positive};

/// Settings of the contact solver; every field has a documented default.
///
/// # Example
/// ```
/// let s = softrod::contact::ContactSettings { penetration_tolerance_m: 1e-11, ..Default::default() };
/// s.validate().unwrap();
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactSettings {
    /// SQP iterations (default 200).
    pub max_iterations: usize,
    /// Newton iterations on the KKT system per active set (default 30).
    pub max_newton_iterations: usize,
    /// Changes of the active set after the SQP (default 20).
    pub max_active_set_changes: usize,
    /// Tolerance of the equilibrium residual with the contact forces,
    /// relative to the applied generalized forces (default 1e-10).
    pub residual_tolerance: f64,
    /// Largest penetration a converged solution may have (m; default
    /// 1e-10, at most 1e-9).
    pub penetration_tolerance_m: f64,
    /// Largest change of a node slope in one step, about the rotation in
    /// rad (default 0.5).
    pub max_step_rotation: f64,
}

impl Default for ContactSettings {
    fn default() -> Self {
        ContactSettings {
            max_iterations: 200,
            max_newton_iterations: 30,
            max_active_set_changes: 20,
            residual_tolerance: 1e-10,
            penetration_tolerance_m: 1e-10,
            max_step_rotation: 0.5,
        }
    }
}

impl ContactSettings {
    /// Checks every field: counts in `1..=100000`, tolerances positive (the
    /// relative one below 1, the penetration at most 1e-9 m), the step
    /// rotation positive.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] or [`Error::TooLarge`] naming the field.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("max_iterations", self.max_iterations),
            ("max_newton_iterations", self.max_newton_iterations),
            ("max_active_set_changes", self.max_active_set_changes),
        ] {
            if v == 0 {
                return Err(Error::invalid(name, v, "must be >= 1"));
            }
            check_at_most(name, v, 100_000)?;
        }
        check_positive("residual_tolerance", self.residual_tolerance)?;
        if self.residual_tolerance >= 1.0 {
            return Err(Error::invalid(
                "residual_tolerance",
                self.residual_tolerance,
                "must be < 1",
            ));
        }
        check_positive("penetration_tolerance_m", self.penetration_tolerance_m)?;
        if self.penetration_tolerance_m > 1e-9 {
            return Err(Error::invalid(
                "penetration_tolerance_m",
                self.penetration_tolerance_m,
                "must be <= 1e-9",
            ));
        }
        check_positive("max_step_rotation", self.max_step_rotation)
    }
}
