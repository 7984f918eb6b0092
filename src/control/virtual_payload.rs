//! The virtual payload (Sec. III, Fig. 5): with model error the estimator
//! returns a load even on an unloaded robot. Recorded along a payload-free
//! run as a function of the configuration, it is subtracted from later
//! estimates to leave the real payload.

use nalgebra::DVector;

use crate::error::{Error, Result, check_all_finite, check_len};

/// Recorded estimates `F(c)` at configurations `c` (any fixed-length
/// vector: the pressures, the end-effector position), interpolated by
/// inverse-distance weighting of the nearest recorded configurations
/// (exact at a recorded one).
///
/// # Example
/// ```
/// use softrod::control::VirtualPayload;
/// let mut v = VirtualPayload::new(4)?;
/// v.record(&[0.0], &[1.0])?;
/// v.record(&[1.0], &[3.0])?;
/// assert_eq!(v.at(&[0.0])?, nalgebra::dvector![1.0]);
/// assert!((v.at(&[0.5])?[0] - 2.0).abs() < 1e-12);
/// assert_eq!(v.subtract(&[1.0], &[5.0])?, nalgebra::dvector![2.0]);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct VirtualPayload {
    neighbours: usize,
    keys: Vec<Vec<f64>>,
    values: Vec<Vec<f64>>,
}

impl VirtualPayload {
    /// An empty record interpolating between `neighbours` (≥ 1) recorded
    /// configurations.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `virtual_payload.neighbours` for 0
    /// (no configuration to interpolate from).
    ///
    /// # Example
    /// ```
    /// use softrod::control::VirtualPayload;
    /// assert!(VirtualPayload::new(3)?.is_empty());
    /// let e = VirtualPayload::new(0).unwrap_err();
    /// assert!(e.to_string().contains("virtual_payload.neighbours"));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn new(neighbours: usize) -> Result<Self> {
        if neighbours == 0 {
            return Err(Error::invalid(
                "virtual_payload.neighbours",
                neighbours,
                "must be at least 1",
            ));
        }
        Ok(VirtualPayload {
            neighbours,
            keys: Vec::new(),
            values: Vec::new(),
        })
    }

    /// Number of records.
    pub fn len(&self) -> usize {
        self.keys.len()
    }

    /// Whether nothing is recorded.
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    /// Records the estimate `f` at configuration `key`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a key or value of another length
    /// than the first record's; [`Error::InvalidParameter`] for non-finite
    /// values.
    pub fn record(&mut self, key: &[f64], f: &[f64]) -> Result<()> {
        check_all_finite("virtual_payload.key", key)?;
        check_all_finite("virtual_payload.f", f)?;
        if let (Some(k), Some(v)) = (self.keys.first(), self.values.first()) {
            check_len("virtual_payload.key", k.len(), key.len())?;
            check_len("virtual_payload.f", v.len(), f.len())?;
        }
        self.keys.push(key.to_vec());
        self.values.push(f.to_vec());
        Ok(())
    }

    /// The virtual payload at configuration `key`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if nothing is recorded;
    /// [`Error::DimensionMismatch`] for a key of another length.
    ///
    /// # Example
    /// See [`VirtualPayload`].
    pub fn at(&self, key: &[f64]) -> Result<DVector<f64>> {
        let (Some(k0), Some(v0)) = (self.keys.first(), self.values.first()) else {
            return Err(Error::invalid(
                "virtual_payload",
                "empty",
                "record a payload-free run first",
            ));
        };
        check_len("virtual_payload.key", k0.len(), key.len())?;
        let mut d: Vec<(f64, usize)> = self
            .keys
            .iter()
            .enumerate()
            .map(|(i, k)| {
                let d2: f64 = k.iter().zip(key).map(|(a, b)| (a - b).powi(2)).sum();
                (d2, i)
            })
            .collect();
        d.sort_by(|a, b| a.0.total_cmp(&b.0));
        if let Some(&(d2, i)) = d.first()
            && d2 == 0.0
        {
            return Ok(DVector::from_column_slice(&self.values[i]));
        }
        let mut out = vec![0.0; v0.len()];
        let mut wsum = 0.0;
        for &(d2, i) in d.iter().take(self.neighbours) {
            let w = 1.0 / d2;
            wsum += w;
            out.iter_mut()
                .zip(&self.values[i])
                .for_each(|(o, v)| *o += w * v);
        }
        out.iter_mut().for_each(|o| *o /= wsum);
        Ok(DVector::from_vec(out))
    }

    /// `f` minus the virtual payload at `key`: the real payload's estimate.
    ///
    /// # Errors
    /// As [`VirtualPayload::at`]; [`Error::DimensionMismatch`] for an `f` of
    /// another length than the records.
    ///
    /// # Example
    /// See [`VirtualPayload`].
    pub fn subtract(&self, key: &[f64], f: &[f64]) -> Result<DVector<f64>> {
        let v = self.at(key)?;
        check_len("f", v.len(), f.len())?;
        Ok(DVector::from_iterator(
            v.len(),
            f.iter().zip(v.iter()).map(|(a, b)| a - b),
        ))
    }
}
