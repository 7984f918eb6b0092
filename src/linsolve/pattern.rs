//! The sparsity pattern of a symmetric tangent, built from the element
//! connectivity, and the matrix the assembler writes on it.
//!
//! The pattern stores the upper triangle (`i <= j`) in compressed sparse
//! columns, every diagonal entry included, row indices sorted. Built from
//! each element's list of global dofs, it keeps for every element the
//! positions (slots) of its entries in the value array: assembling an
//! element's dense block is then `values[slot] += block[a, b]`, no search.
//! Any group of dofs that receives a dense block counts as an "element" (a
//! node loaded by a moment, a rigid body, a joint).

use std::sync::Arc;

use super::LinsolveError;
use super::banded::{BandedMatrix, MAX_ENTRIES};
use crate::error::{Error, Result, check_index, check_len};

/// The largest number of dofs one element may couple (its dense block has
/// the square of it in entries).
pub const MAX_ELEMENT_DOFS: usize = 4096;

/// The sparsity pattern of a symmetric `n × n` matrix, from its elements'
/// dofs, with each element's scatter map.
///
/// # Example
/// ```
/// use softrod::linsolve::SymmetricPattern;
/// // two 2-dof elements sharing dof 1: a 3 × 3 tridiagonal pattern
/// let p = SymmetricPattern::from_elements(3, [[0, 1], [1, 2]])?;
/// assert_eq!(p.n(), 3);
/// assert_eq!(p.nnz_upper(), 5); // 3 diagonal + 2 above
/// assert_eq!(p.bandwidth(), 1);
/// assert!(p.position(2, 1).is_some() && p.position(0, 2).is_none());
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SymmetricPattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    diag: Vec<usize>,
    elem_ptr: Vec<usize>,
    dofs: Vec<usize>,
    slot_ptr: Vec<usize>,
    slots: Vec<usize>,
}

impl SymmetricPattern {
    /// The pattern of an `n × n` symmetric matrix assembled from dense
    /// blocks over the given dof lists (one per element, in element
    /// order; the dofs of one element must be distinct, in any order).
    /// Every diagonal entry is in the pattern, coupled or not.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] (field `elements[e][k]`) for a dof `>= n`;
    /// [`Error::InvalidParameter`] (field `elements[e][k]`) for a dof listed
    /// twice in one element; [`Error::TooLarge`] for an element of more
    /// than [`MAX_ELEMENT_DOFS`] dofs, or more than
    /// [`MAX_ENTRIES`](crate::linsolve::banded::MAX_ENTRIES) stored entries
    /// in all (both refused before allocating for them).
    ///
    /// # Example
    /// ```
    /// use softrod::{linsolve::SymmetricPattern, Error};
    /// let err = SymmetricPattern::from_elements(3, [vec![0, 3]]).unwrap_err();
    /// assert!(matches!(err, Error::IndexOutOfRange { ref name, .. } if name == "elements[0][1]"));
    /// ```
    pub fn from_elements<I, E>(n: usize, elements: I) -> Result<Self>
    where
        I: IntoIterator<Item = E>,
        E: AsRef<[usize]>,
    {
        if n > MAX_ENTRIES {
            return Err(Error::TooLarge {
                name: "n".into(),
                value: n,
                max: MAX_ENTRIES,
            });
        }
        let mut elem_ptr = vec![0];
        let mut dofs = Vec::new();
        let mut pairs_total = n;
        let mut sorted = Vec::new();
        for (e, el) in elements.into_iter().enumerate() {
            let el = el.as_ref();
            let m = el.len();
            if m > MAX_ELEMENT_DOFS {
                return Err(Error::TooLarge {
                    name: format!("elements[{e}]"),
                    value: m,
                    max: MAX_ELEMENT_DOFS,
                });
            }
            pairs_total = pairs_total.saturating_add(m * (m + 1) / 2);
            if pairs_total > MAX_ENTRIES {
                return Err(Error::TooLarge {
                    name: "elements (entries of all element blocks)".into(),
                    value: pairs_total,
                    max: MAX_ENTRIES,
                });
            }
            for (k, &d) in el.iter().enumerate() {
                check_index(&format!("elements[{e}][{k}]"), d, n)?;
            }
            sorted.clear();
            sorted.extend(el.iter().enumerate().map(|(k, &d)| (d, k)));
            sorted.sort_unstable();
            if let Some(w) = sorted.windows(2).find(|w| w[0].0 == w[1].0) {
                return Err(Error::invalid(
                    format!("elements[{e}][{}]", w[1].1.max(w[0].1)),
                    w[0].0,
                    "a dof appears twice in one element",
                ));
            }
            dofs.extend_from_slice(el);
            elem_ptr.push(dofs.len());
        }
        // (column, row) of every upper entry, the diagonal included
        let mut entries: Vec<(usize, usize)> = Vec::with_capacity(pairs_total);
        entries.extend((0..n).map(|j| (j, j)));
        for w in elem_ptr.windows(2) {
            let el = &dofs[w[0]..w[1]];
            for (a, &da) in el.iter().enumerate() {
                for &db in &el[a..] {
                    entries.push((da.max(db), da.min(db)));
                }
            }
        }
        entries.sort_unstable();
        entries.dedup();
        let mut col_ptr = vec![0usize; n + 1];
        for &(j, _) in &entries {
            col_ptr[j + 1] += 1;
        }
        for j in 0..n {
            col_ptr[j + 1] += col_ptr[j];
        }
        let row_idx: Vec<usize> = entries.iter().map(|&(_, i)| i).collect();
        // sorted rows, the diagonal (the largest row of its column) last
        let diag: Vec<usize> = (0..n).map(|j| col_ptr[j + 1] - 1).collect();
        let mut pattern = SymmetricPattern {
            n,
            col_ptr,
            row_idx,
            diag,
            elem_ptr,
            dofs,
            slot_ptr: vec![0],
            slots: Vec::new(),
        };
        let mut slots = Vec::with_capacity(pairs_total - n);
        let mut slot_ptr = Vec::with_capacity(pattern.elem_ptr.len());
        slot_ptr.push(0);
        for w in pattern.elem_ptr.windows(2) {
            let el = &pattern.dofs[w[0]..w[1]];
            for (a, &da) in el.iter().enumerate() {
                for &db in &el[a..] {
                    // present by construction
                    slots.push(pattern.position(da, db).unwrap_or(usize::MAX));
                }
            }
            slot_ptr.push(slots.len());
        }
        pattern.slots = slots;
        pattern.slot_ptr = slot_ptr;
        Ok(pattern)
    }

