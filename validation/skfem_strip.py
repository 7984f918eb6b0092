"""Cantilever references from a 2-D continuum strip (scikit-fem), plane stress, nu = 0.

The rod is replaced by a strip [0, L] x [-h/2, h/2] of unit out-of-plane
thickness, clamped on the face X = 0 (u = 0 there), discretized with
biquadratic Lagrange quadrilaterals (ElementVector(ElementQuad2), 4th-order
quadrature). With nu = 0, plane stress and plane strain coincide (lambda = 0,
mu = E/2).

Two strips:
- "slender": L/h = 30 (h = 0.008 m), E chosen so that E h^3/12 = EI = 0.025 N m^2;
  the equivalent rod has EA = E h = 12 EI/h^2 = 4687.5 N (params.rod_equivalent).
- "thick": the paper's EA = 300 N and EI = 0.025 N m^2 together, which forces
  h = sqrt(12 EI/EA) = 31.6 mm and E = EA/h (L/h = 7.6); for charting only
  ("pass_bound": null): a rod model is not expected to match it closely.

Loads, all dead and chosen to correspond to the rod's loads:
- line loads w(X) (uniform, linear, Gaussian, self-weight) as a BODY FORCE
  w(X)/h per unit reference volume, spread uniformly over the thickness;
- tip force P as a uniform traction P/h on the end face X = L;
- tip moment M as the linear normal traction t_x = -M y / I, I = h^3/12, on the end
  face (linear cases only: a dead traction is not a pure moment once the face
  rotates, so no large tip-moment case is solved here).

Small cases: linear elasticity. Large cases: geometrically nonlinear, total
Lagrangian St Venant-Kirchhoff (S = lambda tr(E) I + 2 mu E, E the Green-Lagrange
strain), Newton with load steps (halved on failure).

Reported: the centerline tip, i.e. the mid-height point (L, 0) of the end face;
the tip angle is the rotation of the end face's chord (bottom to top corner),
theta = atan2(-d_x, d_y); a mesh convergence table (three meshes, the finest is
the reference); and, for the slender strip, the inextensible/extensible rod
elastica with the strip's equivalent EA and EI, the difference to it and a
pass bound (2 x (|strip - rod| + mesh-change of the last refinement)).

Run: `python validation/skfem_strip.py [--out-dir reference] [--case NAME ...] [--strip slender|thick]`.
"""

import argparse
import math
import os
import sys

import numpy as np
from skfem import (
    Basis,
    BilinearForm,
    ElementQuad2,
    ElementVector,
    FacetBasis,
    LinearForm,
    MeshQuad,
    asm,
    condense,
    solve,
)
from skfem.helpers import grad
from skfem.models.elasticity import linear_elasticity

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common as C  # noqa: E402
import elastica  # noqa: E402

GENERATOR = "validation/skfem_strip.py"
INTORDER = 4
NEWTON_TOL = 1e-10  # on max|du| relative to max|u|
NEWTON_TOL_INTERMEDIATE = 1e-5
NEWTON_MAX_IT = 25
LOAD_STEPS = 10

STRIPS = {
    # thickness h, meshes (nx, ny): the last one is the reference
    "slender": {"h": 0.008, "meshes": [(32, 1), (64, 2), (128, 4)]},
    "thick": {"h": math.sqrt(12.0 * C.EI_NM2 / C.EA_N), "meshes": [(16, 2), (32, 4), (64, 8)]},
}

# cases solved here: small ones linearly, large ones nonlinearly
LINEAR_CASES = [
    "uniform_small",
    "linear_small",
    "gaussian_small",
    "tip_force_small",
    "tip_moment_small",
    "self_weight_moment_small",
]
NONLINEAR_CASES = ["uniform_large", "linear_large", "gaussian_large", "tip_force_large"]
SKFEM_CASES = LINEAR_CASES + NONLINEAR_CASES

I2 = np.eye(2)[:, :, None, None]


def _mul(A, B):
    return np.einsum("ij...,jk...->ik...", A, B)


def _tr(A):
    return A[0, 0] + A[1, 1]


def _ddot(A, B):
    return np.einsum("ij...,ij...", A, B)


def _svk(F, lam, mu):
    E = 0.5 * (_mul(np.swapaxes(F, 0, 1), F) - I2)
    return lam * _tr(E) * I2 + 2.0 * mu * E


