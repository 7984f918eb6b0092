//! Payloads the controller is not told about, with a schedule in time.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_finite};
use crate::loads::{LineLoad, Loads, PointForce};

/// Where a payload's mass hangs.
///
/// # Example
/// ```
/// use softrod::plant::PayloadKind;
/// let k: PayloadKind = serde_json::from_str(r#"{"kind": "point_mass", "mass_kg": 0.02, "s_m": 0.24}"#)?;
/// assert_eq!(k, PayloadKind::PointMass { mass_kg: 0.02, s_m: 0.24 });
/// # Ok::<(), serde_json::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PayloadKind {
    /// A mass hanging at one point of the backbone (a tip mass at `s_m = L`).
    PointMass {
        /// Mass (kg, ≥ 0).
        mass_kg: f64,
        /// Undeformed arc coordinate (m).
        s_m: f64,
    },
    /// A mass spread evenly along the whole backbone.
    Distributed {
        /// Mass per undeformed length (kg/m, ≥ 0).
        mass_per_length_kg_per_m: f64,
    },
    /// A point mass that slides along the backbone at constant speed from
    /// `from_s_m` (at the payload's `start_s`) to `to_s_m`, where it stays.
    Sliding {
        /// Mass (kg, ≥ 0).
        mass_kg: f64,
        /// Arc coordinate at the start (m).
        from_s_m: f64,
        /// Arc coordinate at the end (m).
        to_s_m: f64,
        /// Sliding speed along the arc (m/s, > 0).
        speed_m_per_s: f64,
    },
}

/// One payload: what it is and when it acts (`start_s ≤ t < end_s`).
///
/// # Example
/// A 20 g tip mass hung on the 240 mm robot after 2 s:
/// ```
/// use softrod::plant::{Payload, PayloadKind};
/// let p = Payload { kind: PayloadKind::PointMass { mass_kg: 0.02, s_m: 0.24 }, start_s: 2.0, end_s: None };
/// assert!(!p.acts_at(1.0) && p.acts_at(2.5));
/// // as written in a file: the kind's fields and the times side by side
/// let q: Payload = serde_json::from_str(r#"{"kind": "point_mass", "mass_kg": 0.02, "s_m": 0.24, "start_s": 2.0}"#).unwrap();
/// assert_eq!(q, p);
/// assert!(serde_json::from_str::<Payload>(r#"{"kind": "point_mass", "mass_kg": 0.02, "s_m": 0.24, "colour": 1}"#).is_err());
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "PayloadRepr")]
pub struct Payload {
    /// The payload.
    #[serde(flatten)]
    pub kind: PayloadKind,
    /// Time it is put on (s, ≥ 0; default 0).
    #[serde(default)]
    pub start_s: f64,
    /// Time it is taken off (s, > `start_s`), or never (default).
    #[serde(default)]
    pub end_s: Option<f64>,
}

/// A payload as written: the kind's fields and the times side by side
/// (serde's `flatten` cannot refuse unknown fields, this can).
#[derive(Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
enum PayloadRepr {
    PointMass {
        mass_kg: f64,
        s_m: f64,
        #[serde(default)]
        start_s: f64,
        #[serde(default)]
        end_s: Option<f64>,
    },
    Distributed {
        mass_per_length_kg_per_m: f64,
        #[serde(default)]
        start_s: f64,
        #[serde(default)]
        end_s: Option<f64>,
    },
    Sliding {
        mass_kg: f64,
        from_s_m: f64,
        to_s_m: f64,
        speed_m_per_s: f64,
        #[serde(default)]
        start_s: f64,
        #[serde(default)]
        end_s: Option<f64>,
    },
}

impl From<PayloadRepr> for Payload {
    fn from(r: PayloadRepr) -> Self {
        match r {
            PayloadRepr::PointMass {
                mass_kg,
                s_m,
                start_s,
                end_s,
            } => Payload {
                kind: PayloadKind::PointMass { mass_kg, s_m },
                start_s,
                end_s,
            },
            PayloadRepr::Distributed {
                mass_per_length_kg_per_m,
                start_s,
                end_s,
            } => Payload {
                kind: PayloadKind::Distributed {
                    mass_per_length_kg_per_m,
                },
                start_s,
                end_s,
            },
            PayloadRepr::Sliding {
                mass_kg,
                from_s_m,
                to_s_m,
                speed_m_per_s,
                start_s,
                end_s,
            } => Payload {
                kind: PayloadKind::Sliding {
                    mass_kg,
                    from_s_m,
                    to_s_m,
                    speed_m_per_s,
                },
                start_s,
                end_s,
            },
        }
    }
}

impl Payload {
    /// Whether the payload acts at time `t` (s).
    pub fn acts_at(&self, t: f64) -> bool {
        t >= self.start_s && self.end_s.is_none_or(|e| t < e)
    }
}

/// A schedule of payloads (any number act at once: a "mixed" payload is
/// several entries).
///
/// # Example
/// ```
/// use softrod::plant::PayloadSchedule;
/// let s = PayloadSchedule::tip_mass(0.02, 0.24);
/// s.validate(0.24)?;
/// let loads = s.loads_at(1.0, &[0.0, -9.81], &softrod::loads::Loads::default());
/// assert!((loads.point_forces[0].force_n[1] + 0.02 * 9.81).abs() < 1e-15);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PayloadSchedule {
    /// The payloads.
    pub payloads: Vec<Payload>,
}

