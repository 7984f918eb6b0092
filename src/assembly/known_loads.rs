//! The checks and conversions of known loads ([`Load`]) that need the
//! robot: [`Load::validate`] (places on the robot, the element's
//! dimensions), [`Loads::add`] and [`Loads::from_loads`]. They live with
//! the robot so that `loads` stays below `assembly`.

use super::Robot;
use crate::element::Element;
use crate::error::{Error, Result, check_index, check_len};
use crate::loads::{LineLoad, Load, Loads};

impl Load {
    /// Checks this load against `robot`: vectors of the element's
    /// dimension (a moment of its moment dimension), finite values, a
    /// positive tip mass, a non-negative extra weight, and places on the
    /// robot (arc positions, a node beyond the clamped base, a table's
    /// entries, a Gaussian's centre, a follower load on a planar robot).
    /// Errors name the field under `path` (`path.field`; just `field` when
    /// `path` is empty): a scene checks its `loads[i]` with
    /// `path = "loads[i]"`, and [`Loads::add`] with `""`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`], [`Error::DimensionMismatch`] or
    /// [`Error::IndexOutOfRange`] naming the field at fault.
    ///
    /// # Example
    /// ```
    /// use softrod::loads::Load;
    /// let robot = softrod::scene::Scene::two_section().robot()?;
    /// let off = Load::PointForce { s_m: 0.5, force_n: vec![0.0, -0.1] };
    /// assert_eq!(off.validate(&robot, "loads[2]").unwrap_err().field(), Some("loads[2].s_m"));
    /// let short = Load::TipForce { force_n: vec![0.0] };
    /// assert_eq!(short.validate(&robot, "").unwrap_err().field(), Some("force_n"));
    /// assert!(Load::TipMass { mass_kg: 0.02 }.validate(&robot, "loads[0]").is_ok());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn validate<E: Element>(&self, robot: &Robot<E>, path: &str) -> Result<()> {
        self.check_values(E::DIM, E::MOMENT_DIM)
            .and_then(|()| self.check_place(robot))
            .map_err(|e| {
                if path.is_empty() {
                    e
                } else {
                    e.with_prefix(&format!("{path}."))
                }
            })
    }

    /// The checks of [`Load::validate`] against the robot's extent: arc
    /// positions on it, moments beyond the clamped base.
    fn check_place<E: Element>(&self, robot: &Robot<E>) -> Result<()> {
        match self {
            Load::Distributed(l) => {
                l.check_on_robot("", robot.length())?;
                match l {
                    // a bump centred off the robot acts only through its tail:
                    // almost surely a typo (a length in mm, the wrong section)
                    LineLoad::Gaussian { center_m, .. } => {
                        robot.locate("center_m", *center_m).map(|_| ())
                    }
                    _ => Ok(()),
                }
            }
            Load::PointForce { s_m, .. } => robot.locate("s_m", *s_m).map(|_| ()),
            Load::NodeMoment { node, .. } => {
                check_index("node", *node, robot.n_nodes())?;
                if *node == 0 {
                    return Err(Error::invalid(
                        "node",
                        0,
                        "the clamped base takes no moment: must be a free node, >= 1",
                    ));
                }
                Ok(())
            }
            Load::Moment { s_m, .. } => {
                robot.locate("s_m", *s_m)?;
                if *s_m <= 0.0 {
                    return Err(Error::invalid(
                        "s_m",
                        s_m,
                        "the clamped base takes no moment: must be > 0",
                    ));
                }
                Ok(())
            }
            Load::Follower(f) => f.validate("", robot.length()),
            Load::TipForce { .. }
            | Load::TipMoment { .. }
            | Load::SelfWeight { .. }
            | Load::TipMass { .. } => Ok(()),
        }
    }
}

impl Loads {
    /// Adds `load` for `robot`: a tip load at the robot's tip (its length,
    /// its last node), a tip mass under the robot's gravity; the other
    /// kinds as they are. The same check ([`Load::validate`]) and
    /// conversion a scene's loads take ([`crate::scene::Scene::loads`]):
    /// a load a scene refuses is refused here too. Errors name the load's
    /// fields.
    ///
    /// # Errors
    /// As [`Load::validate`]; [`Error::DimensionMismatch`] for a tip mass
    /// on a robot whose gravity has the wrong size.
    ///
    /// # Example
    /// See [`Load`].
    pub fn add<E: Element>(&mut self, robot: &Robot<E>, load: &Load) -> Result<()> {
        load.validate(robot, "")?;
        load.resolve_into(
            E::DIM,
            robot.length(),
            robot.n_nodes(),
            robot.rod().gravity(),
            self,
        )
    }

    /// The loads of a solve from the chamber pressures (Pa) and a list of
    /// known [`Load`]s, as a scene states them: each checked
    /// ([`Load::validate`], errors named `loads[i].…` as in a scene file)
    /// and added ([`Loads::add`]).
    ///
    /// # Errors
    /// As [`Load::validate`] for `loads[i]`; [`Error::DimensionMismatch`]
    /// named `pressures_pa` if there is not one pressure per chamber.
    ///
    /// # Example
    /// ```
    /// use softrod::loads::{Load, Loads, MomentNm};
    /// let robot = softrod::scene::Scene::two_section().robot()?;
    /// let loads = Loads::from_loads(&robot, &[0.0; 4], &[
    ///     Load::TipForce { force_n: vec![0.0, -0.05] },
    ///     Load::Moment { s_m: 0.12, moment_nm: MomentNm::Scalar(0.002) },
    /// ])?;
    /// assert_eq!((loads.point_forces.len(), loads.point_moments.len()), (1, 1));
    /// let bad = Loads::from_loads(&robot, &[0.0; 4], &[Load::TipMass { mass_kg: -1.0 }]);
    /// assert_eq!(bad.unwrap_err().field(), Some("loads[0].mass_kg"));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn from_loads<E: Element>(
        robot: &Robot<E>,
        pressures_pa: &[f64],
        loads: &[Load],
    ) -> Result<Loads> {
        check_len("pressures_pa", robot.n_pressures(), pressures_pa.len())?;
        let mut out = Loads {
            pressures_pa: pressures_pa.to_vec(),
            ..Loads::default()
        };
        for (i, load) in loads.iter().enumerate() {
            load.validate(robot, &format!("loads[{i}]"))?;
            load.resolve_into(
                E::DIM,
                robot.length(),
                robot.n_nodes(),
                robot.rod().gravity(),
                &mut out,
            )?;
        }
        Ok(out)
    }
}