def _tangent_moduli(F, S, lam, mu):
    """A with dP_ij = A_ijmn dG_mn for P = F S(F), S of St Venant-Kirchhoff.

    dP = dG S + F dS, dS = lam tr(dE) I + 2 mu dE, dE = sym(F^T dG):
    A_ijmn = delta_im S_nj + lam F_ij F_mn + mu (F F^T)_im delta_jn + mu F_in F_mj.
    """
    d = np.eye(2)
    A = np.einsum("im,nj...->ijmn...", d, S)
    A += lam * np.einsum("ij...,mn...->ijmn...", F, F)
    A += mu * np.einsum("ik...,mk...,jn->ijmn...", F, F, d)
    A += mu * np.einsum("in...,mj...->ijmn...", F, F)
    return A


@BilinearForm
def _tangent(du, v, w):
    return np.einsum("ijmn...,mn...,ij...->...", w["A"], grad(du), grad(v))


@LinearForm
def _internal(v, w):
    return _ddot(w["P"], grad(v))


class Strip:
    def __init__(self, h, nx, ny):
        self.h = h
        self.L = C.LENGTH_M
        self.E = 12.0 * C.EI_NM2 / h**3
        self.lam, self.mu = 0.0, 0.5 * self.E  # nu = 0
        self.nx, self.ny = nx, ny
        self.mesh = MeshQuad.init_tensor(np.linspace(0.0, self.L, nx + 1), np.linspace(-h / 2, h / 2, ny + 1))
        self.elem = ElementVector(ElementQuad2())
        self.basis = Basis(self.mesh, self.elem, intorder=INTORDER)
        self.end = FacetBasis(
            self.mesh, self.elem, facets=self.mesh.facets_satisfying(lambda x: np.isclose(x[0], self.L)), intorder=INTORDER
        )
        self.clamped = self.basis.get_dofs(lambda x: np.isclose(x[0], 0.0)).all()
        self.free = np.setdiff1d(np.arange(self.basis.N), self.clamped)
        self.probe = self.basis.probes(np.array([[self.L, self.L, self.L], [0.0, -h / 2, h / 2]]))

    def external(self, loads):
        """Dead external force vector for the rod loads (see module docstring)."""
        h = self.h
        inertia = h**3 / 12.0

        @LinearForm
        def body(v, w):
            wx, wy = C.line_load(loads, w.x[0])
            return (wx * v[0] + wy * v[1]) / h

        fx, fy = C.tip_force(loads)
        M = C.tip_moment(loads)

        @LinearForm
        def traction(v, w):
            return (fx / h - M * w.x[1] / inertia) * v[0] + (fy / h) * v[1]

        return asm(body, self.basis) + asm(traction, self.end)

    def tip(self, u):
        """Centerline tip position, end-face angle, and the mid-height tip displacement."""
        p = self.probe @ u  # [ux(mid), ux(bot), ux(top), uy(mid), uy(bot), uy(top)]
        ux, uy = p[0:3], p[3:6]
        dx = (ux[2] - ux[1])
        dy = self.h + (uy[2] - uy[1])
        return [self.L + ux[0], uy[0]], math.atan2(-dx, dy)

    def centerline(self, u):
        i0, i1 = self.basis.split_indices()
        loc = self.basis.doflocs
        sel0 = i0[np.isclose(loc[1, i0], 0.0)]
        sel1 = i1[np.isclose(loc[1, i1], 0.0)]
        o0 = np.argsort(loc[0, sel0])
        o1 = np.argsort(loc[0, sel1])
        X = loc[0, sel0][o0]
        return {"X_m": X, "x_m": X + u[sel0][o0], "y_m": u[sel1][o1]}

    def solve_linear(self, fext):
        K = asm(linear_elasticity(self.lam, self.mu), self.basis)
        u = solve(*condense(K, fext, D=self.clamped))
        return u, {"newton_iterations": 0}

    def solve_nonlinear(self, fext, steps=LOAD_STEPS):
        """Newton with load steps; secant predictor from the last two converged steps."""
        u = self.basis.zeros()
        u_prev, lam_prev = None, None
        lam_done, dlam = 0.0, 1.0 / steps
        total_it, n_steps, halvings = 0, 0, 0
        last_res = None
        while lam_done < 1.0 - 1e-14:
            target = min(1.0, lam_done + dlam)
            guess = u.copy()
            if u_prev is not None:
                guess += (target - lam_done) / (lam_done - lam_prev) * (u - u_prev)
            # loose tolerance on the intermediate load steps, tight on the last
            tol = NEWTON_TOL if target >= 1.0 - 1e-14 else NEWTON_TOL_INTERMEDIATE
            ut, ok, it, res = self._newton(guess, target * fext, tol)
            total_it += it
            if ok:
                u_prev, lam_prev = u, lam_done
                u, lam_done, last_res = ut, target, res
                n_steps += 1
                dlam = min(dlam * 1.5, 2.0 / steps)
            else:
                dlam *= 0.5
                halvings += 1
                if dlam < 1e-4:
                    raise RuntimeError(f"load stepping failed at load factor {lam_done}")
        return u, {"newton_iterations": total_it, "load_steps": n_steps, "step_halvings": halvings,
                   "final_residual_max_abs_n": last_res}

    def _state(self, u):
        """Deformation gradient F, second Piola-Kirchhoff S and first P = F S at the quadrature points."""
        F = grad(self.basis.interpolate(u)) + I2
        S = _svk(F, self.lam, self.mu)
        return F, S, _mul(F, S)

    def _residual(self, u, f):
        _, _, P = self._state(u)
        return asm(_internal, self.basis, P=P) - f

    def _newton(self, u, f, tol):
        """Newton on the free dofs; converged when max|du| <= tol max|u| (and, at the full load,
        the residual is below 1e-6 of the largest nodal load)."""
        fscale = max(np.max(np.abs(f)), 1e-300)
        for it in range(1, NEWTON_MAX_IT + 1):
            F, S, P = self._state(u)
            R = asm(_internal, self.basis, P=P) - f
            K = asm(_tangent, self.basis, A=_tangent_moduli(F, S, self.lam, self.mu))
            du = solve(*condense(K, -R, D=self.clamped))
            if not np.all(np.isfinite(du)):
                return u, False, it, None
            u = u + du
            if np.max(np.abs(du)) <= tol * max(np.max(np.abs(u)), 1e-12):
                if tol > NEWTON_TOL:  # intermediate load step: the increment test is enough
                    return u, True, it, None
                res = float(np.max(np.abs(self._residual(u, f)[self.free])))
                return u, res <= 1e-6 * fscale, it, res
        return u, False, NEWTON_MAX_IT, None


