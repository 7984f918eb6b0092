//! A section of a rod: a uniform piece with its own stiffness, weight,
//! discretization and pneumatic chambers, as written in a scene.

use serde::{Deserialize, Serialize};

use crate::element::PlanarCable;

/// One pneumatic chamber: its torque per pressure and its pressure bounds.
///
/// # Example
/// ```
/// let c = softrod::assembly::Chamber { gain_nm_per_pa: vec![3e-6], pressure_min_pa: 0.0, pressure_max_pa: 100e3 };
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Chamber {
    /// Column of the calibration matrix `G`: torque on the section per unit
    /// pressure (N·m/Pa; one component in 2-D, positive bends counter-clockwise;
    /// three in 3-D, world axes: a spatial cable has no section frame, and
    /// the torque works through the rotation of the section's end tangents
    /// from the base direction, see [`crate::element::SpatialCable`]).
    pub gain_nm_per_pa: Vec<f64>,
    /// Lower pressure bound (Pa).
    pub pressure_min_pa: f64,
    /// Upper pressure bound (Pa).
    pub pressure_max_pa: f64,
}

/// One section of the robot: a uniform piece with its own stiffness, weight,
/// discretization and chambers.
///
/// In JSON, `"elements"` is a positive integer or `"auto"`; `"auto"` sets
/// [`Section::auto_elements`] (and `elements` to 0), and a number clears it.
///
/// # Example
/// ```
/// use softrod::assembly::Section;
/// let s = Section::uniform(0.12, 300.0, 0.025, 10);
/// assert_eq!(s.elements, 10);
/// let auto: Section = serde_json::from_str(
///     r#"{"length_m": 0.12, "ea_n": 300, "ei_nm2": 0.025, "elements": "auto"}"#).unwrap();
/// assert!(auto.auto_elements);
/// assert!(serde_json::to_string(&auto).unwrap().contains(r#""elements":"auto""#));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "SectionJson", into = "SectionJson")]
pub struct Section {
    /// Undeformed length (m).
    pub length_m: f64,
    /// Axial stiffness EA (N).
    pub ea_n: f64,
    /// Bending stiffness EI (N·m²).
    pub ei_nm2: f64,
    /// Mass per undeformed length (kg/m); zero is a weightless section.
    #[serde(default)]
    pub mass_per_length_kg_per_m: f64,
    /// Number of elements.
    pub elements: usize,
    /// Whether the scene asked for `"elements": "auto"`: the count is then
    /// chosen by [`crate::refine::auto_elements`], and `elements` is not
    /// used until the refinement fills it in. A scene refuses to build a
    /// robot from such a section ([`crate::scene::Scene::robot`]); a
    /// [`crate::assembly::RobotSpec`] ignores the flag and builds with `elements`.
    pub auto_elements: bool,
    /// Rest curvature `κ0` (1/m), constant over the section.
    pub rest_curvature_per_m: f64,
    /// Rest curvature as a function of the arc coordinate within the
    /// section (planar robots), instead of the constant
    /// `rest_curvature_per_m` (which must then be 0).
    pub rest_curvature_profile: Option<RestCurvatureProfile>,
    /// Pneumatic chambers acting on this section.
    pub chambers: Vec<Chamber>,
}

/// A section's element count as written in JSON: a number or `"auto"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ElementCount {
    Fixed(usize),
    Auto,
}

impl Serialize for ElementCount {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            ElementCount::Fixed(n) => s.serialize_u64(*n as u64),
            ElementCount::Auto => s.serialize_str("auto"),
        }
    }
}

