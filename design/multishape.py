"""One array, several shapes: inverse design for a set of targets, each reached by a snap
pattern (issue 24).

    from snapmorph.design import inverse_design_multi
    md = inverse_design_multi(["C.svg", "S.svg"], t=0.5e-3, w=5e-3, tol=0.02, verify=True)
    md.units, md.patterns, md.deviations, md.met, md.verification, md.write("build/CS")

What is designed
----------------
One array (its units' sides, lengths L and heights h, and its spacers) and one snap pattern per
target, chosen together so that forward kinematics through the design map puts the array
within `tol` × length of every target (best rigid placement per target by default: each
shape is held on its own). The base is inextensible: every state has the array's one length
Λ = Σ L, and unit i covers the same stretch [S_i, S_i+1] of the base in every state. In the
stretch of a unit, each target must therefore either stay straight (the unit unsnapped) or
turn by that unit's one snapped turning side · θ_i (snapped). Targets of different lengths
cannot all be met (refused, `_check_lengths`).

Method: a discrete layout, continuous least squares, and an exact pattern search, alternated
----------------------------------------------------------------------------------------------
1. **Layout by error diffusion over slots** (`_slot_layout`). The common arc length is cut into
   N equal slots; slot j asks target k to turn D_kj (its tangent's change over the slot).
   Walking the slots, each target carries the turning still owed (r_k, the error carried
   forward, as in error-diffusion dithering). In slot j the unit is chosen among a spacer and,
   for each side σ = ±1 and each subset A of the targets owed turning of that sign, a unit of
   side σ snapped exactly in the targets of A turning τ = mean of what they owe (clipped to the
   map's θ range): the choice that leaves the smallest Σ r_k². Mirror images interleave left
   and right units, straight-plus-curved pieces get units snapped only where each target
   curves, a common curve one unit snapped in every target. That is 1 + 2 (2^K − 1) choices per
   slot, O(N 2^K K).
2. **Least squares over everything continuous at once** (`multishape_fit._JointFit`): every unit's (L, h/L),
   every spacer's L and one placement per target, the residuals being the arc-length-matched
   distances of all K predicted states to their targets (160 pairs each), through the map's
   vectorised interpolants (`design.inverse._FastModel`, the same numbers as
   `design.kinematics.chain`); Jacobians by forward differences, one map lookup for all
   perturbed units; then Lawson re-weightings towards the largest distance of any target.
3. **Exact pattern re-selection** (`design.nearest.branch_and_bound`): for the fitted units,
   each target's pattern is searched over all 2ⁿ states by branch and bound in that target's
   fitted frame; if a better pattern exists, the fit (2) is repeated with it (at most
   `multishape_fit.PATTERN_ROUNDS` times). So the patterns are not fixed by the layout's guess.
4. **Number of units**: N runs from the fewest slots that can hold the turning
   (ceil(Φ⁺/θ_max) + ceil(Φ⁻/θ_max) for the target that needs most) upwards,
   each N with units filling their slot and with units of 60 % of it between spacers; after a
   miss by d > tol the next N is about N sqrt(d / tol) (polygon-like errors fall as 1/N²),
   never more than N + 4, never beyond Λ / L_min slots or `max_units`. It stops at the first
   design meeting tol on every target; otherwise it returns the best one (smallest worst
   deviation), `met` False for the targets it misses, and a warning.

Cost: per N, one least squares of p = 2 n_arched + n_spacers + 3K unknowns and 320 K
residuals (a Jacobian is one map lookup of p shapes and K (p + 1) placed chains, about 10 ms
for n = 12), a few Lawson rounds, and K branch-and-bound searches (milliseconds for designed
arrays: the stretches tell the states apart). A two-target design of about 12 units takes a
few seconds (`bench/bench_multishape.py`).

Verification (`verify_multi`, `verify=True`): the whole array simulated in each pattern
(`design.arrays.simulate_array` on one mesh, the pattern's units snapped in order, actuators
off; 81 nodes per unit, coarser if that simulation fails, see `VERIFY_NODES`), its base
measured against its target both ways.
"""

from __future__ import annotations

import dataclasses
import math
import time
import warnings
from dataclasses import dataclass, field

import numpy as np

