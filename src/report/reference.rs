//! The "truth" of the report: deflected shapes computed by a code we did not
//! write (exudyn's ANCF cable, 128 elements), with the load that made them.
//!
//! A reference file (`reference/exudyn_*.json`, written by `validation/`)
//! holds the nodes `[x, y, x', y']` of exudyn's solution at several element
//! counts and the applied loads in softrod's scene format. The shape between
//! nodes is exudyn's own cubic Hermite interpolation (14), so a marker at any
//! arc coordinate is read off the reference's discretization, not softrod's.
//! The files the report uses are compiled into the binary, so `softrod report`
//! runs from any directory.

use nalgebra::Vector2;
use serde_json::Value;

use crate::element::ArcPoint;
use crate::error::{Error, Result};
use crate::loads::LineLoad;
use crate::loads::Load;

/// The references compiled into the binary: `(name, JSON text)`.
const EMBEDDED: [(&str, &str); 8] = [
    (
        "exudyn_gaussian_large",
        include_str!("../../reference/exudyn_gaussian_large.json"),
    ),
    (
        "exudyn_uniform_large",
        include_str!("../../reference/exudyn_uniform_large.json"),
    ),
    (
        "exudyn_family_uniform_0p1",
        include_str!("../../reference/exudyn_family_uniform_0p1.json"),
    ),
    (
        "exudyn_family_uniform_0p3",
        include_str!("../../reference/exudyn_family_uniform_0p3.json"),
    ),
    (
        "exudyn_family_uniform_1",
        include_str!("../../reference/exudyn_family_uniform_1.json"),
    ),
    (
        "exudyn_family_uniform_3",
        include_str!("../../reference/exudyn_family_uniform_3.json"),
    ),
    (
        "exudyn_family_uniform_10",
        include_str!("../../reference/exudyn_family_uniform_10.json"),
    ),
    (
        "exudyn_family_uniform_20",
        include_str!("../../reference/exudyn_family_uniform_20.json"),
    ),
];

/// The load factors `k` (times the robot's self-weight) of the embedded
/// exudyn family `exudyn_family_uniform_<k>`.
pub const FAMILY_FACTORS: [f64; 6] = [0.1, 0.3, 1.0, 3.0, 10.0, 20.0];

/// The name of the family member with load factor `k` (e.g. 0.1 →
/// `exudyn_family_uniform_0p1`).
pub fn family_name(k: f64) -> String {
    format!("exudyn_family_uniform_{}", format!("{k}").replace('.', "p"))
}

/// One section of the reference robot.
#[derive(Debug, Clone, PartialEq)]
pub struct RefSection {
    /// Length (m).
    pub length_m: f64,
    /// Axial stiffness EA (N).
    pub ea_n: f64,
    /// Bending stiffness EI (N·m²).
    pub ei_nm2: f64,
}

/// A reference solution: the shape and the load that made it.
///
/// # Example
/// ```
/// let r = softrod::report::reference::Reference::embedded("exudyn_uniform_large")?;
/// let tip = r.position_at(r.length_m);
/// assert!(tip[1] < -0.1); // 20 N/m bends the 0.24 m cantilever far down
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// The file's name without `.json` (e.g. `exudyn_uniform_large`).
    pub name: String,
    /// The generator that wrote it (e.g. `validation/exudyn_cantilever.py`).
    pub generator: String,
    /// Its description.
    pub description: String,
    /// Undeformed length (m).
    pub length_m: f64,
    /// Sections from base to tip.
    pub sections: Vec<RefSection>,
    /// The applied distributed loads (the unknown the estimator must find).
    pub loads: Vec<LineLoad>,
    /// Nodes `[x, y, x', y']` of the finest converged run, equally spaced in
    /// the undeformed arc coordinate.
    pub nodes: Vec<[f64; 4]>,
}

fn bad(name: &str, what: &str) -> Error {
    Error::Io {
        path: format!("reference/{name}.json"),
        message: what.to_string(),
    }
}

