"""Shared definitions of the validation cases (geometry, stiffness, loads, JSON).

Every generator imports the cases from here so that exudyn, the elastica and
scikit-fem solve exactly the same problems. A case is a list of load entries
in the JSON schema of `validation/README.md`; the functions below turn a load
list into what each generator needs (the line load w(X), the resultant n(X),
the tip force and the tip moment).

Geometry: clamped cantilever, base at the origin, initially straight along +x,
loads in -y. Paper properties (two 0.12 m sections, EI = 0.025 N m^2,
EA = 300 N).
"""

import json
import math
import platform
import sys
import time
from importlib import metadata

import numpy as np

LENGTH_M = 0.24
SECTION_LENGTH_M = 0.12
EA_N = 300.0
EI_NM2 = 0.025
GRAVITY = 9.81
GAUSS_CENTER_M = 0.16
GAUSS_WIDTH_M = 0.01

SECTIONS = [
    {"length_m": SECTION_LENGTH_M, "ea_n": EA_N, "ei_nm2": EI_NM2},
    {"length_m": SECTION_LENGTH_M, "ea_n": EA_N, "ei_nm2": EI_NM2},
]

UNITS = {"position": "m", "force": "N", "moment": "N m", "angle": "rad", "distributed": "N/m"}


def _uniform(q):
    return {"type": "distributed", "profile": "uniform", "w_n_per_m": [0.0, -q]}


def _linear(q_end):
    return {"type": "distributed", "profile": "linear", "w_start_n_per_m": [0.0, 0.0], "w_end_n_per_m": [0.0, -q_end]}


def _gaussian(a):
    return {
        "type": "distributed",
        "profile": "gaussian",
        "amplitude_n_per_m": [0.0, -a],
        "center_m": GAUSS_CENTER_M,
        "width_m": GAUSS_WIDTH_M,
    }


def _tip_force(p):
    return {"type": "tip_force", "force_n": [0.0, -p]}


def _tip_moment(m):
    return {"type": "tip_moment", "moment_nm": m}


def _self_weight(m):
    return {"type": "self_weight", "mass_per_length_kg_per_m": m, "gravity_m_per_s2": [0.0, -GRAVITY]}


# name -> (description, loads). "small": tip deflection about 0.3-0.6 % of L
# (linear range); "large": tip rotation of 60 degrees or more.
CASES = {
    "uniform_small": ("Uniform line load q = 0.05 N/m in -y (linear range).", [_uniform(0.05)]),
    "uniform_large": ("Uniform line load q = 20 N/m in -y (large deflection).", [_uniform(20.0)]),
    "linear_small": (
        "Line load growing linearly from 0 at the base to 0.1 N/m (in -y) at the tip (linear range).",
        [_linear(0.1)],
    ),
    "linear_large": (
        "Line load growing linearly from 0 at the base to 30 N/m (in -y) at the tip (large deflection).",
        [_linear(30.0)],
    ),
    "gaussian_small": (
        "Gaussian bump line load, peak 0.5 N/m in -y at X = 0.16 m, width 0.01 m (a contact; linear range).",
        [_gaussian(0.5)],
    ),
    "gaussian_large": (
        "Gaussian bump line load, peak 180 N/m in -y at X = 0.16 m, width 0.01 m (a contact; large deflection).",
        [_gaussian(180.0)],
    ),
    "tip_force_small": ("Dead tip force 0.005 N in -y (linear range).", [_tip_force(0.005)]),
    "tip_force_large": ("Dead tip force 2 N in -y (large deflection).", [_tip_force(2.0)]),
    "tip_moment_small": ("Tip moment -0.001 N m (clockwise, bends toward -y; linear range).", [_tip_moment(-0.001)]),
    "tip_moment_large": (
        "Tip moment -0.2 N m (clockwise; the exact inextensible shape is a circular arc of angle 1.92 rad).",
        [_tip_moment(-0.2)],
    ),
    "self_weight_moment_small": (
        "Self-weight 0.005 kg/m under g = 9.81 m/s^2 plus tip moment -0.0005 N m (linear range).",
        [_self_weight(0.005), _tip_moment(-0.0005)],
    ),
    "self_weight_moment_large": (
        "Self-weight 0.5 kg/m under g = 9.81 m/s^2 plus a tip moment +0.2 N m that lifts the rod against gravity.",
        [_self_weight(0.5), _tip_moment(0.2)],
    ),
}