# Private helpers of the single-target design, used as they are (one mechanism for each job):
# the map seen in one state, the fabrication limits, h/L for a turning and the argument checks.
from snapmorph.design.curve_fit import Limits, fabrication_limits, hL_for_turn
from snapmorph.design.inverse import check_choice, check_fraction, check_positive
from snapmorph.design.map_model import StateMap, map_state_kw
from snapmorph.design.multishape_fit import _fit_layout, _JointFit
from snapmorph.design.nearest import measure
from snapmorph.design.targets import Target, place_rigid
from snapmorph.design.units import Unit
from snapmorph.design.verification import verification_failure

__all__ = ["MultiDesign", "inverse_design_multi", "verify_multi"]

PLACEMENTS = ("best", "clamped")
STATES = ("released", "actuated")
#: the units' share of their slot in the two layouts tried per N
SHARES = (1.0, 0.6)
#: the shortest spacer (m) of a multi-shape design (`inverse_design` allows 1 mm): the
#: whole-array mesh gives a spacer as many nodes as a unit, and a 1 mm spacer's micrometre
#: edges stall the simulation's Newton iterations (step size underflow); 3 mm and more do not
SPACER_MIN = 5e-3


# =============================================================================================
# The result
# =============================================================================================
@dataclass
class MultiDesign:
    """An array and one snap pattern per target (SI; deviations as fractions of each target's
    length, placements (x0, y0, angle) m, m, rad of unit 1's start in the target's frame).

    patterns[k]: one bool per unit, True = snapped, for target k; deviations[k]: {"best":
    (max, rms), "clamped": (max, rms)} of the map's prediction; met[k]: deviation with
    `placement_mode` <= tol; verification[k] (after `verify_multi`): the whole array simulated
    in pattern k ({"status", "time", "xy", "deviations", "max_deviation", "failure", ...});
    a target whose verification fails (`verification.verification_failure`) is not met."""

    units: list
    patterns: tuple
    targets: list
    names: tuple
    predicted: list
    deviations: list
    placements: list
    placement_mode: str
    tol: float
    met: tuple
    t: float
    w: float
    state: str = "released"
    limits: Limits | None = None
    verification: list | None = None
    history: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    time: float = 0.0

    # --- views ------------------------------------------------------------------------------
    @property
    def target_lengths(self) -> tuple:
        return tuple(t.length for t in self.targets)

    @property
    def array_length(self) -> float:
        return float(sum(u.L for u in self.units))

    @property
    def states(self) -> tuple:
        """The patterns as '0'/'1' strings (character i: unit i + 1 snapped)."""
        return tuple("".join("1" if p else "0" for p in pat) for pat in self.patterns)

    @property
    def max_deviations(self) -> tuple:
        """Each target's predicted max deviation with `placement_mode`."""
        return tuple(d[self.placement_mode][0] for d in self.deviations)

    @property
    def simulated_deviations(self) -> tuple | None:
        """Each target's simulated max deviation with `placement_mode` (None until verified)."""
        if self.verification is None:
            return None
        return tuple(v["deviations"][self.placement_mode][0] for v in self.verification)

    @property
    def met_all(self) -> bool:
        return all(self.met)

    @property
    def failures(self) -> tuple:
        """Per target: why its whole-array verification failed, or None (passed, not run)."""
        if self.verification is None:
            return (None,) * len(self.targets)
        return tuple(v.get("failure") for v in self.verification)

    def __repr__(self):
        n = sum(not u.is_spacer for u in self.units)
        devs = ", ".join(f"{100 * d:.3g} %" for d in self.max_deviations)
        return (f"MultiDesign({n} arched units + {len(self.units) - n} spacers, "
                f"{len(self.targets)} targets, {self.array_length * 1e3:.1f} mm, max deviations "
                f"{devs} ({self.placement_mode}), tol {100 * self.tol:.3g} % "
                f"{'met' if self.met_all else 'MISSED'})")

    def table(self) -> str:
        """The units (mm, degrees) and, per target, whether each is snapped (1) or not (0)."""
        head = f"{'unit':>4} {'L_mm':>7} {'h_mm':>6} {'h/L':>6} {'side':>4} {'theta_deg':>9} "
        head += " ".join(f"{'T' + str(k + 1):>3}" for k in range(len(self.patterns)))
        lines = [head]
        turns = self._turns()
        for i, u in enumerate(self.units):
            hl = f"{u.h / u.L:6.3f}" if u.h > 0 else "     -"
            side = f"{u.side:+d}" if u.side else "0"
            th = f"{turns[i]:9.2f}" if not u.is_spacer else "        -"
            flags = " ".join(f"{'1' if p[i] else '0':>3}" for p in self.patterns)
            lines.append(f"{i + 1:>4} {u.L * 1e3:7.1f} {u.h * 1e3:6.1f} {hl} {side:>4} {th} "
                         f"{flags}")
        return "\n".join(lines)

    def _turns(self):
        from snapmorph.design.kinematics import chain
        from snapmorph.design.lookup import MapLookup

        if not hasattr(self, "_turn_cache"):
            ch = chain(self.units, None, lookup=MapLookup(self._dm) if hasattr(self, "_dm")
                       else None, state=self.state)
            self._turn_cache = np.degrees(np.diff(ch.angles))
        return self._turn_cache

    def summary(self) -> str:
        """The table, each target's pattern and deviations, as `snapmorph design` prints them."""
        n = sum(not u.is_spacer for u in self.units)
        text = [self.table(),
                f"array length {self.array_length * 1e3:.1f} mm; {n} arched units, "
                f"{len(self.units) - n} spacers; map state {self.state}; "
                f"{len(self.targets)} targets, tol {100 * self.tol:.2f} % ({self.placement_mode} "
                "placement)",
                "target, length, snap pattern (unit 1 first), deviation % of its length "
                "(max / RMS) predicted and simulated, best placement | clamped:"]
        for k, name in enumerate(self.names):
            d = self.deviations[k]
            line = (f"  T{k + 1} {name}: {self.targets[k].length * 1e3:.1f} mm, pattern "
                    f"{self.states[k]}; predicted {100 * d['best'][0]:.2f} / "
                    f"{100 * d['best'][1]:.2f} | {100 * d['clamped'][0]:.2f} / "
                    f"{100 * d['clamped'][1]:.2f}")
            if self.verification is not None:
                v = self.verification[k]
                line += (f"; simulated ({v['status']}, {v['nodes']} nodes/unit, {v['time']:.1f} s) "
                         f"{100 * v['deviations']['best'][0]:.2f} / "
                         f"{100 * v['deviations']['best'][1]:.2f} | "
                         f"{100 * v['deviations']['clamped'][0]:.2f} / "
                         f"{100 * v['deviations']['clamped'][1]:.2f}")
            dev = d[self.placement_mode][0]
            mm = f"{dev * self.targets[k].length * 1e3:.2f} mm"
            line += (f"  -> met ({100 * dev:.2f} % <= {100 * self.tol:.2f} %, {mm})"
                     if self.met[k] else
                     f"  -> TOLERANCE MISSED ({100 * dev:.2f} % > {100 * self.tol:.2f} %, {mm})"
                     if dev > self.tol else
                     f"  -> VERIFICATION FAILED ({self.failures[k]})")
            text.append(line)
        missed = [f"T{k + 1}" for k, d in enumerate(self.max_deviations) if d > self.tol]
        if missed:
            text.append("TOLERANCE MISSED for " + ", ".join(missed) + ": this is the best "
                        "design found")
        failed = [f"T{k + 1}" for k, f in enumerate(self.failures) if f]
        if failed:
            text.append("VERIFICATION FAILED for " + ", ".join(failed) + ": the whole-array "
                        "simulation does not confirm the design; not met")
        text += [f"note: {note}" for note in self.notes]
        return "\n".join(text)

    def morph_plan(self, a: int, b: int, **kw):
        """The reconfiguration from target a's pattern to target b's (0-based indices):
        `design.reconfigure.morph_plan`, drawn in target a's frame."""
        from snapmorph.design.reconfigure import morph_plan

        kw.setdefault("placement", self.placements[a][self.placement_mode])
        kw.setdefault("state", self.state)
        if hasattr(self, "_dm"):
            kw.setdefault("design_map", self._dm)
        return morph_plan(self.units, self.patterns[a], self.patterns[b], **kw)

    def write(self, out_dir, bed_length_mm: float | None = None, colours: dict | None = None,
              drawings: bool = True) -> list:
        """Write units.csv (with target 1's placement line), patterns.csv, predicted_k.csv
        (and simulated_k.csv), one overlay plot per target (target_k.png), one figure of all
        targets with their patterns (patterns.png), the morphing plan between consecutive
        targets (morph.png), design.txt and the DXF/SVG drawings; returns the paths (mm)."""
        from pathlib import Path

        from snapmorph.design.multishape_plots import plot_patterns, plot_target_overlay
        from snapmorph.design.units import write_units_csv

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        mode = self.placement_mode
        units_csv = write_units_csv(self.units, out / "units.csv",
                                    placement=self.placements[0][mode])
        if not self.met_all:
            lines = units_csv.read_text().splitlines(keepends=True)
            notes = [f"# TOLERANCE MISSED for T{k + 1} ({100 * d:.2f} % > {100 * self.tol:.2f} "
                     f"%); best design found ({mode} placement)\n"
                     for k, d in enumerate(self.max_deviations) if d > self.tol]
            notes += [f"# VERIFICATION FAILED for T{k + 1}: {f}\n"
                      for k, f in enumerate(self.failures) if f]
            units_csv.write_text("".join(lines[:1] + notes + lines[1:]))
        paths = [units_csv, self._write_patterns(out / "patterns.csv")]
        for k in range(len(self.targets)):
            p = out / f"predicted_{k + 1}.csv"
            np.savetxt(p, self.predicted[k] * 1e3, delimiter=",", fmt="%.4f",
                       header="x_mm,y_mm", comments="")
            paths.append(p)
            if self.verification is not None:
                p = out / f"simulated_{k + 1}.csv"
                np.savetxt(p, self.verification[k]["xy"] * 1e3, delimiter=",", fmt="%.4f",
                           header="x_mm,y_mm", comments="")
                paths.append(p)
            paths.append(plot_target_overlay(self, k, out / f"target_{k + 1}.png"))
        paths.append(plot_patterns(self, out / "patterns.png"))
        if len(self.targets) >= 2:
            from snapmorph.design.multishape_plots import plot_morph_plans

            paths.append(plot_morph_plans(self, out / "morph.png"))
        (out / "design.txt").write_text(self.summary() + "\n")
        paths.append(out / "design.txt")
        if drawings:
            from snapmorph.design.drawings import write_drawings

            paths += write_drawings(self.units, out, bed_length_mm=bed_length_mm,
                                    colours=colours)
        return paths

    def _write_patterns(self, path):
        """patterns.csv: one line per target: its name, pattern, placement (mm, deg), length
        and deviations (%), and whether tol is met."""
        import csv

        with open(path, "w", newline="") as fh:
            wr = csv.writer(fh)
            wr.writerow(["target", "name", "pattern", "x0_mm", "y0_mm", "angle_deg", "length_mm",
                         "predicted_best_pct", "predicted_clamped_pct", "simulated_best_pct",
                         "simulated_clamped_pct", "met"])
            for k, name in enumerate(self.names):
                x0, y0, a = self.placements[k][self.placement_mode]
                d = self.deviations[k]
                sim = ("", "")
                if self.verification is not None:
                    v = self.verification[k]["deviations"]
                    sim = (f"{100 * v['best'][0]:.4f}", f"{100 * v['clamped'][0]:.4f}")
                wr.writerow([k + 1, name, self.states[k], f"{x0 * 1e3:.6g}", f"{y0 * 1e3:.6g}",
                             f"{math.degrees(a):.6g}", f"{self.targets[k].length * 1e3:.3f}",
                             f"{100 * d['best'][0]:.4f}", f"{100 * d['clamped'][0]:.4f}", *sim,
                             "yes" if self.met[k] else "no"])
        return path


