//! The robot's configurations without a solve: the straight reference and
//! the arcs of its actuation (where a cold static solve starts).

use nalgebra::DVector;

use super::Robot;
use crate::element::Element;

impl<E: Element> Robot<E> {
    /// The stress-free straight configuration along the base direction
    /// (exact equilibrium without loads, actuation and rest curvature), all
    /// `n_q` coordinates.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration();
    /// assert_eq!(q.len(), robot.n_q());
    /// // tip node: at (0.24, 0), tangent (1, 0)
    /// assert_eq!(q.rows(robot.n_q() - 4, 4).as_slice(), &[0.24, 0.0, 1.0, 0.0]);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn reference_configuration(&self) -> DVector<f64> {
        let d = E::DIM;
        self.rod
            .straight_configuration(&self.base_node[..d], &self.base_node[d..2 * d])
    }

    /// The configuration the section torques of `pressures` (plus rest
    /// curvature) would give without any other load: each section a circular
    /// arc of curvature `κ_s = M_s / EI_s + κ0_s`, inextensible (planar
    /// robots; a spatial robot gets the straight configuration). The static
    /// solver starts cold solves here: it is exact for pure actuation and
    /// much closer to equilibrium than the straight line.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{Chamber, RobotSpec, Section};
    /// use softrod::loads::Loads;
    /// use softrod::statics::StaticSolver;
    /// let mut section = Section::uniform(0.24, 300.0, 0.025, 8);
    /// section.chambers = vec![Chamber { gain_nm_per_pa: vec![1e-6], pressure_min_pa: -1e5, pressure_max_pa: 1e5 }];
    /// let robot = RobotSpec::new(vec![section]).build_planar()?;
    /// let q = robot.arc_configuration(&[2e4]);
    /// // pure actuation: the arc is the equilibrium
    /// let loads = Loads { pressures_pa: vec![2e4], ..Loads::default() };
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// assert!((q - &eq.q).amax() < 1e-6);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn arc_configuration(&self, pressures: &[f64]) -> DVector<f64> {
        if E::DIM != 2 || E::MOMENT_DIM != 1 {
            return self.reference_configuration();
        }
        let nd = E::NODE_DOFS;
        let torques = self.section_torques(pressures);
        let mut q = Vec::with_capacity(self.n_q());
        let th0 = match self.spec.base.direction {
            None => self.spec.base.angle_rad,
            Some(_) => self.base_node[3].atan2(self.base_node[2]),
        };
        let (mut x, mut y, mut th) = (self.base_node[0], self.base_node[1], th0);
        let mut s_prev = 0.0;
        for (i, &s) in self.rod.node_arc().iter().enumerate() {
            if i > 0 {
                let sec = self.section_of_element(i - 1);
                let spec = &self.rod.sections()[sec];
                let ds = s - s_prev;
                let start = self.rod.node_arc()[self.section_nodes()[sec].0];
                let k = torques.get((0, sec)).copied().unwrap_or(0.0) / spec.ei_nm2
                    + spec.rest_curvature_at(s_prev + 0.5 * ds - start);
                let dth = k * ds;
                if dth.abs() < 1e-9 {
                    x += ds * (th + 0.5 * dth).cos();
                    y += ds * (th + 0.5 * dth).sin();
                } else {
                    x += ((th + dth).sin() - th.sin()) / k;
                    y += (th.cos() - (th + dth).cos()) / k;
                }
                th += dth;
            }
            s_prev = s;
            let node = E::straight_node(&[x, y], &[th.cos(), th.sin()]);
            q.extend(node.iter().take(nd));
        }
        DVector::from_vec(q)
    }
}
