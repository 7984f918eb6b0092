//! Pinches with closed forms, shared by the friction check's and the
//! slip's tests.

use crate::grasp::friction::FrictionContact;

/// Two flat vertical jaws at `x = ∓x_m` touching at heights `y_m` (left,
/// right), each pressing inward with `n` (N).
pub(crate) fn flat_jaws(x_m: f64, y_m: [f64; 2], n: f64) -> [FrictionContact; 2] {
    [
        FrictionContact {
            point_m: [-x_m, y_m[0]],
            normal: [1.0, 0.0],
            max_normal_force_n: n,
        },
        FrictionContact {
            point_m: [x_m, y_m[1]],
            normal: [-1.0, 0.0],
            max_normal_force_n: n,
        },
    ]
}

/// A disc of radius `r_m` about the origin pinched at the two points at
/// elevation `theta_rad` above its centre (below when negative), the
/// normals through the centre, each pressing with `n` (N).
pub(crate) fn disc_pinch(r_m: f64, theta_rad: f64, n: f64) -> [FrictionContact; 2] {
    let (s, c) = theta_rad.sin_cos();
    [
        FrictionContact {
            point_m: [-r_m * c, r_m * s],
            normal: [c, -s],
            max_normal_force_n: n,
        },
        FrictionContact {
            point_m: [r_m * c, r_m * s],
            normal: [-c, -s],
            max_normal_force_n: n,
        },
    ]
}