# =============================================================================================
# Inputs
# =============================================================================================
def _read_targets(targets) -> tuple[list, tuple]:
    """(list of Target, names) from the targets argument: a list or tuple of at least two."""
    from pathlib import Path

    from snapmorph.design.target_input import as_target

    if isinstance(targets, (str, bytes, Target, np.ndarray)) or hasattr(targets, "__fspath__") \
            or not isinstance(targets, (list, tuple)):
        raise ValueError("targets must be a list of at least two targets (each (N, 2) points in "
                         "m, a .csv/.svg/.dxf file in mm or a design.Target); got "
                         f"{type(targets).__name__} (for one target use design.inverse_design)")
    if len(targets) < 2:
        raise ValueError(f"targets must list at least two targets (one shape per snap "
                         f"pattern); got {len(targets)} (for one target use "
                         "design.inverse_design)")
    out, names = [], []
    for k, obj in enumerate(targets):
        out.append(as_target(obj, what=f"target {k + 1}"))
        names.append(Path(obj).name if isinstance(obj, str) or hasattr(obj, "__fspath__")
                     else f"target {k + 1}")
    return out, tuple(names)


def _check_lengths(targets, tol: float, placement: str) -> None:
    """Refuse targets whose lengths no array of one length can meet within tol.

    The base does not stretch: every state is Λ long. Even for straight targets (where the
    length is all that matters) the best placement leaves |Λ − ℓ_k| / 2 at each end and the
    clamped one |Λ − ℓ_k| at the free end, so two targets can both be met only if
    |ℓ_a − ℓ_b| <= 2 tol (ℓ_a + ℓ_b) (best) or tol (ℓ_a + ℓ_b) (clamped)."""
    ell = [t.length for t in targets]
    factor = 2.0 if placement == "best" else 1.0
    for a in range(len(ell)):
        for b in range(a + 1, len(ell)):
            allowed = factor * tol * (ell[a] + ell[b])
            if abs(ell[a] - ell[b]) > allowed:
                raise ValueError(
                    f"targets {a + 1} and {b + 1} differ in length: {ell[a] * 1e3:.1f} mm and "
                    f"{ell[b] * 1e3:.1f} mm; the base does not stretch, so every state of an "
                    f"array has one length, and with tol = {100 * tol:g} % ({placement} "
                    f"placement) lengths may differ by at most {allowed * 1e3:.1f} mm; scale "
                    "the targets to one length")


