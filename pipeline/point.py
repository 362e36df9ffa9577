"""Solve one grid point with the unit solver and normalise the result per the map schema.

A point solver has the signature
    solve(h_over_L, t_over_L, w_over_L, b_over_L, resolution, samples) -> record (dict)
with the keys of `empty_record`. `solve_point` is the real one (it calls `snapmorph.units.planar`); tests
inject fakes. `finalise_record` enforces the schema's rules on any solver's output, so that one
odd point can never break a build.
"""

from __future__ import annotations

import math

import numpy as np

from snapmorph.pipeline.schema import (
    BISTABLE_ONLY, DEFAULT_SAMPLES, FAILED, FLAG_VARS, FLOAT_VARS, MONOSTABLE, NOT_BISTABLE,
    INVALID_GEOMETRY, NOT_CONVERGED, OK, OPTIONAL_VARS, RELEASED_VARS, SHAPE_VARS, STATUS_CODES,
)

#: reference base length (m) and Young's modulus (Pa) used to build the SI geometry; the
#: normalised outputs do not depend on them
L_REF = 0.1
E_REF = 2.2e9
#: the actuator joint of the maps, over L: the paper's 1/8 in stem at its L = 100 mm
JOINT_LENGTH_OVER_L = 0.03175
#: the maps bond the whole flat part b + w of each end (`UnitGeometry.bond_length` = None)
BOND_LENGTH = "b+w"


def _joint_length(L: float) -> float:
    """The maps' joint (m) for base length L: exactly `UnitGeometry`'s default 1/8 in at the
    reference L = 0.1 m (so that a map point and a default `simulate_unit` are identical)."""
    from snapmorph.units.geometry import JOINT_LENGTH_DEFAULT

    return JOINT_LENGTH_DEFAULT if L == L_REF else JOINT_LENGTH_OVER_L * L


def model_options() -> dict:
    """The unit-model options a map is built with (recorded as global attributes, and part of
    a build's fingerprint)."""
    return {"joint_length_over_L": JOINT_LENGTH_OVER_L, "bond_length_over_L": BOND_LENGTH}


def empty_record(samples: int = DEFAULT_SAMPLES, status: int = NOT_CONVERGED, message: str = "") -> dict:
    """A record with every field absent: NaN floats, flags 0/-1, NaN base shape."""
    rec = {name: math.nan for name in FLOAT_VARS}
    rec.update({"bistable": 0, "self_standing": -1, "bifurcation": -1})
    rec["status"] = status
    for name in SHAPE_VARS:
        rec[name] = np.full((samples, 2), np.nan)
    rec["message"] = message
    return rec


def resample_shape(xz, samples: int) -> np.ndarray:
    """Resample a polyline (m, 2) to `samples` points uniform in arc length, translated to start
    at (0, 0) and rotated so that its start tangent (first segment) points along +x."""
    xz = np.asarray(xz, dtype=float)
    if xz.ndim != 2 or xz.shape[1] != 2 or xz.shape[0] < 2:
        raise ValueError(f"base shape must be an (m >= 2, 2) array, got shape {xz.shape}")
    if not np.all(np.isfinite(xz)):
        raise ValueError("base shape holds non-finite values")
    seg = np.diff(xz, axis=0)
    ds = np.hypot(seg[:, 0], seg[:, 1])
    if not np.any(ds > 0):
        raise ValueError("base shape has zero length")
    s = np.concatenate([[0.0], np.cumsum(ds)])
    su = np.linspace(0.0, s[-1], samples)
    pts = np.column_stack([np.interp(su, s, xz[:, 0]), np.interp(su, s, xz[:, 1])]) - xz[0]
    tx, tz = seg[np.argmax(ds > 0)]
    c, sn = tx / math.hypot(tx, tz), tz / math.hypot(tx, tz)
    rot = np.array([[c, sn], [-sn, c]])  # rotation by -angle of the start tangent
    out = pts @ rot.T
    out[0] = 0.0
    return out