# What `make_references.py --only cheap` runs (CI): one cheap exudyn case and
# one cheap scikit-fem case.
CHEAP = {"exudyn": ["tip_force_large"], "skfem": ["tip_force_small"]}


# ---------------------------------------------------------------------------
# Load algebra shared by the generators
# ---------------------------------------------------------------------------

def line_load(loads, X):
    """Dead line load w(X) = (wx, wy) in N/m (distributed entries and self-weight)."""
    wx = 0.0 * X
    wy = 0.0 * X
    for ld in loads:
        if ld["type"] == "distributed":
            p = ld["profile"]
            if p == "uniform":
                wx = wx + ld["w_n_per_m"][0]
                wy = wy + ld["w_n_per_m"][1]
            elif p == "linear":
                a, b = ld["w_start_n_per_m"], ld["w_end_n_per_m"]
                s = X / LENGTH_M
                wx = wx + a[0] + (b[0] - a[0]) * s
                wy = wy + a[1] + (b[1] - a[1]) * s
            elif p == "gaussian":
                g = np.exp(-((X - ld["center_m"]) ** 2) / (2.0 * ld["width_m"] ** 2))
                wx = wx + ld["amplitude_n_per_m"][0] * g
                wy = wy + ld["amplitude_n_per_m"][1] * g
            else:
                raise ValueError(f"unknown profile {p}")
        elif ld["type"] == "self_weight":
            m = ld["mass_per_length_kg_per_m"]
            wx = wx + m * ld["gravity_m_per_s2"][0]
            wy = wy + m * ld["gravity_m_per_s2"][1]
    return wx, wy


def resultant_function(loads):
    """Return X -> (Rx, Ry), the integral of the line load from X to the tip (N).

    Closed forms: uniform q (L - X); linear a + (b - a) s/L gives
    a (L - X) + (b - a)(L^2 - X^2)/(2L); Gaussian A exp(-(s-c)^2/(2 sigma^2))
    gives A sigma sqrt(pi/2) [erf((L-c)/(sqrt2 sigma)) - erf((X-c)/(sqrt2 sigma))].
    """
    L = LENGTH_M
    const = [0.0, 0.0]  # coefficient of (L - X)
    quad_ = [0.0, 0.0]  # coefficient of (L^2 - X^2)/(2L)
    gauss = []  # (Ax, Ay, c, sigma)
    for ld in loads:
        if ld["type"] == "distributed":
            p = ld["profile"]
            if p == "uniform":
                for i in range(2):
                    const[i] += ld["w_n_per_m"][i]
            elif p == "linear":
                a, b = ld["w_start_n_per_m"], ld["w_end_n_per_m"]
                for i in range(2):
                    const[i] += a[i]
                    quad_[i] += b[i] - a[i]
            elif p == "gaussian":
                gauss.append((*ld["amplitude_n_per_m"], ld["center_m"], ld["width_m"]))
            else:
                raise ValueError(f"unknown profile {p}")
        elif ld["type"] == "self_weight":
            for i in range(2):
                const[i] += ld["mass_per_length_kg_per_m"] * ld["gravity_m_per_s2"][i]
    r2 = math.sqrt(2.0)

    def resultant(X):
        f = L - X
        g = (L * L - X * X) / (2.0 * L)
        rx = const[0] * f + quad_[0] * g
        ry = const[1] * f + quad_[1] * g
        for ax, ay, c, s in gauss:
            h = s * math.sqrt(math.pi / 2.0) * (math.erf((L - c) / (r2 * s)) - math.erf((X - c) / (r2 * s)))
            rx += ax * h
            ry += ay * h
        return rx, ry

    return resultant


def tip_force(loads):
    fx = sum(ld["force_n"][0] for ld in loads if ld["type"] == "tip_force")
    fy = sum(ld["force_n"][1] for ld in loads if ld["type"] == "tip_force")
    return fx, fy


def tip_moment(loads):
    return sum(ld["moment_nm"] for ld in loads if ld["type"] == "tip_moment")


