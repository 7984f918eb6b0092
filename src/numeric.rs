//! Small vector operations the solvers share (one copy of each).

/// `Σ a_i b_i` over the common length: the band kernels' dot product (four
/// partial sums).
pub(crate) use crate::linsolve::banded::dot;

/// The Euclidean norm `|v|_2`, summed in order.
pub(crate) fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The largest absolute entry `|v|_∞` (0 for an empty slice).
pub(crate) fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// A fixed-size vector from a serde field `v` named `name`: its length
/// must be `D`.
pub(crate) fn fixed<const D: usize>(
    name: &str,
    v: &[f64],
) -> crate::Result<nalgebra::SVector<f64, D>> {
    crate::error::check_len(name, D, v.len())?;
    Ok(nalgebra::SVector::from_column_slice(v))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norms_and_dot() {
        let v = [3.0, -4.0];
        assert_eq!(norm2(&v), 5.0);
        assert_eq!(max_abs(&v), 4.0);
        assert_eq!(dot(&v, &[1.0, 1.0, 7.0]), -1.0);
    }
}