def _flag(value) -> int:
    if value is None:
        return -1
    return 1 if bool(value) else 0


def normalise_result(r, samples: int = DEFAULT_SAMPLES) -> dict:
    """Turn a `snapmorph.units.UnitResult` (SI) into a schema record (dimensionless)."""
    g = r.geometry
    L = g.L
    EI = g.E * g.w * g.t**3 / 12.0  # E I_arch (N m^2)
    f_scale = L**2 / EI
    u_scale = L / EI
    status = int(r.status_code)
    if status not in STATUS_CODES or status < 0:
        return empty_record(samples, NOT_CONVERGED, f"solver returned unknown status_code {status}")
    rec = empty_record(samples, status, str(getattr(r, "status", "")))
    if status in FAILED:
        return rec
    rec["F_cr"] = float(r.F_cr) * f_scale
    rec["d_cr"] = float(r.d_cr) / L
    rec["bifurcation"] = _flag(r.bifurcation)
    if status in NOT_BISTABLE:
        return rec
    rec["bistable"] = 1 if r.bistable else 0
    rec["self_standing"] = _flag(r.self_standing)
    rec["d_unstable"] = float(r.d_unstable) / L
    rec["d_second"] = float(r.d_second) / L
    rec["S"] = float(r.S) / L
    rec["theta"] = float(r.theta_deg)
    rec["theta_end"] = float(getattr(r, "theta_end_deg", math.nan))
    rec["energy_barrier"] = float(r.energy_barrier) * u_scale
    rec["energy_stored"] = float(r.energy_stored) * u_scale
    rec["base_shape"] = resample_shape(np.asarray(r.base_shape, dtype=float) / L, samples)
    rel = getattr(r, "released", None) or {}
    if rec["self_standing"] == 1 and "base_shape" in rel:
        rec["S_released"] = float(rel["S"]) / L
        rec["theta_released"] = float(rel["theta_deg"])
        rec["theta_end_released"] = float(rel.get("theta_end_deg", math.nan))
        rec["base_shape_released"] = resample_shape(np.asarray(rel["base_shape"], float) / L, samples)
    return rec


def unit_model():
    """The planar unit model (`snapmorph.units.planar`: UnitGeometry, simulate_unit,
    DEFAULT_NODES), looked up in ``sys.modules`` at call time so that tests can stand in."""
    import importlib

    return importlib.import_module("snapmorph.units.planar")


def solve_point(h_over_L, t_over_L, w_over_L, b_over_L=0.0, resolution=None,
                samples: int = DEFAULT_SAMPLES, time_limit=None) -> dict:
    """Simulate one unit (L = 0.1 m, E = 2.2 GPa, the maps' joint and bond) and return its
    dimensionless schema record.

    ``time_limit``: wall time (s) for the point (None: none); past it the point gets status 4
    (timeout). Never raises: a geometry ValueError gives status 3 (invalid_geometry), any other
    exception or a failed solve gives status 2 (not_converged) with NaN fields; `message` says
    why.
    """
    try:
        model = unit_model()
        UnitGeometry, simulate_unit = model.UnitGeometry, model.simulate_unit
    except Exception as exc:  # the solver itself is broken: record, do not stop
        return empty_record(samples, NOT_CONVERGED, f"cannot import the unit model: {exc!r}")
    L = L_REF
    try:
        g = UnitGeometry(L=L, h=h_over_L * L, t=t_over_L * L, w=w_over_L * L, b=b_over_L * L,
                         E=E_REF, joint_length=_joint_length(L))
    except ValueError as exc:
        return empty_record(samples, INVALID_GEOMETRY, f"invalid geometry: {exc}")
    except Exception as exc:
        return empty_record(samples, NOT_CONVERGED, f"geometry failed: {exc!r}")
    try:
        if time_limit is None:
            r = simulate_unit(g, nodes=resolution)
        else:
            r = simulate_unit(g, nodes=resolution, time_limit=time_limit)
        return finalise_record(normalise_result(r, samples), samples)
    except Exception as exc:
        return empty_record(samples, NOT_CONVERGED, f"solver raised {exc!r}")