    /// Order `n` of the matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of stored entries (the upper triangle with the diagonal).
    pub fn nnz_upper(&self) -> usize {
        self.row_idx.len()
    }

    /// Number of elements (dof groups) the pattern was built from.
    pub fn n_elements(&self) -> usize {
        self.elem_ptr.len() - 1
    }

    /// The global dofs of element `e` (as given), or `None` past the end.
    ///
    /// # Example
    /// ```
    /// let p = softrod::linsolve::SymmetricPattern::from_elements(4, [vec![3, 0], vec![1, 2]])?;
    /// assert_eq!(p.n_elements(), 2);
    /// assert_eq!(p.element_dofs(0), Some(&[3, 0][..]));
    /// assert_eq!(p.element_dofs(2), None);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn element_dofs(&self, e: usize) -> Option<&[usize]> {
        let (a, b) = (*self.elem_ptr.get(e)?, *self.elem_ptr.get(e + 1)?);
        self.dofs.get(a..b)
    }

    /// Column pointers of the upper triangle (`n + 1` entries).
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// Row indices of the upper triangle, sorted in each column (the
    /// diagonal last).
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// Slot of the diagonal entry `(j, j)` in the value array, for every `j`.
    pub fn diagonal_slots(&self) -> &[usize] {
        &self.diag
    }

    /// Slot of entry `(i, j)` (either triangle: `(i, j)` and `(j, i)` share
    /// one) in the value array, `None` outside the pattern. A binary
    /// search; assembly uses the precomputed element slots instead.
    ///
    /// # Example
    /// ```
    /// let p = softrod::linsolve::SymmetricPattern::from_elements(3, [[0, 2]])?;
    /// assert_eq!(p.position(2, 0), p.position(0, 2));
    /// assert!(p.position(1, 1).is_some()); // every diagonal entry is stored
    /// assert_eq!(p.position(0, 1), None);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn position(&self, i: usize, j: usize) -> Option<usize> {
        let (r, c) = (i.min(j), i.max(j));
        if c >= self.n {
            return None;
        }
        let (a, b) = (self.col_ptr[c], self.col_ptr[c + 1]);
        self.row_idx[a..b].binary_search(&r).ok().map(|k| a + k)
    }

    /// The half bandwidth `max |i − j|` over the stored entries (0 for a
    /// diagonal pattern): a band matrix with `kl = ku` equal to it holds
    /// the pattern.
    ///
    /// # Example
    /// ```
    /// // a chain of two-node elements, 2 dofs per node: bandwidth 2·2 − 1
    /// let els: Vec<Vec<usize>> = (0..5).map(|e| (2 * e..2 * e + 4).collect()).collect();
    /// let p = softrod::linsolve::SymmetricPattern::from_elements(12, &els)?;
    /// assert_eq!(p.bandwidth(), 3);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn bandwidth(&self) -> usize {
        (0..self.n)
            .filter(|&j| self.col_ptr[j + 1] > self.col_ptr[j])
            .map(|j| j - self.row_idx[self.col_ptr[j]])
            .max()
            .unwrap_or(0)
    }

    /// The slots of element `e`'s entries, for its local pairs `a <= b` in
    /// row-major order of the upper triangle of its block.
    fn element_slots(&self, e: usize) -> Option<&[usize]> {
        let (a, b) = (*self.slot_ptr.get(e)?, *self.slot_ptr.get(e + 1)?);
        self.slots.get(a..b)
    }
}