impl<'de> Deserialize<'de> for ElementCount {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = ElementCount;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(r#"a positive integer or "auto""#)
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Self::Value, E> {
                usize::try_from(v)
                    .map(ElementCount::Fixed)
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Unsigned(v), &self))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<Self::Value, E> {
                u64::try_from(v)
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Signed(v), &self))
                    .and_then(|v| self.visit_u64(v))
            }
            fn visit_str<E: serde::de::Error>(
                self,
                v: &str,
            ) -> std::result::Result<Self::Value, E> {
                if v == "auto" {
                    Ok(ElementCount::Auto)
                } else {
                    Err(E::invalid_value(serde::de::Unexpected::Str(v), &self))
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// The JSON form of [`Section`].
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SectionJson {
    length_m: f64,
    ea_n: f64,
    ei_nm2: f64,
    #[serde(default)]
    mass_per_length_kg_per_m: f64,
    elements: ElementCount,
    #[serde(default)]
    rest_curvature_per_m: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    rest_curvature_profile: Option<RestCurvatureProfile>,
    #[serde(default)]
    chambers: Vec<Chamber>,
}

impl From<SectionJson> for Section {
    fn from(j: SectionJson) -> Self {
        let (elements, auto_elements) = match j.elements {
            ElementCount::Fixed(n) => (n, false),
            ElementCount::Auto => (0, true),
        };
        Section {
            length_m: j.length_m,
            ea_n: j.ea_n,
            ei_nm2: j.ei_nm2,
            mass_per_length_kg_per_m: j.mass_per_length_kg_per_m,
            elements,
            auto_elements,
            rest_curvature_per_m: j.rest_curvature_per_m,
            rest_curvature_profile: j.rest_curvature_profile,
            chambers: j.chambers,
        }
    }
}

impl From<Section> for SectionJson {
    fn from(s: Section) -> Self {
        SectionJson {
            length_m: s.length_m,
            ea_n: s.ea_n,
            ei_nm2: s.ei_nm2,
            mass_per_length_kg_per_m: s.mass_per_length_kg_per_m,
            elements: if s.auto_elements {
                ElementCount::Auto
            } else {
                ElementCount::Fixed(s.elements)
            },
            rest_curvature_per_m: s.rest_curvature_per_m,
            rest_curvature_profile: s.rest_curvature_profile,
            chambers: s.chambers,
        }
    }
}

impl Section {
    /// A weightless section with no chambers and no rest curvature.
    pub fn uniform(length_m: f64, ea_n: f64, ei_nm2: f64, elements: usize) -> Self {
        Section {
            length_m,
            ea_n,
            ei_nm2,
            mass_per_length_kg_per_m: 0.0,
            elements,
            auto_elements: false,
            rest_curvature_per_m: 0.0,
            rest_curvature_profile: None,
            chambers: Vec::new(),
        }
    }

    /// The rest curvature `κ0` (1/m) at arc coordinate `x` (m) from the
    /// section's start: the profile's value if it has one, else the
    /// constant `rest_curvature_per_m`.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RestCurvatureProfile, Section};
    /// let mut s = Section::uniform(0.2, 300.0, 0.025, 4);
    /// s.rest_curvature_profile = Some(RestCurvatureProfile {
    ///     s_m: vec![0.0, 0.2], kappa_per_m: vec![0.0, 10.0] });
    /// assert!((s.rest_curvature_at(0.05) - 2.5).abs() < 1e-15);
    /// ```
    pub fn rest_curvature_at(&self, x: f64) -> f64 {
        match &self.rest_curvature_profile {
            Some(p) => p.at(x),
            None => self.rest_curvature_per_m,
        }
    }
}

/// The planar cable element of length `le` (m) of section `s` (or of a
/// piece of it, whose profile starts at the element's first node), with
/// `ax` axial and `be` bending Gauss points: its constant rest curvature,
/// or its profile sampled at the bending points.
///
/// # Errors
/// As [`PlanarCable::with_rest_curvature`].
pub(crate) fn planar_element(
    s: &Section,
    le: f64,
    ax: usize,
    be: usize,
) -> crate::error::Result<PlanarCable> {
    match &s.rest_curvature_profile {
        Some(p) => PlanarCable::with_rest_curvature(le, s.ea_n, s.ei_nm2, |x| p.at(x), ax, be),
        None => PlanarCable::with_rules(le, s.ea_n, s.ei_nm2, s.rest_curvature_per_m, ax, be),
    }
}

/// A rest curvature `κ0(X)` given by a table: `kappa_per_m[k]` (1/m) at the
/// arc coordinate `s_m[k]` (m, from the section's start), linear in `X`
/// between neighbouring entries. The table covers its section: `s_m`
/// starts at 0, ends at the section's `length_m` and never decreases; an
/// arc position written twice is a jump (the second value holds from there
/// on). Each element samples `κ0` at its bending Gauss points, so a kink or
/// a jump is resolved exactly when a node sits on it.
///
/// A planar rod whose rest curvature is `κ0(X)` is, unloaded, the curve
/// whose tangent angle is `θ(X) = θ(0) + ∫₀^X κ0`; a moment `M` at its tip
/// adds `M / EI` to the curvature everywhere.
///
/// # Example
/// ```
/// use softrod::assembly::RestCurvatureProfile;
/// let p: RestCurvatureProfile = serde_json::from_str(
///     r#"{"s_m": [0, 0.05, 0.05, 0.1], "kappa_per_m": [0, 0, 5, 5]}"#).unwrap();
/// assert_eq!((p.at(0.04), p.at(0.05), p.at(0.07)), (0.0, 5.0, 5.0));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RestCurvatureProfile {
    /// Arc coordinates of the entries (m from the section's start, non-decreasing).
    pub s_m: Vec<f64>,
    /// Rest curvature at each entry (1/m, counter-clockwise positive).
    pub kappa_per_m: Vec<f64>,
}

impl RestCurvatureProfile {
    /// `κ0` (1/m) at `x` (m); the first or last value beyond the table's ends.
    pub fn at(&self, x: f64) -> f64 {
        let k = self.s_m.partition_point(|&s| s <= x);
        let Some(k) = k.checked_sub(1) else {
            return self.kappa_per_m.first().copied().unwrap_or(0.0);
        };
        match (
            self.s_m.get(k),
            self.s_m.get(k + 1),
            self.kappa_per_m.get(k),
            self.kappa_per_m.get(k + 1),
        ) {
            (Some(s0), Some(s1), Some(a), Some(b)) if s1 > s0 => a + (x - s0) / (s1 - s0) * (b - a),
            (_, _, Some(a), _) => *a,
            _ => 0.0,
        }
    }

    /// The same profile seen from `offset` (m) further along: entry `k` at
    /// `s_m[k] − offset` (the profile of an element starting at `offset`).
    pub(crate) fn shifted(&self, offset: f64) -> Self {
        RestCurvatureProfile {
            s_m: self.s_m.iter().map(|s| s - offset).collect(),
            kappa_per_m: self.kappa_per_m.clone(),
        }
    }
}