impl PayloadSchedule {
    /// No payload.
    pub fn none() -> Self {
        PayloadSchedule::default()
    }

    /// A mass at the tip of a robot of length `length_m`, from the start.
    pub fn tip_mass(mass_kg: f64, length_m: f64) -> Self {
        PayloadSchedule {
            payloads: vec![Payload {
                kind: PayloadKind::PointMass {
                    mass_kg,
                    s_m: length_m,
                },
                start_s: 0.0,
                end_s: None,
            }],
        }
    }

    /// Checks every field against a robot of length `length_m`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`payloads[i].mass_kg`,
    /// `payloads[i].s_m`, `payloads[i].end_s`, …): a negative or non-finite
    /// mass, a point off the robot, a start before 0, an end not after the
    /// start (time going backwards), a sliding speed ≤ 0.
    pub fn validate(&self, length_m: f64) -> Result<()> {
        for (i, p) in self.payloads.iter().enumerate() {
            let f = |name: &str| format!("payloads[{i}].{name}");
            let mass = |name: &str, m: f64| -> Result<()> {
                if m.is_finite() && m >= 0.0 {
                    Ok(())
                } else {
                    Err(Error::invalid(f(name), m, "must be finite and >= 0"))
                }
            };
            let on_robot = |name: &str, s: f64| -> Result<()> {
                if s.is_finite() && (0.0..=length_m).contains(&s) {
                    Ok(())
                } else {
                    Err(Error::invalid(
                        f(name),
                        s,
                        format!("must lie on the robot, in [0, {length_m}] m"),
                    ))
                }
            };
            match &p.kind {
                PayloadKind::PointMass { mass_kg, s_m } => {
                    mass("mass_kg", *mass_kg)?;
                    on_robot("s_m", *s_m)?;
                }
                PayloadKind::Distributed {
                    mass_per_length_kg_per_m,
                } => mass("mass_per_length_kg_per_m", *mass_per_length_kg_per_m)?,
                PayloadKind::Sliding {
                    mass_kg,
                    from_s_m,
                    to_s_m,
                    speed_m_per_s,
                } => {
                    mass("mass_kg", *mass_kg)?;
                    on_robot("from_s_m", *from_s_m)?;
                    on_robot("to_s_m", *to_s_m)?;
                    if !(speed_m_per_s.is_finite() && *speed_m_per_s > 0.0) {
                        return Err(Error::invalid(
                            f("speed_m_per_s"),
                            speed_m_per_s,
                            "must be finite and > 0",
                        ));
                    }
                }
            }
            check_finite(&f("start_s"), p.start_s)?;
            if p.start_s < 0.0 {
                return Err(Error::invalid(f("start_s"), p.start_s, "must be >= 0"));
            }
            if let Some(e) = p.end_s
                && !(e.is_finite() && e > p.start_s)
            {
                return Err(Error::invalid(
                    f("end_s"),
                    e,
                    format!(
                        "must be after start_s = {} s (time cannot go backwards)",
                        p.start_s
                    ),
                ));
            }
        }
        Ok(())
    }

    /// `base` plus the weights of the payloads acting at time `t` under
    /// gravity `gravity_m_per_s2` (point forces and uniform line loads).
    pub fn loads_at(&self, t: f64, gravity_m_per_s2: &[f64], base: &Loads) -> Loads {
        let mut loads = base.clone();
        let weight = |m: f64| gravity_m_per_s2.iter().map(|g| m * g).collect::<Vec<f64>>();
        for p in self.payloads.iter().filter(|p| p.acts_at(t)) {
            match &p.kind {
                PayloadKind::PointMass { mass_kg, s_m } => loads.point_forces.push(PointForce {
                    s_m: *s_m,
                    force_n: weight(*mass_kg),
                }),
                PayloadKind::Distributed {
                    mass_per_length_kg_per_m,
                } => loads.line_loads.push(LineLoad::Uniform {
                    w_n_per_m: weight(*mass_per_length_kg_per_m),
                }),
                PayloadKind::Sliding {
                    mass_kg,
                    from_s_m,
                    to_s_m,
                    speed_m_per_s,
                } => {
                    let travelled = speed_m_per_s * (t - p.start_s);
                    let span = to_s_m - from_s_m;
                    let s = from_s_m + span.signum() * travelled.min(span.abs());
                    loads.point_forces.push(PointForce {
                        s_m: s,
                        force_n: weight(*mass_kg),
                    });
                }
            }
        }
        loads
    }

    /// The total payload mass acting at time `t` on a robot of length
    /// `length_m` (kg).
    pub fn mass_at(&self, t: f64, length_m: f64) -> f64 {
        self.payloads
            .iter()
            .filter(|p| p.acts_at(t))
            .map(|p| match &p.kind {
                PayloadKind::PointMass { mass_kg, .. } | PayloadKind::Sliding { mass_kg, .. } => {
                    *mass_kg
                }
                PayloadKind::Distributed {
                    mass_per_length_kg_per_m,
                } => mass_per_length_kg_per_m * length_m,
            })
            .sum()
    }
}