impl Reference {
    /// One of the references compiled into the binary (see [`embedded_names`]).
    ///
    /// # Errors
    /// [`Error::Io`] for an unknown name or a malformed file.
    pub fn embedded(name: &str) -> Result<Reference> {
        let text = EMBEDDED
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, t)| *t)
            .ok_or_else(|| bad(name, "no such embedded reference"))?;
        Reference::from_json(name, text)
    }

    /// Parses a reference file's text (the schema of `validation/README.md`:
    /// `params.{length_m, sections, loads}`, `values.runs[*].{elements,
    /// converged, nodes}`). Only distributed loads are accepted.
    ///
    /// # Errors
    /// [`Error::Io`] naming what is missing or malformed.
    pub fn from_json(name: &str, text: &str) -> Result<Reference> {
        let v: Value = serde_json::from_str(text).map_err(|e| bad(name, &e.to_string()))?;
        let p = &v["params"];
        let num = |x: &Value, what: &str| x.as_f64().ok_or_else(|| bad(name, what));
        let length_m = num(&p["length_m"], "params.length_m missing")?;
        let sections = p["sections"]
            .as_array()
            .ok_or_else(|| bad(name, "params.sections missing"))?
            .iter()
            .map(|s| {
                Ok(RefSection {
                    length_m: num(&s["length_m"], "section length_m")?,
                    ea_n: num(&s["ea_n"], "section ea_n")?,
                    ei_nm2: num(&s["ei_nm2"], "section ei_nm2")?,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let loads = p["loads"]
            .as_array()
            .ok_or_else(|| bad(name, "params.loads missing"))?
            .iter()
            .map(|l| match serde_json::from_value::<Load>(l.clone()) {
                Ok(Load::Distributed(d)) => Ok(d),
                Ok(other) => Err(bad(name, &format!("not a distributed load: {other:?}"))),
                Err(e) => Err(bad(name, &format!("params.loads: {e}"))),
            })
            .collect::<Result<Vec<_>>>()?;
        let runs = v["values"]["runs"]
            .as_array()
            .ok_or_else(|| bad(name, "values.runs missing"))?;
        let finest = runs
            .iter()
            .filter(|r| r["converged"].as_bool() == Some(true))
            .max_by_key(|r| r["elements"].as_u64().unwrap_or(0))
            .ok_or_else(|| bad(name, "no converged run"))?;
        let nodes: Vec<[f64; 4]> = serde_json::from_value(finest["nodes"].clone())
            .map_err(|e| bad(name, &format!("values.runs[*].nodes: {e}")))?;
        if nodes.len() < 2 || nodes.iter().flatten().any(|x| !x.is_finite()) {
            return Err(bad(name, "nodes: fewer than 2 or not finite"));
        }
        if sections.is_empty() || length_m.is_nan() || length_m <= 0.0 {
            return Err(bad(name, "no sections or non-positive length"));
        }
        Ok(Reference {
            name: name.to_string(),
            generator: v["generator"].as_str().unwrap_or("unknown").to_string(),
            description: v["description"].as_str().unwrap_or("").to_string(),
            length_m,
            sections,
            loads,
            nodes,
        })
    }

    /// Number of elements of the reference's discretization.
    pub fn n_elements(&self) -> usize {
        self.nodes.len() - 1
    }

    /// Element and local coordinate of arc coordinate `s` (clamped to the robot).
    fn locate(&self, s: f64) -> (usize, f64, f64) {
        let ne = self.n_elements();
        let le = self.length_m / ne as f64;
        let s = s.clamp(0.0, self.length_m);
        let e = ((s / le).floor() as usize).min(ne - 1);
        (e, ((s - e as f64 * le) / le).clamp(0.0, 1.0), le)
    }

    /// Position `r(s)` (m) by the reference's own cubic Hermite interpolation
    /// (14) of its nodes; `s` is clamped to `[0, L]`.
    ///
    /// # Example
    /// ```
    /// use softrod::report::reference::{embedded_names, Reference};
    /// let r = Reference::embedded(embedded_names()[0])?;
    /// assert!(r.position_at(0.0).norm() < 1e-12); // the clamp
    /// assert!((r.slope_at(0.0) - nalgebra::Vector2::x()).norm() < 1e-9);
    /// let w = r.load_at(0.5 * r.length_m);
    /// assert!(w.norm() > 0.0 && r.resultant_force_n().norm() > 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn position_at(&self, s: f64) -> Vector2<f64> {
        self.interpolate(s, ArcPoint::value_into)
    }

    /// Slope `r'(s)` (dimensionless) by the same interpolation.
    ///
    /// # Example
    /// See [`Reference::position_at`].
    pub fn slope_at(&self, s: f64) -> Vector2<f64> {
        self.interpolate(s, ArcPoint::slope_into)
    }

    /// The crate's one Hermite interpolation ([`ArcPoint`]) of the
    /// reference's element holding `s`: values or slopes.
    fn interpolate(
        &self,
        s: f64,
        how: fn(&ArcPoint, &[f64], &mut [f64]) -> Result<()>,
    ) -> Vector2<f64> {
        let (e, xi, le) = self.locate(s);
        let (a, b) = (&self.nodes[e], &self.nodes[e + 1]);
        let mut fe = [f64::NAN; 8];
        for (dst, src) in fe.iter_mut().zip(a.iter().take(4).chain(b.iter().take(4))) {
            *dst = *src;
        }
        let mut out = [f64::NAN; 2];
        if how(&ArcPoint::new(0, xi, le), &fe, &mut out).is_err() {
            out = [f64::NAN; 2];
        }
        Vector2::from(out)
    }

    /// The applied load per undeformed length at `s` (N/m, world axes).
    ///
    /// # Example
    /// See [`Reference::position_at`].
    pub fn load_at(&self, s: f64) -> Vector2<f64> {
        self.loads.iter().fold(Vector2::zeros(), |acc, l| {
            let w = l.at(s, self.length_m);
            acc + Vector2::new(
                w.as_slice().first().copied().unwrap_or(0.0),
                w.as_slice().get(1).copied().unwrap_or(0.0),
            )
        })
    }

    /// Resultant force of the applied load (N), midpoint rule on 4800 cells.
    ///
    /// # Example
    /// See [`Reference::position_at`].
    pub fn resultant_force_n(&self) -> Vector2<f64> {
        let k = 4800;
        let ds = self.length_m / k as f64;
        (0..k).fold(Vector2::zeros(), |acc, i| {
            acc + self.load_at((i as f64 + 0.5) * ds) * ds
        })
    }
}

/// The names of the references compiled into the binary.
pub fn embedded_names() -> Vec<&'static str> {
    EMBEDDED.iter().map(|(n, _)| *n).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn family_names_match_the_embedded_files() {
        for k in FAMILY_FACTORS {
            let r = Reference::embedded(&family_name(k)).unwrap();
            assert_eq!(r.n_elements(), 128);
        }
    }
}