def run_case(name, out_dir, strip="slender"):
    description, loads = C.CASES[name]
    cfg = STRIPS[strip]
    h = cfg["h"]
    nonlinear = name in NONLINEAR_CASES
    table = []
    times = {}
    with C.Timer() as t_all:
        for nx, ny in cfg["meshes"]:
            with C.Timer() as t:
                s = Strip(h, nx, ny)
                fext = s.external(loads)
                u, info = s.solve_nonlinear(fext) if nonlinear else s.solve_linear(fext)
            pos, ang = s.tip(u)
            row = {"nx": nx, "ny": ny, "dofs": s.basis.N, "tip_position_m": pos, "tip_angle_rad": ang,
                   "tip_displacement_m": [pos[0] - s.L, pos[1]]}
            row.update(info)
            table.append(row)
            times[f"{nx}x{ny}"] = t.elapsed
            C.log(f"  skfem {strip} {name} {nx}x{ny} tip=({pos[0]:.9f}, {pos[1]:.9f}) angle={ang:.9f} {t.elapsed:.2f}s")
    finest = table[-1]
    mesh_change = math.dist(table[-1]["tip_position_m"], table[-2]["tip_position_m"])
    ea_eq = C.EI_NM2 * 12.0 / h**2
    values = {
        "tip_position_m": finest["tip_position_m"],
        "tip_angle_rad": finest["tip_angle_rad"],
        "tip_point": "mid-height point (L, 0) of the end face; angle: rotation of the end face chord",
        "mesh_convergence": table,
        "mesh_change_last_refinement_m": mesh_change,
        "centerline": s.centerline(u),
    }
    rod = elastica.solve(loads, extensible=True, ea=ea_eq, steps=elastica.continuation_steps(name))
    diff = math.dist(rod["tip_position_m"], finest["tip_position_m"])
    values["rod_elastica_equivalent"] = {
        "ea_n": ea_eq,
        "ei_nm2": C.EI_NM2,
        "tip_position_m": rod["tip_position_m"],
        "tip_angle_rad": rod["tip_angle_rad"],
        "tip_position_difference_m": diff,
        "tip_angle_difference_rad": abs(rod["tip_angle_rad"] - finest["tip_angle_rad"]),
    }
    if not nonlinear:
        values["linear_theory"] = _linear_theory(loads, s)
    if strip == "slender":
        if nonlinear:
            values["pass_bound"] = {
                "tip_position_abs_m": 2.0 * (diff + mesh_change),
                "basis": "2 x (|strip tip - extensible rod elastica tip with EA = 12 EI/h^2| + change of the tip "
                "over the last mesh refinement): the rod-vs-continuum model gap (shear, clamp, St Venant-Kirchhoff "
                "vs linear moment-curvature at a few % surface strain) plus discretization",
            }
        else:
            dy = abs(rod["tip_position_m"][1] - finest["tip_position_m"][1])
            dy_mesh = abs(table[-1]["tip_position_m"][1] - table[-2]["tip_position_m"][1])
            values["pass_bound"] = {
                "tip_y_abs_m": 2.0 * (dy + dy_mesh),
                "basis": "compare tip y only (a linear analysis has no axial shortening): 2 x (|strip tip y - "
                "extensible rod elastica tip y with EA = 12 EI/h^2| + change of tip y over the last mesh "
                "refinement); the gap is mostly shear deformation",
            }
    else:
        values["pass_bound"] = None
    disc = {
        "model": "2-D continuum, plane stress, nu = 0, unit out-of-plane thickness",
        "analysis": "geometrically nonlinear, total Lagrangian St Venant-Kirchhoff, Newton + load steps"
        if nonlinear else "linear elasticity",
        "element": "ElementVector(ElementQuad2) biquadratic quadrilaterals",
        "quadrature_order": INTORDER,
        "meshes_nx_ny": cfg["meshes"],
        "clamp": "u = 0 on the whole face X = 0",
        "line_load_as": "body force w(X)/h per unit reference volume (dead)",
        "tip_force_as": "uniform traction P/h on the end face (dead)",
        "tip_moment_as": "linear normal traction -M y/I on the end face (dead), I = h^3/12",
        "newton_tolerance": "max|du| <= 1e-10 max|u| at the full load (1e-5 at intermediate load steps), "
        "then residual <= 1e-6 max|f|" if nonlinear else None,
        "strip_height_m": h,
        "young_modulus_pa": 12.0 * C.EI_NM2 / h**3,
        "poisson_ratio": 0.0,
    }
    sections = [{"length_m": C.SECTION_LENGTH_M, "ea_n": ea_eq, "ei_nm2": C.EI_NM2}] * 2
    prm = C.params(loads, disc, sections=sections, rod_equivalent={"ea_n": ea_eq, "ei_nm2": C.EI_NM2},
                   strip={"kind": strip, "height_m": h, "slenderness_L_over_h": C.LENGTH_M / h})
    doc = C.document(GENERATOR, name, f"{strip} strip: {description}", prm, values,
                     extra_versions=("scikit-fem",), timing_s={"total": t_all.elapsed, "per_mesh": times})
    path = os.path.join(out_dir, f"skfem_{strip}_{name}.json")
    C.write_json(path, doc)
    return [{"case": name, "generator": f"skfem {strip} {finest['nx']}x{finest['ny']}",
             "tip": finest["tip_position_m"], "angle": finest["tip_angle_rad"], "time": t_all.elapsed, "path": path}]


