//! Where a robot writes its tangent stiffness: the symmetric sparse matrix
//! on the robot's connectivity pattern (what the linear solvers factor),
//! or the band matrix of wave 1.

use std::sync::Arc;

use crate::error::Result;
use crate::linsolve::{BandedMatrix, SymmetricMatrix, SymmetricPattern};
use crate::loads::force_field::StiffnessSink;

/// A matrix [`crate::assembly::Robot::tangent_into`] can assemble into: it
/// takes scattered entries ([`StiffnessSink`]) and whole element blocks of
/// the chain.
///
/// # Example
/// ```
/// use softrod::assembly::TangentTarget;
/// use softrod::linsolve::{BandedMatrix, SymmetricMatrix};
/// fn takes<K: TangentTarget>(_: &mut K) {}
/// takes(&mut BandedMatrix::zeros(1, 0, 0));
/// ```
pub trait TangentTarget: StiffnessSink {
    /// Makes `self` the zero matrix of a robot with `n_free` free
    /// coordinates, half bandwidth `kb` and tangent pattern `pattern`
    /// (reallocated only if its shape differs).
    fn reset(&mut self, n_free: usize, kb: usize, pattern: &Arc<SymmetricPattern>);

    /// Adds element `e`'s stiffness `h` (`edof × edof`, row-major), whose
    /// free coordinates are the run `off .. off + edof`.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `h` does not fit the element.
    fn add_chain_block(&mut self, e: usize, off: usize, edof: usize, h: &[f64]) -> Result<()>;

    /// Adds `values`, the values of a [`SymmetricMatrix`] on the robot's
    /// tangent pattern, if `self` is such a matrix (`true`); `false` (and
    /// nothing added) otherwise, the default. (How a robot puts its kept
    /// element tangent at the reference configuration into a solve's
    /// matrix, just after [`TangentTarget::reset`]: added to zeros.)
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section, TangentTarget};
    /// use softrod::linsolve::{BandedMatrix, SymmetricMatrix};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 2)]).build_planar()?;
    /// let mut k = SymmetricMatrix::zeros(robot.tangent_pattern().clone());
    /// let ones = vec![1.0; k.values().len()];
    /// assert!(k.add_values(&ones) && k.add_values(&ones));
    /// assert!(k.values().iter().all(|v| *v == 2.0));
    /// assert!(!k.add_values(&[1.0]));
    /// assert!(!BandedMatrix::zeros(1, 0, 0).add_values(&[1.0]));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn add_values(&mut self, values: &[f64]) -> bool {
        let _ = values;
        false
    }
}

impl TangentTarget for BandedMatrix {
    fn reset(&mut self, n_free: usize, kb: usize, _pattern: &Arc<SymmetricPattern>) {
        if self.n() != n_free || self.kl() != kb || self.ku() != kb {
            *self = BandedMatrix::zeros(n_free, kb, kb);
        } else {
            self.fill_zero();
        }
    }

    fn add_chain_block(&mut self, _e: usize, off: usize, edof: usize, h: &[f64]) -> Result<()> {
        crate::error::check_len("h", edof * edof, h.len())?;
        // off + edof <= n_free and edof - 1 <= kb: in the band
        self.add_block_unchecked(off, edof, h);
        Ok(())
    }
}

impl TangentTarget for SymmetricMatrix {
    fn reset(&mut self, _n_free: usize, _kb: usize, pattern: &Arc<SymmetricPattern>) {
        if Arc::ptr_eq(self.pattern(), pattern) || **self.pattern() == **pattern {
            self.fill_zero();
        } else {
            *self = SymmetricMatrix::zeros(pattern.clone());
        }
    }

    fn add_chain_block(&mut self, e: usize, _off: usize, _edof: usize, h: &[f64]) -> Result<()> {
        // the pattern's element e is the chain's element e (the same dofs)
        self.add_element(e, h)
    }

    fn add_values(&mut self, values: &[f64]) -> bool {
        let own = self.values_mut();
        if own.len() != values.len() {
            return false;
        }
        own.iter_mut().zip(values).for_each(|(a, b)| *a += b);
        true
    }
}
