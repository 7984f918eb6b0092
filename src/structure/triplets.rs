//! A sparse matrix as a list of `(row, column, value)` entries, the form in
//! which the structure's tangent is assembled (duplicates add up): a sparse
//! factorization takes it as it is, a test turns it into a dense matrix.

use crate::error::{Result, check_len};
use crate::loads::force_field::StiffnessSink;

/// An `n × n` matrix as a list of entries; repeated `(row, column)` pairs
/// add up.
///
/// # Example
/// ```
/// use softrod::loads::force_field::StiffnessSink;
/// use softrod::structure::Triplets;
/// let mut k = Triplets::new(2);
/// k.add(0, 0, 2.0);
/// k.add(0, 0, 1.0);
/// k.add(1, 0, -1.0);
/// assert_eq!(k.to_dense()[(0, 0)], 3.0);
/// assert_eq!(k.mul_vec(&[1.0, 1.0]).unwrap(), nalgebra::dvector![3.0, -1.0]);
/// ```
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Triplets {
    n: usize,
    entries: Vec<(usize, usize, f64)>,
}

impl Triplets {
    /// An empty `n × n` matrix.
    pub fn new(n: usize) -> Self {
        Triplets {
            n,
            entries: Vec::new(),
        }
    }

    /// Empties the list and sets the size to `n` (keeps the memory).
    pub fn reset(&mut self, n: usize) {
        self.n = n;
        self.entries.clear();
    }

    /// The size `n`.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The entries `(row, column, value)`, in the order they were added.
    pub fn entries(&self) -> &[(usize, usize, f64)] {
        &self.entries
    }

    /// The largest `|value|` of the entries as added (before repeated
    /// entries are summed): the scale of the matrix.
    pub fn max_abs(&self) -> f64 {
        self.entries.iter().fold(0.0f64, |m, e| m.max(e.2.abs()))
    }

    /// The dense matrix (repeated entries summed).
    pub fn to_dense(&self) -> nalgebra::DMatrix<f64> {
        let mut m = nalgebra::DMatrix::zeros(self.n, self.n);
        for &(i, j, v) in &self.entries {
            m[(i, j)] += v;
        }
        m
    }

    /// `y = A x`.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `x` does not have `n` entries.
    pub fn mul_vec(&self, x: &[f64]) -> Result<nalgebra::DVector<f64>> {
        check_len("x", self.n, x.len())?;
        let mut y = nalgebra::DVector::zeros(self.n);
        for &(i, j, v) in &self.entries {
            y[i] += v * x[j];
        }
        Ok(y)
    }
}

impl StiffnessSink for Triplets {
    /// Adds the entry (entries outside `n × n` are dropped).
    fn add(&mut self, row: usize, col: usize, value: f64) {
        if row < self.n && col < self.n {
            self.entries.push((row, col, value));
        }
    }
}