def _linear_theory(loads, s):
    """Euler-Bernoulli tip deflection and the Timoshenko shear term (kappa = 5/6, G = E/2 for nu = 0).

    Shear deflection at the tip: (int_0^L s w(s) ds + P L) / (kappa G A), the shear force
    V(X) = P + int_X^L w integrated over X.
    """
    from scipy.integrate import quad

    eb = C.linear_tip_deflection(loads)
    kGA = (5.0 / 6.0) * s.mu * s.h
    L = s.L
    first_moment = quad(lambda x: x * C.line_load(loads, x)[1], 0.0, L, points=[C.GAUSS_CENTER_M],
                        epsabs=1e-16, epsrel=1e-13, limit=200)[0]
    shear = (first_moment + C.tip_force(loads)[1] * L) / kGA
    return {"euler_bernoulli_tip_deflection_m": eb, "timoshenko_shear_term_m": shear,
            "note": "shear term (int_0^L X w(X) dX + P L)/(kappa G A), kappa = 5/6, G = E/2"}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "reference"))
    ap.add_argument("--case", nargs="*", default=SKFEM_CASES)
    ap.add_argument("--strip", nargs="*", default=list(STRIPS))
    a = ap.parse_args(argv)
    os.makedirs(a.out_dir, exist_ok=True)
    for strip in a.strip:
        for name in a.case:
            for row in run_case(name, a.out_dir, strip):
                print(f"{row['case']:28s} {row['generator']:22s} tip = ({row['tip'][0]:.9f}, {row['tip'][1]:.9f}) "
                      f"angle = {row['angle']:.9f}  {row['time']:.2f} s")


if __name__ == "__main__":
    main()
