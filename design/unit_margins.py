"""Does a design hold? Each unit's snap-back load and strain against stated margins, and the
designed array under its own weight in its orientation (issue 23, part B).

- `snap_back`: the snap-back load of a snapped unit, by a direct push: from state (iii) held
  by its actuator at zero force (`SnapRecord.held`), the apex is pulled back away from the
  base by displacement control (the unit's own frame, rollers at its supports, the same
  push-through experiment as the snap, `units.push_through`); the largest pull force on
  the way back to state (i) is F_back (N) -- the issue's F_back, "the apex force that
  returns state (iii) to (i)", with the actuator glued as in the paper's test.
- `check_margins`: the one check of per-unit numbers (F_back, strain) against the
  allowable strain and the smallest snap-back load; today fed by `unit_margins` (the
  single units simulated), later by a map lookup once maps carry F_back and strain_max.
- `verify_loads`: what `inverse_design(..., material=, orientation=, max_strain=,
  min_backload=)` runs: the whole array under self-weight (`design.array_loads`), the
  interference of its parts, the margins; a failure makes the design not met, is written
  into its verification failure and warned about.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

__all__ = ["UnitMargin", "snap_back", "unit_margins", "check_margins", "verify_loads"]


@dataclass
class UnitMargin:
    """unit: 0-based index; F_back: snap-back load (N; NaN when not computed); strain: the
    largest surface strain along the snap, in the released state and under the loads
    (dimensionless); where: where that strain sits."""

    unit: int
    F_back: float
    strain: float
    where: str


def snap_back(model, held, i: int, steps: int = 20, max_distance: float = 3.0):
    """(F_back N, d at F_back m, status) of unit ``i`` (0-based) of ``model`` from its held
    state (iii) ``held`` (n_nodes, 2) m (module doc). status "ok" or why the pull did not
    bring the unit back to state (i) (then F_back is the largest force sampled, or NaN)."""
    from snapmorph.design.arrays import ARRAY_RULES, _frame, _UnitInArray
    from snapmorph.units.push_through import first_peak, push_through

    m = model.meshes[i]
    Q = np.asarray(held, float)
    P = _frame(Q, Q[m.supports[0]].copy(), Q[m.supports[1]] - Q[m.supports[0]])
    # the first force maximum (none: no snap back within max_distance h), refined by
    # displacement-controlled solves (the snap's own F_cr is read off the samples'
    # parabola, 1e-3 off): F_back is a margin a design is judged by
    rules = replace(ARRAY_RULES, peak=first_peak, refine_peak=True)
    out = push_through(_UnitInArray(model, i, P, steps, max_distance, 1e-4, towards=-1.0),
                       rules)
    status = "ok" if out.bistable else f"unit {i + 1}: the pull back: {out.status}"
    return float(out.F_cr), float(out.d_cr), status


def unit_margins(units, nodes=None, E=None, backload: bool = True) -> list:
    """[UnitMargin] of every arched unit of ``units`` simulated alone (a one-unit array, one
    per distinct geometry; the side does not matter): F_back by `snap_back` (NaN with
    ``backload`` False) and the strain of its snap. Raises ValueError when a unit does not
    snap alone."""
    from snapmorph.design.arrays import PETG_E, build_array, simulate_array

    E = PETG_E if E is None else E
    cache, out = {}, []
    for i, u in enumerate(units):
        if u.is_spacer:
            continue
        key = (u.L, u.h, u.t, u.w, u.b)
        if key not in cache:
            model = build_array([u], nodes=nodes, E=E)
            r = simulate_array([u], [True], model=model)
            if r.status != "ok":
                raise ValueError(f"unit {i + 1} alone: {r.status}")
            rec = r.snaps[0]
            F_back, status = float("nan"), "ok"
            if backload:
                F_back, _, status = snap_back(model, rec.held, 0)
                if status != "ok":
                    F_back = float("nan")
            cache[key] = (F_back, rec.strain_max, rec.strain_where)
        F_back, strain, where = cache[key]
        out.append(UnitMargin(i, F_back, strain, where))
    return out


def check_margins(margins, allowable_strain: float, min_backload: float | None) -> list:
    """[why] a unit misses its margins: strain above ``allowable_strain`` (dimensionless) or
    a snap-back load below ``min_backload`` (N; None: not checked; an F_back that could not
    be computed counts as missed). ``margins``: [UnitMargin], from `unit_margins` or a map."""
    out = []
    for m in margins:
        if m.strain > allowable_strain:
            out.append(f"unit {m.unit + 1}: strain {100 * m.strain:.2f} % ({m.where}) above the "
                       f"allowable {100 * allowable_strain:.2f} %")
        if min_backload is not None and not (m.F_back >= min_backload):
            got = "not found" if math.isnan(m.F_back) else f"{m.F_back:.4g} N"
            out.append(f"unit {m.unit + 1}: snap-back load {got} below min_backload "
                       f"{min_backload:.4g} N")
    return out


def _check_options(material, orientation, max_strain, min_backload):
    from snapmorph.design.array_loads import gravity_direction, resolve_material

    mat = resolve_material("paper" if material is None else material)
    orientation = "upright" if orientation is None else orientation
    gravity_direction(orientation)
    if max_strain is not None:
        if isinstance(max_strain, bool) or not isinstance(max_strain, (int, float, np.number)) \
                or not (0 < float(max_strain) < 1):
            raise ValueError(f"max_strain must be a strain, 0 < max_strain < 1 (0.02 is 2 %); "
                             f"got {max_strain!r}")
    if min_backload is not None:
        if isinstance(min_backload, bool) or not isinstance(min_backload, (int, float, np.number)) \
                or not (math.isfinite(min_backload) and min_backload >= 0):
            raise ValueError(f"min_backload must be a force in N, finite and >= 0; got "
                             f"{min_backload!r}")
    allowable = float(max_strain) if max_strain is not None else mat.allowable_strain
    return mat, orientation, allowable


def verify_loads(design, material=None, orientation=None, max_strain=None,
                 min_backload=None, nodes=None) -> dict | None:
    """The designed array under its own weight (``material``, default the paper's PETG, in
    ``orientation``, default "upright") and each unit's margins (``max_strain``, default the
    material's allowable strain; ``min_backload`` N). Nothing is done (None) when all four
    are None. Stores and returns ``design.load_check`` {"loaded", "margins", "allowable_strain",
    "min_backload", "interference", "failures", "message"}; any failure makes ``design.met``
    False, is added to ``design.verification_failure`` and warned (UserWarning)."""
    import warnings

    from snapmorph.design.array_loads import load_array
    from snapmorph.design.arrays import simulate_array

    if material is None and orientation is None and max_strain is None and min_backload is None:
        return None
    mat, orientation, allowable = _check_options(material, orientation, max_strain, min_backload)
    ver = design.verification or {}
    r = ver.get("result")
    if r is None:
        r = simulate_array(design.units, None, nodes=nodes)
    failures = []
    loaded = None
    if r.status != "ok":
        failures.append(f"the whole-array simulation ended {r.status!r}")
    else:
        # the simulated array's E may not be the material's: the shapes under dead loads
        # depend on load / E only, so the weight is scaled by E_model / E_material (exact
        # for the elastic model) and the loads in N are scaled back
        ratio = r.model.E / mat.E
        loaded = load_array(r.model, r.positions, g=9.81 * ratio, orientation=orientation,
                            material=mat)
        loaded.g, loaded.total_load = 9.81, loaded.total_load / ratio
        if not loaded.holds:
            failures.append(f"under its own weight ({mat.name}, {orientation}): "
                            f"{loaded.status}")
    margins = unit_margins(design.units, nodes=nodes, E=mat.E, backload=min_backload is not None)
    if loaded is not None:  # the strain under the weight counts too
        for m in margins:
            s, where = loaded.strains[m.unit]
            if s > m.strain:
                m.strain, m.where = s, f"{where}, under its weight"
    failures += check_margins(margins, allowable, min_backload)
    overlaps = list(r.interference)
    if loaded is not None:
        from snapmorph.design.interference import interference

        overlaps += interference(r.model, loaded.positions, r.state + " loaded")
    if overlaps:
        failures.append(f"{len(overlaps)} overlap(s) of parts: {overlaps[0]}")
    message = "; ".join(failures) if failures else None
    design.load_check = {"loaded": loaded, "margins": margins, "allowable_strain": allowable,
                         "min_backload": min_backload, "material": mat,
                         "orientation": orientation, "interference": overlaps,
                         "failures": failures, "message": message}
    if message:
        design.met = False
        prev = design.verification_failure
        design.verification_failure = message if not prev else f"{prev}; {message}"
        warnings.warn(f"the design does not hold: {message}", UserWarning, stacklevel=3)
    return design.load_check