/// A symmetric matrix on a [`SymmetricPattern`]: the values of its upper
/// triangle, in the pattern's order. What the assembler writes and a
/// [`TangentSolver`](crate::linsolve::TangentSolver) factors.
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::{SymmetricMatrix, SymmetricPattern};
/// let p = Arc::new(SymmetricPattern::from_elements(3, [[0, 1], [1, 2]])?);
/// let mut k = SymmetricMatrix::zeros(p);
/// for e in 0..2 {
///     // a spring of stiffness 2 between the element's two dofs
///     k.add_element(e, &[2.0, -2.0, -2.0, 2.0])?;
/// }
/// assert_eq!(k.get(1, 1), 4.0);
/// assert_eq!(k.get(2, 1), -2.0);
/// assert_eq!(k.get(0, 2), 0.0);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SymmetricMatrix {
    pattern: Arc<SymmetricPattern>,
    values: Vec<f64>,
}

impl SymmetricMatrix {
    /// The zero matrix on `pattern`.
    pub fn zeros(pattern: Arc<SymmetricPattern>) -> Self {
        let values = vec![0.0; pattern.nnz_upper()];
        SymmetricMatrix { pattern, values }
    }

    /// Its pattern.
    pub fn pattern(&self) -> &Arc<SymmetricPattern> {
        &self.pattern
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.pattern.n
    }

    /// Values of the upper triangle in the pattern's order.
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// Mutable values of the upper triangle in the pattern's order.
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Sets every entry to zero (keeps the allocation).
    pub fn fill_zero(&mut self) {
        self.values.fill(0.0);
    }

    /// Adds element `e`'s dense symmetric block (`m × m` row-major, `m`
    /// its dof count, in the order of its dof list). Only the block's
    /// upper triangle (`a <= b`) is read. No search: the slots were
    /// computed with the pattern.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] (field `e`) past the last element,
    /// [`Error::DimensionMismatch`] (field `block`) for a block not `m²` long.
    pub fn add_element(&mut self, e: usize, block: &[f64]) -> Result<()> {
        let pattern = &self.pattern;
        let (Some(dofs), Some(slots)) = (pattern.element_dofs(e), pattern.element_slots(e)) else {
            return Err(Error::IndexOutOfRange {
                name: "e".into(),
                index: e,
                len: pattern.n_elements(),
            });
        };
        let m = dofs.len();
        check_len("block", m * m, block.len())?;
        let mut s = slots.iter();
        for (a, row) in block.chunks_exact(m.max(1)).enumerate().take(m) {
            for (v, &slot) in row[a..].iter().zip(&mut s) {
                if let Some(x) = self.values.get_mut(slot) {
                    *x += v;
                }
            }
        }
        Ok(())
    }