# =============================================================================================
# 1. The layout: error diffusion over slots
# =============================================================================================
def _turning_profiles(targets, u) -> np.ndarray:
    """Each target's tangent direction at arc-length fractions u, relative to its start
    (degrees, unwrapped): (K, len(u))."""
    return np.array([np.degrees(np.interp(u * t.length, t.s, t.angle) - t.angle[0])
                     for t in targets])


def _slot_counts_min(targets, lim: Limits) -> int:
    """The fewest slots that can hold the turning: a unit turns one way, by at most θ_max, so
    the array needs at least max_k ceil(Φ⁺_k / θ_max) left-turning units and max_k
    ceil(Φ⁻_k / θ_max) right-turning ones (Φ±_k target k's total left / right turning; turning
    below θ_min / 2 needs no unit); at least one slot."""
    phi = _turning_profiles(targets, np.linspace(0.0, 1.0, 801))
    d = np.diff(phi, axis=1)
    need = {1: 0, -1: 0}
    for row in d:
        for sgn in (1, -1):
            total = float(sgn * row[sgn * row > 0].sum())
            if total >= 0.5 * lim.theta_min:
                need[sgn] = max(need[sgn], math.ceil(total / lim.theta_max - 1e-9))
    return max(1, need[1] + need[-1])


def _slot_layout(targets, N: int, share: float, lim: Limits, dm, t, w, length: float):
    """(sides, L, h/L, patterns (K, n) bool) of the error-diffusion layout with N slots (see
    the module docstring, step 1)."""
    K = len(targets)
    edges = np.linspace(0.0, 1.0, N + 1)
    phi = _turning_profiles(targets, edges)
    D = np.diff(phi, axis=1)  # (K, N) degrees
    slot = length / N
    owed = np.zeros(K)
    subsets = [tuple(k for k in range(K) if (m >> k) & 1) for m in range(1, 2 ** K)]
    items = []  # (side, L, hL, snapped targets)
    for j in range(N):
        want = owed + D[:, j]
        best = (float(want @ want), 0, 0.0, ())
        for sgn in (1, -1):
            for A in subsets:
                if not all(sgn * want[k] > 0 for k in A):
                    continue
                tau = float(np.clip(np.mean([sgn * want[k] for k in A]), lim.theta_min,
                                    lim.theta_max))
                left = want.copy()
                left[list(A)] -= sgn * tau
                cost = float(left @ left)
                if cost < best[0] - 1e-12:
                    best = (cost, sgn, tau, A)
        _, sgn, tau, A = best
        if sgn == 0:
            items.append((0, slot, 0.0, ()))
            owed = want
            continue
        L = float(np.clip(share * slot, lim.L_min, lim.L_max))
        gap = max(0.0, slot - L)  # the unit at the slot's middle, spacers either side
        halves = gap >= 2 * lim.spacer_min
        if halves:
            items.append((0, gap / 2, 0.0, ()))
        hL = hL_for_turn(dm, tau, L, t, w, lim, {})
        items.append((sgn, L, hL, A))
        if halves or gap >= lim.spacer_min:
            items.append((0, gap / 2 if halves else gap, 0.0, ()))
        owed = want.copy()
        owed[list(A)] -= sgn * tau
    merged = []
    for it in items:
        if it[0] == 0 and merged and merged[-1][0] == 0:
            merged[-1] = (0, merged[-1][1] + it[1], 0.0, ())
        else:
            merged.append(it)
    merged = [it for it in merged if it[0] != 0 or it[1] >= lim.spacer_min]
    if not merged:
        merged = [(0, length, 0.0, ())]
    sides = np.array([it[0] for it in merged], dtype=int)
    pats = np.array([[k in it[3] for it in merged] for k in range(K)], dtype=bool)
    return (sides, np.array([it[1] for it in merged]), np.array([it[2] for it in merged]),
            pats)


