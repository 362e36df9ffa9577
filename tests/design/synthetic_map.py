"""A small schema-conformant design map made of smooth synthetic functions, for tests.

θ rises linearly with h/L from the bistability boundary (h/L = 0.09: monostable below) and
weakly with t/L and w/L; the snapped base is a circular arc of turning θ and length
1 - 0.2 (h/L)² (per unit length), so S/L is its chord. The released state (schema 2) is the
same as the actuated one here (every bistable point self-standing), θ_end = θ / 2. The file
follows docs/design-map-schema.md and loads through `maps.DesignMap`.
"""

from __future__ import annotations

import math

import numpy as np

H = np.round(np.arange(0.05, 0.5001, 0.025), 6)
T = np.array([0.0025, 0.005, 0.0075, 0.01, 0.0125])
W = np.array([0.02, 0.04, 0.06, 0.08, 0.10])
M = 65
H_BISTABLE = 0.09


def theta_deg(h, t, w):
    """Synthetic θ (degrees) of the snapped unit."""
    return 180.0 * (h - 0.07) * (1.0 + 3.0 * (t - 0.005)) * (1.0 + 0.5 * (w - 0.05))


def arc_shape(theta, length, m=M):
    """Circular arc from (0, 0) heading +x, turning θ (degrees) left, (m, 2)."""
    s = np.linspace(0.0, length, m)
    k = math.radians(theta) / length
    return np.stack([np.sin(k * s) / k, (1 - np.cos(k * s)) / k], axis=-1)


def base_length(h):
    return 1.0 - 0.2 * h * h


def make_dataset():
    import xarray as xr

    shape3 = (H.size, T.size, W.size)
    theta = np.full(shape3, np.nan)
    S = np.full(shape3, np.nan)
    base = np.full(shape3 + (M, 2), np.nan)
    status = np.ones(shape3, dtype="i1")
    for i, h in enumerate(H):
        for j, t in enumerate(T):
            for k, w in enumerate(W):
                if h < H_BISTABLE:
                    continue
                th = theta_deg(h, t, w)
                xy = arc_shape(th, base_length(h))
                theta[i, j, k], S[i, j, k] = th, xy[-1, 0] / math.cos(math.radians(th) / 2)
                base[i, j, k] = xy
                status[i, j, k] = 0
    hh, tt, ww = np.meshgrid(H, T, W, indexing="ij")
    F = 50.0 * hh * (1 + 10 * tt) * (1 + ww)
    dims = ("h_over_L", "t_over_L", "w_over_L")
    ds = xr.Dataset(
        {
            "F_cr": (dims, F, {"units": "1", "long_name": "critical force F_cr L^2 / (E I_arch)"}),
            "d_cr": (dims, 0.5 * hh, {"units": "1", "long_name": "d_cr / L"}),
            "d_unstable": (dims, np.where(status == 0, hh, np.nan), {"units": "1", "long_name": "d_unstable / L"}),
            "d_second": (dims, np.where(status == 0, 2 * hh, np.nan), {"units": "1", "long_name": "d_second / L"}),
            "S": (dims, S, {"units": "1", "long_name": "S / L"}),
            "theta": (dims, theta, {"units": "degree", "long_name": "signed angle between base end tangents"}),
            "energy_barrier": (dims, np.where(status == 0, hh * hh, np.nan), {"units": "1", "long_name": "energy barrier"}),
            "energy_stored": (dims, np.where(status == 0, 0.5 * hh * hh, np.nan), {"units": "1", "long_name": "energy stored"}),
            "bistable": (dims, (status == 0).astype("i1"), {"units": "1", "long_name": "bistable"}),
            "self_standing": (dims, np.where(status == 0, 1, -1).astype("i1"), {"units": "1", "long_name": "self standing"}),
            "theta_end": (dims, theta / 2, {"units": "degree", "long_name": "end angle, theta / 2"}),
            "S_released": (dims, S, {"units": "1", "long_name": "S / L released"}),
            "theta_released": (dims, theta, {"units": "degree", "long_name": "theta released"}),
            "theta_end_released": (dims, theta / 2, {"units": "degree", "long_name": "theta_end released"}),
            "base_shape_released": (dims + ("sample", "xz"), base, {"units": "1", "long_name": "released base / L"}),
            "bifurcation": (dims, np.full(shape3, -1, dtype="i1"), {"units": "1", "long_name": "bifurcation"}),
            "status": (dims, status, {"units": "1", "long_name": "status",
                                      "flag_values": np.array([-1, 0, 1, 2, 3, 4, 5], dtype="i1"),
                                      "flag_meanings": "pending ok monostable not_converged invalid_geometry "
                                                       "timeout second_state_unstable"}),
            "base_shape": (dims + ("sample", "xz"), base, {"units": "1", "long_name": "base centreline in state (iii) / L"}),
            "solve_time": (dims, np.zeros(shape3), {"units": "s", "long_name": "solve time"}),
        },
        coords={"h_over_L": H, "t_over_L": T, "w_over_L": W, "sample": np.arange(M),
                "xz": np.array(["x", "z"])},
        attrs={"schema_version": 2, "b_over_L": 0.0, "resolution": 0, "package_version": "test",
               "git_commit": "synthetic", "created": "2026-01-01T00:00:00Z",
               "normalisation": "F_norm = F L^2 / (E I_arch), I_arch = w t^3 / 12",
               "E_reference": 2.2e9, "title": "synthetic design map for design/ tests"},
    )
    for name in ("status", "bistable", "self_standing", "bifurcation"):
        ds[name].encoding["_FillValue"] = None
    return ds


def write(path):
    make_dataset().to_netcdf(path)
    return path