    /// Adds `v` to entry `(i, j)` (and so to `(j, i)`), found by binary
    /// search.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] (field `i` or `j`) for an index `>= n`;
    /// [`Error::InvalidParameter`] (field `j`) for an entry outside the
    /// pattern.
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::{SymmetricMatrix, SymmetricPattern};
    /// let mut k = SymmetricMatrix::zeros(Arc::new(SymmetricPattern::from_elements(3, [[0, 1]])?));
    /// k.add(1, 0, 2.5)?;
    /// assert_eq!(k.get(0, 1), 2.5);
    /// assert!(k.add(0, 2, 1.0).is_err()); // not coupled
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn add(&mut self, i: usize, j: usize, v: f64) -> Result<()> {
        check_index("i", i, self.n())?;
        check_index("j", j, self.n())?;
        match self.pattern.position(i, j) {
            Some(k) => {
                self.values[k] += v;
                Ok(())
            }
            None => Err(Error::invalid(
                "j",
                j,
                format!("entry ({i}, {j}) is outside the sparsity pattern"),
            )),
        }
    }

    /// Adds `v` to entry `(i, j)` if it is in the pattern (binary search)
    /// and says whether it was; no error, no allocation (a scatter that
    /// drops what the pattern does not hold).
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::{SymmetricMatrix, SymmetricPattern};
    /// let mut k = SymmetricMatrix::zeros(Arc::new(SymmetricPattern::from_elements(3, [[0, 1]])?));
    /// assert!(k.add_if_present(1, 0, 2.5));
    /// assert!(!k.add_if_present(0, 2, 1.0) && !k.add_if_present(7, 0, 1.0));
    /// assert_eq!(k.get(0, 1), 2.5);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn add_if_present(&mut self, i: usize, j: usize, v: f64) -> bool {
        if i >= self.n() || j >= self.n() {
            return false;
        }
        match self.pattern.position(i, j) {
            Some(k) => {
                self.values[k] += v;
                true
            }
            None => false,
        }
    }

    /// Entry `(i, j)` (zero outside the pattern).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.pattern.position(i, j).map_or(0.0, |k| self.values[k])
    }

    /// The stored entries `(i, j, a_ij)` of the upper triangle (`i <= j`),
    /// column by column.
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::{SymmetricMatrix, SymmetricPattern};
    /// let mut k = SymmetricMatrix::zeros(Arc::new(SymmetricPattern::from_elements(2, [[0, 1]])?));
    /// k.add_element(0, &[4.0, 1.0, 1.0, 3.0])?;
    /// let e: Vec<_> = k.iter_upper().collect();
    /// assert_eq!(e, vec![(0, 0, 4.0), (0, 1, 1.0), (1, 1, 3.0)]);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn iter_upper(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        let p = &self.pattern;
        (0..p.n).flat_map(move |j| {
            (p.col_ptr[j]..p.col_ptr[j + 1]).map(move |k| (p.row_idx[k], j, self.values[k]))
        })
    }

    /// Largest absolute entry.
    pub fn max_abs(&self) -> f64 {
        self.values.iter().fold(0.0f64, |m, v| m.max(v.abs()))
    }

    /// `y = A x` into `y`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `x` or `y` does not have `n` entries.
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::{SymmetricMatrix, SymmetricPattern};
    /// let mut k = SymmetricMatrix::zeros(Arc::new(SymmetricPattern::from_elements(2, [[0, 1]])?));
    /// k.add_element(0, &[4.0, 1.0, 1.0, 3.0])?;
    /// let mut y = [0.0; 2];
    /// k.mul_vec_into(&[1.0, 2.0], &mut y)?;
    /// assert_eq!(y, [6.0, 7.0]);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn mul_vec_into(&self, x: &[f64], y: &mut [f64]) -> Result<()> {
        check_len("x", self.n(), x.len())?;
        check_len("y", self.n(), y.len())?;
        y.fill(0.0);
        for (i, j, v) in self.iter_upper() {
            y[i] += v * x[j];
            if i != j {
                y[j] += v * x[i];
            }
        }
        Ok(())
    }

    /// The same matrix as a [`BandedMatrix`] with `kl = ku` the pattern's
    /// bandwidth.
    ///
    /// # Errors
    /// [`Error::TooLarge`] if the band storage would exceed
    /// [`MAX_ENTRIES`](crate::linsolve::banded::MAX_ENTRIES).
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::{SymmetricMatrix, SymmetricPattern};
    /// let mut k = SymmetricMatrix::zeros(Arc::new(SymmetricPattern::from_elements(3, [[0, 1], [1, 2]])?));
    /// k.add(2, 1, -1.0)?;
    /// let b = k.to_banded()?;
    /// assert_eq!((b.kl(), b.ku()), (1, 1));
    /// assert_eq!(b.get(1, 2), -1.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn to_banded(&self) -> Result<BandedMatrix> {
        let kb = self.pattern.bandwidth();
        let mut b = BandedMatrix::try_zeros(self.n(), kb, kb)?;
        for (i, j, v) in self.iter_upper() {
            b.add(i, j, v);
            if i != j {
                b.add(j, i, v);
            }
        }
        Ok(b)
    }

    /// Checks that every value is finite, naming the first entry that is not.
    pub(crate) fn check_finite(&self) -> std::result::Result<(), LinsolveError> {
        match self.values.iter().position(|v| !v.is_finite()) {
            None => Ok(()),
            Some(k) => {
                let col = self.pattern.col_ptr.partition_point(|&p| p <= k) - 1;
                Err(LinsolveError::NonFinite {
                    row: self.pattern.row_idx[k],
                    col,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    #[allow(clippy::needless_range_loop)]
    fn element_blocks_land_where_a_dense_assembly_puts_them() {
        // unsorted, overlapping dof lists with a non-banded coupling
        let elements = vec![vec![4, 0, 2], vec![2, 3], vec![1, 4]];
        let p = Arc::new(SymmetricPattern::from_elements(5, &elements).unwrap());
        let mut k = SymmetricMatrix::zeros(p.clone());
        let mut dense = [[0.0f64; 5]; 5];
        for (e, el) in elements.iter().enumerate() {
            let m = el.len();
            let mut block = vec![0.0; m * m];
            for a in 0..m {
                for b in a..m {
                    let v = (10 * e + 3 * a + b) as f64 + 1.0;
                    block[a * m + b] = v;
                    block[b * m + a] = v;
                }
            }
            k.add_element(e, &block).unwrap();
            for a in 0..m {
                for b in 0..m {
                    dense[el[a]][el[b]] += block[a * m + b];
                }
            }
        }
        for (i, row) in dense.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                assert_eq!(k.get(i, j), *v, "({i}, {j})");
                assert_eq!(p.position(i, j).is_some(), *v != 0.0 || i == j);
            }
        }
        assert_eq!(p.bandwidth(), 4);
        let x = [1.0, -2.0, 0.5, 3.0, -1.0];
        let mut y = [0.0; 5];
        k.mul_vec_into(&x, &mut y).unwrap();
        for i in 0..5 {
            let yd: f64 = (0..5).map(|j| dense[i][j] * x[j]).sum();
            assert!((y[i] - yd).abs() < 1e-12);
        }
        let b = k.to_banded().unwrap();
        for i in 0..5 {
            for j in 0..5 {
                assert_eq!(b.get(i, j), dense[i][j]);
            }
        }
    }

    #[test]
    fn bad_connectivity_and_bad_writes_are_refused() {
        assert!(matches!(
            SymmetricPattern::from_elements(3, [vec![0, 1, 0]]),
            Err(Error::InvalidParameter { ref name, .. }) if name == "elements[0][2]"
        ));
        assert!(matches!(
            SymmetricPattern::from_elements(usize::MAX, [[0usize; 0]; 0]),
            Err(Error::TooLarge { .. })
        ));
        let p = Arc::new(SymmetricPattern::from_elements(3, [[0, 1]]).unwrap());
        let mut k = SymmetricMatrix::zeros(p);
        assert!(matches!(
            k.add_element(1, &[0.0; 4]),
            Err(Error::IndexOutOfRange { .. })
        ));
        assert!(matches!(
            k.add_element(0, &[0.0; 3]),
            Err(Error::DimensionMismatch { .. })
        ));
        assert!(k.add(0, 2, 1.0).is_err());
        assert!(k.add(0, 3, 1.0).is_err());
        k.add(1, 0, 2.0).unwrap();
        assert_eq!(k.get(0, 1), 2.0);
        k.values_mut()[0] = f64::NAN;
        assert_eq!(
            k.check_finite(),
            Err(LinsolveError::NonFinite { row: 0, col: 0 })
        );
    }
}