def default_resolution():
    """The solver's converged default resolution (`snapmorph.units.planar.DEFAULT_NODES`), or None if the
    solver does not say (or cannot be imported)."""
    try:
        unit = unit_model()
    except Exception:
        return None
    n = getattr(unit, "DEFAULT_NODES", None)
    return int(n) if isinstance(n, (int, np.integer)) and not isinstance(n, bool) else None


def warm_up(resolution=None) -> float:
    """Compile (or load from the numba cache) the solver kernels by solving one small point.

    Returns the time taken (s). Raises if the solver cannot run at all, so that a broken solver
    stops a build before it records thousands of failures.
    """
    import time

    unit = unit_model()
    t0 = time.perf_counter()
    hook = getattr(unit, "warm_up", None)
    if callable(hook):
        hook()
    else:
        g = unit.UnitGeometry(L=L_REF, h=0.02, t=0.5e-3, w=5e-3, b=0.0, E=E_REF)
        unit.simulate_unit(g, nodes=resolution)
    return time.perf_counter() - t0


def finalise_record(rec, samples: int = DEFAULT_SAMPLES) -> dict:
    """Check and clean any solver's record so it obeys the schema.

    Missing keys or wrong types turn the point into status 2 (the schema-2 additions,
    `OPTIONAL_VARS` and base_shape_released, may be left out: they are then NaN); fields that
    do not exist for the point's status are set to NaN; an "ok" record with non-finite fields
    becomes status 2; released-state fields exist exactly where self_standing = 1.
    """
    if not isinstance(rec, dict):
        return empty_record(samples, NOT_CONVERGED, f"solver returned {type(rec).__name__}, not dict")
    try:
        status = int(rec["status"])
        if status not in STATUS_CODES or status < 0:
            raise ValueError(f"unknown status {status}")
        out = empty_record(samples, status, str(rec.get("message", "")))
        if status in FAILED:
            return out
        for name in FLOAT_VARS:
            if name in OPTIONAL_VARS and name not in rec:
                continue
            out[name] = float(rec[name])
        for name in FLAG_VARS:
            v = int(rec[name])
            if v not in (-1, 0, 1):
                raise ValueError(f"flag {name} = {v} is not -1, 0 or 1")
            out[name] = v
        for name in SHAPE_VARS:
            if name == "base_shape_released" and name not in rec:
                continue
            shape = np.asarray(rec[name], dtype=float)
            if shape.shape != (samples, 2):
                raise ValueError(f"{name} has shape {shape.shape}, expected ({samples}, 2)")
            out[name] = shape.copy()
    except Exception as exc:
        return empty_record(samples, NOT_CONVERGED, f"malformed solver record: {exc!r}")
    if status in NOT_BISTABLE:
        for name in (*BISTABLE_ONLY, *RELEASED_VARS):
            out[name] = math.nan
        for name in SHAPE_VARS:
            out[name][:] = np.nan
        out["bistable"] = 0
        out["self_standing"] = -1
        return out
    # status OK: everything must be present; the released state exactly where self-standing
    if out["self_standing"] != 1:
        for name in RELEASED_VARS:
            out[name] = math.nan
        out["base_shape_released"][:] = np.nan
    required = [n for n in FLOAT_VARS if n not in OPTIONAL_VARS]
    if out["self_standing"] == 1 and any(n in rec for n in RELEASED_VARS):
        required += [n for n in RELEASED_VARS]
    missing = [n for n in required if not math.isfinite(out[n])]
    if not np.all(np.isfinite(out["base_shape"])):
        missing.append("base_shape")
    if "S_released" in required and not np.all(np.isfinite(out["base_shape_released"])):
        missing.append("base_shape_released")
    if out["bistable"] != 1:
        missing.append("bistable")
    if missing:
        return empty_record(samples, NOT_CONVERGED, f"status ok but missing/invalid: {', '.join(missing)}")
    assert status == OK
    return out
