//! Building a rod: the checks of its sections and the assembly of its
//! elements, self-weight and load Gram matrix.

use super::{ChamberRef, MAX_EDOF, MAX_ELEMENTS, Rod, Section, add_shape_force, slot};
use super::{MAX_SECTION_LENGTH_M, MAX_SECTION_LENGTH_RATIO};
use crate::element::Element;
use crate::error::{
    Error, Result, check_all_finite, check_at_most, check_finite, check_len, check_positive,
};
use crate::linsolve::BandedMatrix;
use crate::quadrature::GaussRule;

/// Largest rest curvature times section length a profile may hold: `|κ0| L`
/// is the angle the section turns through unloaded (rad); beyond 1e6 turns
/// it is a unit mistake or a value that can only overflow.
const MAX_REST_TURN_RAD: f64 = 1e6 * std::f64::consts::TAU;

/// Checks a rest-curvature profile of `section` (fields `path.s_m[k]`,
/// `path.kappa_per_m[k]`): at least two entries, as many values as arc
/// positions, finite, non-decreasing from 0 to the section's length, and
/// the constant `rest_curvature_per_m` left at 0.
fn check_rest_curvature_profile(
    path: &str,
    p: &super::super::section::RestCurvatureProfile,
    section: &Section,
) -> Result<()> {
    if section.rest_curvature_per_m != 0.0 {
        return Err(Error::invalid(
            path.replace("rest_curvature_profile", "rest_curvature_per_m"),
            section.rest_curvature_per_m,
            "must be 0 when the section has a rest_curvature_profile (give one or the other)",
        ));
    }
    if p.s_m.len() < 2 {
        return Err(Error::invalid(
            format!("{path}.s_m"),
            format!("{:?}", p.s_m),
            "a profile needs at least two entries",
        ));
    }
    check_len(
        &format!("{path}.kappa_per_m"),
        p.s_m.len(),
        p.kappa_per_m.len(),
    )?;
    let l = section.length_m;
    let tol = 1e-12 * l;
    let last = p.s_m.len() - 1;
    for (k, s) in p.s_m.iter().enumerate() {
        let name = format!("{path}.s_m[{k}]");
        check_finite(&name, *s)?;
        if k == 0 && s.abs() > tol {
            return Err(Error::invalid(
                name,
                s,
                "the profile starts at the section's start: must be 0",
            ));
        }
        if k > 0 && *s < p.s_m[k - 1] {
            return Err(Error::invalid(
                name,
                s,
                format!("must not be less than the entry before, {} m", p.s_m[k - 1]),
            ));
        }
        if k == last && (s - l).abs() > tol {
            return Err(Error::invalid(
                name,
                s,
                format!("the profile ends at the section's end: must be its length_m, {l} m"),
            ));
        }
    }
    for (k, v) in p.kappa_per_m.iter().enumerate() {
        let name = format!("{path}.kappa_per_m[{k}]");
        check_finite(&name, *v)?;
        if v.abs() * l > MAX_REST_TURN_RAD {
            return Err(Error::invalid(
                name,
                v,
                format!(
                    "times the section's length {l} m turns by more than {MAX_REST_TURN_RAD:e} rad \
                     (curvatures are in 1/m)"
                ),
            ));
        }
    }
    Ok(())
}

/// Refuses a section longer than [`MAX_SECTION_LENGTH_M`] and sections whose
/// lengths differ by more than [`MAX_SECTION_LENGTH_RATIO`], naming the
/// longest (lengths already checked finite and positive).
fn check_section_lengths(path: &str, sections: &[Section]) -> Result<()> {
    let (mut long, mut short) = (0, 0);
    for (i, s) in sections.iter().enumerate() {
        if s.length_m > sections[long].length_m {
            long = i;
        }
        if s.length_m < sections[short].length_m {
            short = i;
        }
    }
    let Some(l) = sections.get(long).map(|s| s.length_m) else {
        return Ok(());
    };
    let name = format!("{path}.sections[{long}].length_m");
    if l > MAX_SECTION_LENGTH_M {
        return Err(Error::invalid(
            name,
            l,
            format!("must be at most {MAX_SECTION_LENGTH_M:e} m (lengths are in m)"),
        ));
    }
    let shortest = sections[short].length_m;
    if l > MAX_SECTION_LENGTH_RATIO * shortest {
        // name the one farther from the metre scale; mention the other
        let (bad, other) = if l.ln().abs() >= shortest.ln().abs() {
            (long, short)
        } else {
            (short, long)
        };
        return Err(Error::invalid(
            format!("{path}.sections[{bad}].length_m"),
            sections[bad].length_m,
            format!(
                "differs from `{path}.sections[{other}].length_m` = {:e} m by more than a factor \
                 {MAX_SECTION_LENGTH_RATIO:e}: arc positions on the shorter section cannot be resolved",
                sections[other].length_m
            ),
        ));
    }
    Ok(())
}