def self_weight(loads):
    """(mass per length, gravity) of the self-weight entry, or None."""
    for ld in loads:
        if ld["type"] == "self_weight":
            return ld["mass_per_length_kg_per_m"], ld["gravity_m_per_s2"]
    return None


def linear_tip_deflection(loads, ei=EI_NM2, L=LENGTH_M):
    """Euler-Bernoulli small-deflection tip displacement in y (textbook formulas).

    uniform q: q L^4/(8 EI); linear 0 -> q at tip: 11 q L^4/(120 EI);
    tip force P: P L^3/(3 EI); tip moment M: M L^2/(2 EI); gaussian bump:
    superposition of point loads, int w(a) a^2 (3L - a)/(6 EI) da (numerical).
    """
    v = 0.0
    for ld in loads:
        if ld["type"] == "distributed" and ld["profile"] == "uniform":
            v += ld["w_n_per_m"][1] * L**4 / (8 * ei)
        elif ld["type"] == "distributed" and ld["profile"] == "linear":
            a, b = ld["w_start_n_per_m"][1], ld["w_end_n_per_m"][1]
            v += a * L**4 / (8 * ei) + (b - a) * 11 * L**4 / (120 * ei)
        elif ld["type"] == "distributed" and ld["profile"] == "gaussian":
            from scipy.integrate import quad

            amp, c, s = ld["amplitude_n_per_m"][1], ld["center_m"], ld["width_m"]
            f = lambda a: amp * math.exp(-((a - c) ** 2) / (2 * s * s)) * a * a * (3 * L - a) / (6 * ei)
            v += quad(f, 0.0, L, points=[c], epsabs=1e-16, epsrel=1e-13, limit=200)[0]
        elif ld["type"] == "tip_force":
            v += ld["force_n"][1] * L**3 / (3 * ei)
        elif ld["type"] == "tip_moment":
            v += ld["moment_nm"] * L**2 / (2 * ei)
        elif ld["type"] == "self_weight":
            v += ld["mass_per_length_kg_per_m"] * ld["gravity_m_per_s2"][1] * L**4 / (8 * ei)
    return v


# ---------------------------------------------------------------------------
# JSON output
# ---------------------------------------------------------------------------

def versions(extra=()):
    out = {"python": platform.python_version()}
    for pkg in ("numpy", "scipy", *extra):
        try:
            out[pkg] = metadata.version(pkg)
        except metadata.PackageNotFoundError:
            out[pkg] = None
    return out


def params(loads, discretization, sections=None, length_m=LENGTH_M, **extra):
    p = {
        "length_m": length_m,
        "sections": sections if sections is not None else SECTIONS,
        "base": {"position_m": [0.0, 0.0], "angle_rad": 0.0},
        "loads": loads,
        "discretization": discretization,
    }
    p.update(extra)
    return p


def document(generator, case, description, params_, values, extra_versions=(), timing_s=None):
    doc = {
        "generator": generator,
        "versions": versions(extra_versions),
        "case": case,
        "description": description,
        "params": params_,
        "units": UNITS,
        "values": values,
    }
    if timing_s is not None:
        doc["timing_s"] = timing_s
    return doc


def write_json(path, doc):
    with open(path, "w") as f:
        json.dump(_clean(doc), f, indent=1, allow_nan=False)
        f.write("\n")


def _clean(o):
    """Turn numpy scalars/arrays into plain Python for json (floats keep repr precision);
    a non-finite float (a diverged run) becomes null."""
    if isinstance(o, dict):
        return {k: _clean(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_clean(v) for v in o]
    if isinstance(o, np.ndarray):
        return _clean(o.tolist())
    if isinstance(o, np.bool_):
        return bool(o)
    if isinstance(o, np.integer):
        return int(o)
    if isinstance(o, np.floating):
        o = float(o)
    if isinstance(o, float) and not math.isfinite(o):
        return None
    return o


class Timer:
    def __enter__(self):
        self.t0 = time.perf_counter()
        return self

    def __exit__(self, *a):
        self.elapsed = time.perf_counter() - self.t0


def log(*a):
    print(*a, file=sys.stderr, flush=True)