def _units_from(sides, L, hL, t, w, b_over_L) -> list:
    return [Unit(L=float(Li), h=0.0, t=t, w=w, side=0) if sd == 0 else
            Unit(L=float(Li), h=float(hi * Li), t=t, w=w, side=int(sd), b=b_over_L * float(Li))
            for sd, Li, hi in zip(sides, L, hL)]


def _assess(fit: _JointFit, v, quick: bool):
    """Each target's deviations and placements of the fitted design (its local chains through
    the fast model, placed by `design.nearest.measure`); quick: a short placement search from
    the fitted frame (while comparing layouts)."""
    L, hL, frames = fit.unpack(v)
    zs, ts, zf = fit.shapes(L, hL)
    devs, places, locals_ = [], [], []
    for k, tg in enumerate(fit.targets):
        z = fit.chains(zs[None], ts[None], zf[None], k, np.zeros(1, complex), np.zeros(1))[0]
        local = np.stack([z.real, z.imag], axis=-1)
        x0, y0, a0 = frames[k]
        d, p = measure(local, tg, start=(x0, y0), angle=a0, maxiter=80 if quick else 400,
                       kabsch=not quick)
        devs.append(d)
        places.append(p)
        locals_.append(local)
    return devs, places, locals_


def inverse_design_multi(targets, t: float, w: float, *, tol: float = 0.02,
                         placement: str = "best", design_map=None, L_range=None,
                         hL_range=None, min_barrier: float = 0.5, state: str = "released",
                         max_units: int = 40, verify: bool = False, nodes: int | None = None,
                         progress=None) -> MultiDesign:
    """Design one array and one snap pattern per target so that the map's forward kinematics of
    each pattern is within `tol` of its target (SI units; the method is in the module
    docstring).

    targets: a list of at least two targets, each (N, 2) points in m, a .csv/.svg/.dxf file in
        mm or a `design.Target`, of one length (within what tol allows: refused otherwise,
        with both lengths).
    tol: largest deviation allowed, a fraction of each target's length (0 < tol < 1).
    placement: "best" (each pattern after its best rigid placement on its target) or "clamped"
        (unit 1's start on each target's start point and tangent). Both are reported.
    L_range, hL_range, min_barrier, state, max_units: as in `design.inverse_design`.
    verify: also simulate the whole array in each pattern (`verify_multi`; nodes per unit).
    progress: None or a callable progress(stage) ("layouts", "verify").
    Returns a `MultiDesign`; when tol is missed for some target it warns (`UserWarning`) and
    returns the best design found with met[k] False there.
    """
    t0 = time.perf_counter()
    t, w = check_positive("t", t), check_positive("w", w)
    tol = check_fraction("tol", tol)
    placement = check_choice("placement", placement, PLACEMENTS)
    state = check_choice("state", state, STATES)
    if isinstance(max_units, bool) or not isinstance(max_units, (int, np.integer)) or max_units < 1:
        raise ValueError(f"max_units must be an integer >= 1, got {max_units!r}")
    try:
        min_barrier = float(min_barrier)
    except (TypeError, ValueError):
        raise ValueError(f"min_barrier must be a number (E I_arch / L), got "
                         f"{min_barrier!r}") from None
    if not (math.isfinite(min_barrier) and min_barrier >= 0):
        raise ValueError(f"min_barrier must be >= 0 (E I_arch / L), got {min_barrier!r}")
    if progress is not None and not callable(progress):
        raise ValueError(f"progress must be None or a callable progress(stage); got {progress!r}")
    tick = progress if progress is not None else (lambda stage: None)
    tgts, names = _read_targets(targets)
    _check_lengths(tgts, tol, placement)
    from snapmorph.design.lookup import MapLookup, default_map

    raw = design_map if design_map is not None else default_map()
    state_kw, state_used = map_state_kw(raw, state)
    dm = StateMap(raw, state_kw)
    lim = dataclasses.replace(fabrication_limits(dm, t, w, L_range, hL_range, min_barrier, {}),
                              spacer_min=SPACER_MIN)
    b_over_L = MapLookup(dm).b_over_L
    length = float(np.mean([tg.length for tg in tgts]))

    n_lo = _slot_counts_min(tgts, lim)
    n_hi = max(n_lo, int(length // lim.L_min))
    N, tried, best, seen = n_lo, [], None, set()
    while True:
        worst_n = None
        for share in SHARES:
            sides, L, hL, pats = _slot_layout(tgts, N, share, lim, dm, t, w, length)
            n_arched = int(np.count_nonzero(sides))
            key = (tuple(sides), pats.tobytes(), tuple(np.round(L, 9)))
            if key in seen:
                continue
            seen.add(key)
            if n_arched > max_units:
                tried.append(dict(slots=N, share=share, error=f"{n_arched} arched units > "
                                                                f"max_units = {max_units}"))
                continue
            tick("layouts")
            frames = [(float(tg.start[0]), float(tg.start[1]), tg.start_angle) for tg in tgts]
            fit, v, nfev, changes = _fit_layout(dm, t, w, sides, L, hL, pats, frames, tgts, lim,
                                                placement, tol)
            # the arc-length-matched distances bound the deviation from above: measure the
            # deviation itself only for a layout that may be within reach
            matched = float(np.max(np.hypot(*fit.residuals(v).reshape(-1, 2).T)))
            if matched <= 2.5 * tol:
                devs, places, _ = _assess(fit, v, quick=True)
                worst = max(d[placement][0] for d in devs)
            else:
                worst = matched
            tried.append(dict(slots=N, share=share, units=fit.n, arched=n_arched,
                              worst=worst, nfev=nfev, pattern_changes=changes))
            if best is None or worst < best[0]:
                best = (worst, fit, v)
            worst_n = worst if worst_n is None else min(worst_n, worst)
            if worst <= tol:
                break
        if best[0] <= tol or N >= n_hi:
            break
        grow = N + 1 if worst_n is None else int(math.ceil(N * math.sqrt(worst_n / tol)))
        N = min(n_hi, max(N + 1, min(grow, N + 4)))
    if best is None:
        raise ValueError("no design: " + "; ".join(str(d.get("error")) for d in tried)
                         + "; raise max_units")
    _, fit, v = best
    devs, places, _ = _assess(fit, v, quick=False)
    L, hL, _ = fit.unpack(v)
    units = _units_from(fit.m.sides, L, hL, t, w, b_over_L)
    patterns = tuple(tuple(bool(x) for x in p) for p in fit.patterns)
    predicted = [_placed(units, p, pl[placement], dm, state_used)
                 for p, pl in zip(patterns, places)]
    met = tuple(bool(d[placement][0] <= tol) for d in devs)
    md = MultiDesign(units=units, patterns=patterns, targets=tgts, names=names,
                     predicted=predicted, deviations=devs, placements=places,
                     placement_mode=placement, tol=tol, met=met, t=t, w=w, state=state_used,
                     limits=lim, history=tried)
    md._dm = raw
    if state_used != state:
        md.notes.append(f"the map has no {state} state; used {state_used}")
    if verify:
        tick("verify")
        verify_multi(md, nodes=nodes)
    for k, failure in enumerate(md.failures):
        if failure:
            warnings.warn(f"verification failed for target {k + 1} ({names[k]}): {failure}",
                          UserWarning, stacklevel=2)
    missed = ", ".join(f"target {k + 1} ({names[k]}: {100 * d[placement][0]:.2f} %)"
                       for k, d in enumerate(devs) if d[placement][0] > tol)
    if missed:
        msg = (f"tolerance missed: the best array found deviates from {missed} > tol "
               f"{100 * tol:.2f} % ({placement} placement); no array of these units' ranges "
               f"was found that meets every target (tried {len(tried)} layouts, up to "
               f"{max((d.get('arched', 0) for d in tried), default=0)} arched units)")
        md.notes.append(msg)
        warnings.warn(msg, UserWarning, stacklevel=2)
    md.time = time.perf_counter() - t0
    return md


def _placed(units, pattern, placement, dm, state) -> np.ndarray:
    """The base of `units` in `pattern` by `design.kinematics.chain`, placed (m)."""
    from snapmorph.design.kinematics import chain
    from snapmorph.design.lookup import MapLookup

    x0, y0, a0 = placement
    return chain(units, list(pattern), lookup=MapLookup(dm), start=(x0, y0), start_angle=a0,
                 state=state).xy


#: mesh resolutions (nodes per unit) `verify_multi` tries in turn: the whole-array Newton
#: iterations of `design.arrays.snap_unit` stall (step size underflow at d = 0) on long arrays
#: meshed at the single unit's 161 nodes, e.g. a unit snapped after 400 mm of unsnapped units;
#: 81 nodes (the map itself is built at 101) deviates from the 161-node shape by about 0.05 %
#: of the length (`tests/design/test_multishape.py` measures it)
VERIFY_NODES = (81, 61, 41)


def verify_multi(md: MultiDesign, nodes: int | None = None) -> list:
    """Simulate the whole array in each target's pattern (`design.arrays.simulate_array` on
    one mesh, the pattern's units snapped in order, actuators removed) and measure each base
    against its target both ways. nodes: resolution per unit; None tries `VERIFY_NODES` in
    turn until the simulation succeeds. Returns (and stores as `md.verification`) one dict
    per target: {"status", "time", "nodes", "xy" (placed as the design says), "xy_best",
    "deviations", "placements", "max_deviation", "state"}."""
    from snapmorph.design.arrays import build_array, simulate_array

    resolutions = VERIFY_NODES if nodes is None else (nodes,)
    models = {}
    out = []
    for k, (pattern, tg) in enumerate(zip(md.patterns, md.targets)):
        t0 = time.perf_counter()
        for nd in resolutions:
            if nd not in models:
                models[nd] = build_array(md.units, nodes=nd)
            r = simulate_array(md.units, snapped=list(pattern), model=models[nd])
            if r.status == "ok":
                break
        x0, y0, a0 = md.placements[k][md.placement_mode]
        devs, places = measure(r.base, tg, start=(x0, y0), angle=a0)
        out.append({"status": r.status, "time": time.perf_counter() - t0, "nodes": nd,
                    "xy": place_rigid(r.base, (x0, y0), a0),
                    "xy_best": place_rigid(r.base, places["best"][:2], places["best"][2]),
                    "deviations": devs, "placements": places,
                    "max_deviation": devs[md.placement_mode][0], "state": r.state})
    md.verification = out
    # a target whose verification fails is never met (`verification_failure`)
    for v, tg in zip(out, md.targets):
        v["failure"] = verification_failure(v["status"], v["max_deviation"], md.tol,
                                            md.placement_mode, tg.length)
    md.met = tuple(bool(d <= md.tol) and not v["failure"]
                   for d, v in zip(md.max_deviations, out))
    return out
