//! The crate's error type.
//!
//! Every fallible call in `softrod` returns [`Result<T>`](Result). Variants carry
//! the data that says what was wrong and where (the field name, the index, the
//! solver report), so a caller can react programmatically and a person can read
//! the message.
//!
//! There is one error enum for the whole crate, not one per module: the
//! modules share most failure kinds (a bad parameter, a wrong size, an absurd
//! size, an index off the end, a failed solve), and a caller in a control loop
//! matches on the kind, not on the module it came from. The enum is
//! `#[non_exhaustive]`, so variants can be added without breaking callers.
//! [`Error::field`] gives the name of the field at fault.
//!
//! What a failed solve reports (its status, its report) is plain data from
//! [`crate::outcome`], which depends on no solver: this module imports no
//! solver module, so no module cycle runs through the error type.

use crate::outcome::{ContactReport, EstimateStatus, RefinementFailure, StaticReport};

/// Errors returned by `softrod`.
///
/// # Example
/// ```
/// use softrod::{Error, element::PlanarCable};
/// let err = PlanarCable::new(-1.0, 300.0, 0.025).unwrap_err();
/// assert!(matches!(err, Error::InvalidParameter { ref name, .. } if name == "length_m"));
/// ```
#[derive(Debug, Clone, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A parameter has a value outside its valid range (or is not finite).
    #[error("invalid parameter `{name}` = {value}: {reason}")]
    InvalidParameter {
        /// The parameter's name (with its path in a scene, e.g. `robot.sections[1].ei_nm2`).
        name: String,
        /// The offending value, as text.
        value: String,
        /// What the valid range is.
        reason: String,
    },
    /// A size or count exceeds what the library accepts; refused before
    /// anything proportional to it is allocated.
    #[error("`{name}` = {value} is too large: at most {max}")]
    TooLarge {
        /// The field's name (with its path in a scene).
        name: String,
        /// The requested size.
        value: usize,
        /// The largest accepted size.
        max: usize,
    },
    /// An index (a node, a row) is outside its range.
    #[error("index `{name}` = {index} is out of range: must be below {len}")]
    IndexOutOfRange {
        /// The field's name (with its path in a scene).
        name: String,
        /// The offending index.
        index: usize,
        /// The number of valid indices.
        len: usize,
    },
    /// A vector or matrix has the wrong size.
    #[error("dimension mismatch in `{name}`: expected {expected}, got {got}")]
    DimensionMismatch {
        /// What was passed.
        name: String,
        /// The size that was expected.
        expected: usize,
        /// The size that was given.
        got: usize,
    },
    /// A linear system could not be solved: a pivot vanished.
    #[error("singular matrix in {context}: pivot {index} is {pivot:e} (its row's scale {scale:e})")]
    Singular {
        /// Which matrix (e.g. "tangent stiffness").
        context: String,
        /// Row/column of the vanishing pivot.
        index: usize,
        /// The pivot's value.
        pivot: f64,
        /// The largest absolute entry of the pivot's row.
        scale: f64,
    },
    /// The static (equilibrium) solver did not converge.
    #[error("static solve did not converge: {report}")]
    NotConverged {
        /// What the solver reached before it stopped.
        report: Box<StaticReport>,
    },
    /// A contact solve (rod against obstacles) did not reach a
    /// non-penetrating equilibrium: its report says why.
    #[error("contact solve did not converge: {report}")]
    ContactNotConverged {
        /// What the contact solver reached before it stopped.
        report: Box<ContactReport>,
    },
    /// A matrix that must be positive definite (a Gauss–Newton system) is not.
    #[error("{context} is not positive definite")]
    NotPositiveDefinite {
        /// Which matrix.
        context: String,
    },
    /// A factorization that was required to be positive definite met a
    /// pivot that is not clearly positive (the linear solver's
    /// `NotPositiveDefinite`, with its data).
    #[error("{context}: not positive definite, pivot {pivot:e} at row {index}")]
    NonPositivePivot {
        /// Which matrix.
        context: String,
        /// Row of the pivot (of the matrix as given, not of a reordering).
        index: usize,
        /// The pivot (of the Jacobi-scaled matrix, whose diagonal is 1 + shift).
        pivot: f64,
    },
    /// An estimate did not converge and the caller asked for a converged one
    /// ([`crate::estimate::Estimate::converged`]); the estimators themselves
    /// return their last iterate with its status.
    #[error("estimation did not converge: {status} ({iterations} outer iterations)")]
    EstimateNotConverged {
        /// How the estimation ended.
        status: EstimateStatus,
        /// Outer iterations taken.
        iterations: usize,
    },
    /// The refinement of `"elements": "auto"` sections did not reach its
    /// tolerance (see [`crate::refine`]).
    #[error("refinement did not reach its tolerance: {report}")]
    RefinementNotConverged {
        /// The target, every mesh tried and why the refinement stopped.
        report: Box<RefinementFailure>,
    },
    /// A scene file could not be read or is malformed.
    #[error("scene: {message}")]
    Scene {
        /// What is wrong, naming the field where possible.
        message: String,
    },
    /// Reading or writing a file failed (a reference file, a report output).
    #[error("input/output failed for `{path}`: {message}")]
    Io {
        /// The file or directory.
        path: String,
        /// What went wrong.
        message: String,
    },
    /// A result record (the input of `softrod plot`) that has no picture:
    /// not a softrod record of format "1", or a kind that is not drawn.
    #[error(
        "`{path}`: a record of format_version `{format_version}`, command `{command}`, scene_kind `{scene_kind}` has no picture (`softrod plot` draws format \"1\" records of `solve` and `estimate` on robot scenes, `solve` on parallel robots and `avoid`)"
    )]
    UnsupportedRecord {
        /// The file read.
        path: String,
        /// Its `format_version` (`(none)` if absent).
        format_version: String,
        /// Its `command` (`(none)` if absent).
        command: String,
        /// Its `scene_kind` (`(none)` if absent).
        scene_kind: String,
    },
    /// A computation produced a value that is not finite.
    #[error("non-finite value in {context}")]
    NonFinite {
        /// Where it appeared.
        context: String,
    },
    /// An allocation failed (the factors of a linear solve, a workspace).
    #[error("out of memory in {context}")]
    OutOfMemory {
        /// What was being allocated.
        context: String,
    },
}