impl<E: Element> Rod<E> {
    /// The checks of [`Rod::new`] that bound what it allocates: at least one
    /// section, an element type the assembly can hold, at most
    /// [`MAX_ELEMENTS`] elements. Returns the number of elements.
    pub(crate) fn check_layout(sections: &[Section], path: &str) -> Result<usize> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        if sections.is_empty() {
            return Err(Error::invalid(
                format!("{path}.sections"),
                "[]",
                "a robot needs at least one section",
            ));
        }
        // the assembly's fixed-size scratch buffers and node layout
        if d == 0 || E::MOMENT_DIM == 0 || nd < 2 * d || 2 * nd > MAX_EDOF {
            return Err(Error::invalid(
                "element",
                format!("DIM = {d}, NODE_DOFS = {nd}"),
                format!("needs 2 DIM <= NODE_DOFS <= {}", MAX_EDOF / 2),
            ));
        }
        let mut total = 0usize;
        for (i, s) in sections.iter().enumerate() {
            // `total <= MAX_ELEMENTS` here, so the subtraction cannot underflow
            check_at_most(
                &format!("{path}.sections[{i}].elements"),
                s.elements,
                MAX_ELEMENTS - total,
            )?;
            total += s.elements;
        }
        Ok(total)
    }

    /// All checks of [`Rod::new`], without building anything: returns the
    /// number of elements.
    pub(crate) fn check_sections(
        sections: &[Section],
        gravity_m_per_s2: &[f64],
        axial_gauss_points: usize,
        bending_gauss_points: usize,
        path: &str,
    ) -> Result<usize> {
        let d = E::DIM;
        let total = Self::check_layout(sections, path)?;
        check_len("gravity_m_per_s2", d, gravity_m_per_s2.len())?;
        check_all_finite("gravity_m_per_s2", gravity_m_per_s2)?;
        for (name, n) in [
            (format!("{path}.axial_gauss_points"), axial_gauss_points),
            (format!("{path}.bending_gauss_points"), bending_gauss_points),
        ] {
            if n == 0 {
                return Err(Error::invalid(name, n, "must be >= 1"));
            }
            check_at_most(&name, n, crate::quadrature::MAX_POINTS)?;
        }
        for (i, s) in sections.iter().enumerate() {
            let p = |f: &str| format!("{path}.sections[{i}].{f}");
            check_positive(&p("length_m"), s.length_m)?;
            check_positive(&p("ea_n"), s.ea_n)?;
            check_positive(&p("ei_nm2"), s.ei_nm2)?;
            if !(s.mass_per_length_kg_per_m.is_finite() && s.mass_per_length_kg_per_m >= 0.0) {
                return Err(Error::invalid(
                    p("mass_per_length_kg_per_m"),
                    s.mass_per_length_kg_per_m,
                    "must be finite and >= 0",
                ));
            }
            if s.elements == 0 {
                return Err(Error::invalid(
                    p("elements"),
                    0,
                    "a section needs at least one element",
                ));
            }
            check_finite(&p("rest_curvature_per_m"), s.rest_curvature_per_m)?;
            if let Some(profile) = &s.rest_curvature_profile {
                check_rest_curvature_profile(&p("rest_curvature_profile"), profile, s)?;
            }
            for (c, ch) in s.chambers.iter().enumerate() {
                let pc = |f: &str| format!("{path}.sections[{i}].chambers[{c}].{f}");
                check_len(
                    &pc("gain_nm_per_pa"),
                    E::MOMENT_DIM,
                    ch.gain_nm_per_pa.len(),
                )?;
                check_all_finite(&pc("gain_nm_per_pa"), &ch.gain_nm_per_pa)?;
                check_finite(&pc("pressure_min_pa"), ch.pressure_min_pa)?;
                check_finite(&pc("pressure_max_pa"), ch.pressure_max_pa)?;
                if ch.pressure_min_pa > ch.pressure_max_pa {
                    return Err(Error::invalid(
                        pc("pressure_max_pa"),
                        ch.pressure_max_pa,
                        format!(
                            "must be >= `{}` = {}: one of the two is wrong",
                            pc("pressure_min_pa"),
                            ch.pressure_min_pa
                        ),
                    ));
                }
            }
        }
        check_section_lengths(path, sections)?;
        Ok(total)
    }

    /// Validates the sections and builds the rod; `make` builds one element
    /// of a section from `(section, element length, axial points, bending
    /// points)`. Field names start with `path` (`robot` gives
    /// `robot.sections[1].ei_nm2`); gravity is `gravity_m_per_s2` (m/s²).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field at fault for no
    /// sections, zero elements, non-positive lengths or stiffnesses,
    /// negative mass, non-finite numbers, inverted pressure bounds, Gauss
    /// rules of no points, or an element type whose constants do not fit;
    /// [`Error::TooLarge`] for more than [`MAX_ELEMENTS`] elements or Gauss
    /// rules above [`crate::quadrature::MAX_POINTS`] points (both refused
    /// before anything proportional is allocated);
    /// [`Error::DimensionMismatch`] for vectors of the wrong size. Errors of
    /// `make` come back with the section's path prefixed to the field name.
    pub fn new(
        sections: &[Section],
        gravity_m_per_s2: &[f64],
        axial_gauss_points: usize,
        bending_gauss_points: usize,
        path: &str,
        make: impl Fn(&Section, f64, usize, usize) -> Result<E>,
    ) -> Result<Self> {
        let nd = E::NODE_DOFS;
        let total = Self::check_sections(
            sections,
            gravity_m_per_s2,
            axial_gauss_points,
            bending_gauss_points,
            path,
        )?;
        let chambers: Vec<ChamberRef> = sections
            .iter()
            .enumerate()
            .flat_map(|(i, s)| {
                s.chambers.iter().map(move |ch| ChamberRef {
                    section: i,
                    gain: ch.gain_nm_per_pa.clone(),
                    min: ch.pressure_min_pa,
                    max: ch.pressure_max_pa,
                })
            })
            .collect();
        // elements and nodes
        let mut elements = Vec::with_capacity(total);
        let mut node_s = Vec::with_capacity(total + 1);
        let mut section_nodes = Vec::with_capacity(sections.len());
        node_s.push(0.0);
        let mut s0 = 0.0;
        for (i, sec) in sections.iter().enumerate() {
            let le = sec.length_m / sec.elements as f64;
            let start = node_s.len() - 1;
            let prefix = |e: Error| e.with_prefix(&format!("{path}.sections[{i}]."));
            let proto = make(sec, le, axial_gauss_points, bending_gauss_points).map_err(prefix)?;
            for k in 0..sec.elements {
                match &sec.rest_curvature_profile {
                    // κ0(X) differs from element to element: each its own piece
                    Some(p) => {
                        let piece = Section {
                            rest_curvature_profile: Some(p.shifted(k as f64 * le)),
                            ..sec.clone()
                        };
                        elements.push(
                            make(&piece, le, axial_gauss_points, bending_gauss_points)
                                .map_err(prefix)?,
                        );
                    }
                    None => elements.push(proto.clone()),
                }
                node_s.push(if k + 1 == sec.elements {
                    s0 + sec.length_m
                } else {
                    s0 + (k + 1) as f64 * le
                });
            }
            s0 += sec.length_m;
            section_nodes.push((start, node_s.len() - 1));
        }
        let n_q = node_s.len() * nd;
        let kb = 2 * nd - 1;
        let line_rule = GaussRule::new(5)?;
        let mut rod = Rod {
            sections: sections.to_vec(),
            gravity: gravity_m_per_s2.to_vec(),
            elements,
            node_s,
            section_nodes,
            gravity_force: vec![0.0; n_q],
            chambers,
            gram: BandedMatrix::zeros(n_q, kb, kb),
            elem_gram: Vec::new(),
            line_rule,
        };
        rod.assemble_gram();
        // self-weight: uniform line load m g per section
        let mut gravity = vec![0.0; n_q];
        for (e, el) in rod.elements.iter().enumerate() {
            let m = rod.sections[rod.section_of_element(e)].mass_per_length_kg_per_m;
            if m == 0.0 {
                continue;
            }
            let w: Vec<f64> = rod.gravity.iter().map(|g| m * g).collect();
            for (xi, wt) in rod.line_rule.iter() {
                add_shape_force(
                    el,
                    xi,
                    &w,
                    wt * el.length(),
                    &mut gravity[e * nd..(e + 2) * nd],
                );
            }
        }
        rod.gravity_force = gravity;
        Ok(rod)
    }

    fn assemble_gram(&mut self) {
        let nd = E::NODE_DOFS;
        let d = E::DIM;
        let rule = GaussRule::new(4).unwrap_or_else(|_| self.line_rule.clone());
        let mut blocks = Vec::with_capacity(self.elements.len());
        for (e, el) in self.elements.iter().enumerate() {
            let le = el.length();
            let mut m = [[0.0; 4]; 4];
            for (xi, w) in rule.iter() {
                let s = el.shape(xi);
                for k in 0..4 {
                    for l in 0..4 {
                        m[k][l] += w * le * s[k] * s[l];
                    }
                }
            }
            // S = [s_1 I, s_2 I, s_3 I, s_4 I]; component k of q_e block = s_k
            for (k, mk) in m.iter().enumerate() {
                for (l, mkl) in mk.iter().enumerate() {
                    for i in 0..d {
                        self.gram
                            .add(e * nd + slot::<E>(k) + i, e * nd + slot::<E>(l) + i, *mkl);
                    }
                }
            }
            blocks.push(m);
        }
        self.elem_gram = blocks;
    }
}