/// `Result` with the crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl Error {
    /// Shorthand for [`Error::InvalidParameter`].
    pub(crate) fn invalid(
        name: impl Into<String>,
        value: impl ToString,
        reason: impl Into<String>,
    ) -> Self {
        let mut value = value.to_string();
        // `f64`'s Display writes 1e-320 with 320 digits: keep messages short
        if value.len() > 24
            && let Ok(v) = value.parse::<f64>()
        {
            value = format!("{v:e}");
        }
        Error::InvalidParameter {
            name: name.into(),
            value,
            reason: reason.into(),
        }
    }
}

impl Error {
    /// The name of the field at fault, for the variants that carry one.
    ///
    /// # Example
    /// ```
    /// let err = softrod::element::PlanarCable::new(0.1, f64::NAN, 0.025).unwrap_err();
    /// assert_eq!(err.field(), Some("ea_n"));
    /// ```
    pub fn field(&self) -> Option<&str> {
        match self {
            Error::InvalidParameter { name, .. }
            | Error::TooLarge { name, .. }
            | Error::IndexOutOfRange { name, .. }
            | Error::DimensionMismatch { name, .. } => Some(name),
            _ => None,
        }
    }

    /// Prefixes the field name (e.g. with its path in a scene).
    pub(crate) fn with_prefix(mut self, prefix: &str) -> Self {
        match &mut self {
            Error::InvalidParameter { name, .. }
            | Error::TooLarge { name, .. }
            | Error::IndexOutOfRange { name, .. }
            | Error::DimensionMismatch { name, .. } => name.insert_str(0, prefix),
            _ => {}
        }
        self
    }
}

/// `check(name)` with the field name formatted only when the check fails
/// (the load checks run on every solve; a formatted name is an
/// allocation): the check runs with an empty name first and, on an error,
/// again with `name()`.
pub(crate) fn named<T>(
    check: impl Fn(&str) -> Result<T>,
    name: impl FnOnce() -> String,
) -> Result<T> {
    check("").or_else(|_| check(&name()))
}

/// Checks that `value` is at most `max`.
pub(crate) fn check_at_most(name: &str, value: usize, max: usize) -> Result<()> {
    if value <= max {
        Ok(())
    } else {
        Err(Error::TooLarge {
            name: name.into(),
            value,
            max,
        })
    }
}

/// Checks that `index` is below `len`.
pub(crate) fn check_index(name: &str, index: usize, len: usize) -> Result<()> {
    if index < len {
        Ok(())
    } else {
        Err(Error::IndexOutOfRange {
            name: name.into(),
            index,
            len,
        })
    }
}

/// Checks that `value` is finite and strictly positive.
pub(crate) fn check_positive(name: &str, value: f64) -> Result<()> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(name, value, "must be finite and > 0"))
    }
}

/// Checks that `value` is finite.
pub(crate) fn check_finite(name: &str, value: f64) -> Result<()> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(name, value, "must be finite"))
    }
}

/// Checks that every entry of `values` is finite.
pub(crate) fn check_all_finite(name: &str, values: &[f64]) -> Result<()> {
    match values.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::invalid(
            format!("{name}[{i}]"),
            values[i],
            "must be finite",
        )),
    }
}

/// Checks a length.
pub(crate) fn check_len(name: &str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(Error::DimensionMismatch {
            name: name.into(),
            expected,
            got,
        })
    }
}
