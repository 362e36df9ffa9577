"""`Design`, the result of inverse design: the units, the predicted all-snapped base, its
deviations from the target both ways, and the table, summary and files of a design."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Piece:
    """How one unit came out of the biarcs: its arc(s) of the target (a spacer may cover
    several merged flat arcs), and the turning (degrees) and chord (m) it was designed for."""

    arcs: list
    turn_deg: float
    chord: float


@dataclass
class Design:
    """An inverse design. Lengths in m; deviations as fractions of `target_length`."""

    units: list
    predicted: np.ndarray
    target: np.ndarray
    target_length: float
    max_deviation: float
    rms_deviation: float
    control_points: np.ndarray
    control_angles: np.ndarray
    arcs: list
    pieces: list
    t: float
    w: float
    points: np.ndarray | None = None
    refinement: dict | None = None
    history: list = field(default_factory=list)
    #: the tolerance asked for (fraction of target_length) and whether the selected deviation
    #: meets it
    tol: float | None = None
    met: bool | None = None
    #: "best" (best rigid placement) or "clamped" (unit 1 on the target's start and tangent):
    #: which of `deviations` is `max_deviation` / `rms_deviation` and where `predicted` sits
    placement_mode: str = "clamped"
    #: (x0, y0, angle) m, m, rad: unit 1's start point and start direction in the target frame
    placement: tuple | None = None
    deviations: dict = field(default_factory=dict)
    placements: dict = field(default_factory=dict)
    #: the unit state the map was entered with ("released" or "actuated")
    state: str = "actuated"
    theta_convention: str = "ours"
    #: whole-array simulation (`verify_design`), None until verified
    verification: dict | None = None
    #: why the whole-array verification failed (status not ok, or its deviation misses tol);
    #: None when it passed or did not run. A failed verification makes `met` False
    verification_failure: str | None = None
    #: the tolerances asked for: a fraction of the target's length and an absolute one (m,
    #: None if not given); `tol` is the stricter of the two, as a fraction
    tol_rel: float | None = None
    tol_abs: float | None = None
    #: the target as read (`target_io.TargetFile`: points, drawing frame), None if unknown
    source: object | None = None
    notes: list = field(default_factory=list)
    limits: object | None = None
    time: float = 0.0

    def __repr__(self):
        # short: the arrays (target, predicted, arcs) would print about 10 kB
        n_arched = sum(not u.is_spacer for u in self.units)
        met = "" if self.met is None else f", tol {100 * self.tol:.3g} % {'met' if self.met else 'MISSED'}"
        return (f"Design({n_arched} arched units + {len(self.units) - n_arched} spacers, target "
                f"{self.target_length * 1e3:.1f} mm, max deviation {100 * self.max_deviation:.3g} % "
                f"({self.placement_mode}){met}, t={self.t * 1e3:.3g} mm, w={self.w * 1e3:.3g} mm, "
                f"state {self.state})")

    @property
    def joints(self) -> np.ndarray:
        """Unit end points of the predicted array (n + 1, 2), m."""
        return self._chain.joints

    def table(self) -> str:
        """The unit table as text (mm, degrees): each unit's snapped turning and chord (forward
        kinematics) and the turning of the target arc(s) it stands for; b_mm (the arch's flat
        ends) when an arched unit has b > 0, as units.csv."""
        ch = self._chain
        turn = np.degrees(np.diff(ch.angles))
        chord = np.hypot(*np.diff(ch.joints, axis=0).T)
        with_b = any(u.b > 0 and not u.is_spacer for u in self.units)
        lines = [f"{'unit':>4} {'L_mm':>7} {'h_mm':>6} {'h/L':>6} {'side':>4} {'turn_deg':>8} "
                 f"{'S_mm':>7} {'target_deg':>10}" + (f" {'b_mm':>6}" if with_b else "")]
        for i, (u, p) in enumerate(zip(self.units, self.pieces)):
            hl = f"{u.h / u.L:6.3f}" if u.h > 0 else "     -"
            side = f"{u.side:+d}" if u.side else "0"
            b = (f" {'-' if u.is_spacer else f'{u.b * 1e3:.2f}':>6}") if with_b else ""
            lines.append(f"{i + 1:>4} {u.L * 1e3:7.1f} {u.h * 1e3:6.1f} {hl} {side:>4} "
                         f"{turn[i]:8.2f} {chord[i] * 1e3:7.1f} {p.turn_deg:10.2f}{b}")
        return "\n".join(lines)

    def write(self, out_dir, bed_length_mm: float | None = None, colours: dict | None = None,
              drawings: bool = True, *, bed=None, kerf_mm: float = 0.0, stl: bool = True,
              assembly: bool = True) -> list:
        """Write into out_dir: units.csv, predicted.csv (simulated.csv), target.csv (the curve
        as read, mm), overlay.svg/.dxf (target, predicted, simulated in the drawing's own
        coordinates: `targets_frame.write_in_drawing_frame`), design.png, design.txt and,
        unless drawings is False, the workshop files (`workshop.write_workshop`: drawings,
        nested on sheets of `bed` "600x400" when given, `kerf_mm`, STL molds, assembly sheet;
        a part larger than a common bed without `bed` is a `drawings.BedWarning`). Returns the
        paths."""
        import warnings
        from pathlib import Path

        from snapmorph.design.plots import plot_design
        from snapmorph.design.targets_frame import write_in_drawing_frame, write_target_csv
        from snapmorph.design.units import write_units_csv

        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        paths = [write_units_csv(self.units, out / "units.csv", placement=self.placement)]
        if self.met is False:
            _mark_missed(out / "units.csv", self)
        np.savetxt(out / "predicted.csv", self.predicted * 1e3, delimiter=",", fmt="%.4f",
                   header="x_mm,y_mm", comments="")
        paths.append(out / "predicted.csv")
        simulated = None if self.verification is None else self.verification["xy"]
        if simulated is not None:
            np.savetxt(out / "simulated.csv", simulated * 1e3, delimiter=",",
                       fmt="%.4f", header="x_mm,y_mm", comments="")
            paths.append(out / "simulated.csv")
        if self.source is not None:
            paths.append(write_target_csv(self.source.points, out / "target.csv"))
            paths += write_in_drawing_frame(self.source.frame, {
                "target": self.source.points, "predicted": self.predicted,
                "simulated": simulated}, out)
        paths.append(plot_design(self, out / "design.png"))
        (out / "design.txt").write_text(self.summary() + "\n")
        paths.append(out / "design.txt")
        if drawings:
            from snapmorph.design.drawings import BedWarning
            from snapmorph.design.workshop import write_workshop

            ws = write_workshop(self.units, out, bed=bed, bed_length_mm=bed_length_mm,
                                kerf_mm=kerf_mm, colours=colours, stl=stl, assembly=assembly,
                                shape_xy=self.predicted)
            paths += ws.paths
            for msg in ws.warnings:
                warnings.warn(msg, BedWarning, stacklevel=2)
        return paths

    @property
    def tol_governs(self) -> str:
        """Which tolerance `tol` is: "relative" (the fraction asked) or "absolute" (the
        absolute one, stricter for this target's length)."""
        if self.tol_abs is not None and (self.tol_rel is None or self.tol < self.tol_rel):
            return "absolute"
        return "relative"

    def _verdict(self) -> list:
        """The summary's lines on the tolerance: which one governs, met or missed, and a failed
        whole-array verification."""
        L, mode = self.target_length, self.placement_mode
        what = f"tolerance {100 * self.tol:.2f} % = {self.tol * L * 1e3:.2f} mm ({mode} placement"
        if self.tol_abs is not None:
            rel = self.tol_rel if self.tol_rel is not None else self.tol
            what += (f"; the absolute {self.tol_abs * 1e3:.2f} mm governs, stricter than "
                     f"{100 * rel:.2f} %" if self.tol_governs == "absolute" else
                     f"; {100 * rel:.2f} % governs, stricter than the absolute "
                     f"{self.tol_abs * 1e3:.2f} mm")
        what += ")"
        dev = f"{100 * self.max_deviation:.2f} %, {self.max_deviation * L * 1e3:.2f} mm"
        if self.max_deviation > self.tol:
            lines = [f"TOLERANCE MISSED: {dev} > {what}; this is the best design found"]
        elif self.verification_failure:
            lines = [f"{what}: predicted within it ({dev}), but not confirmed"]
        else:
            lines = [f"{what}: met ({dev})"]
        if self.verification_failure:
            lines.append(f"VERIFICATION FAILED: {self.verification_failure}; the design is not "
                         "met")
        return lines

    def summary(self) -> str:
        """The table and the deviations, as printed by `snapmorph design`."""
        L = self.target_length
        text = [self.table(),
                f"target length {L * 1e3:.1f} mm; {sum(not u.is_spacer for u in self.units)} "
                f"arched units, {sum(u.is_spacer for u in self.units)} spacers; map state: "
                f"{self.state}; angle convention: {self.theta_convention}"]
        rows = [("predicted (map)", self.deviations)]
        if self.verification is not None:
            v = self.verification
            rows.append((f"simulated array ({v['status'].split(':')[0]}, {v['time']:.1f} s)",
                         v["deviations"]))
        text.append("deviation from the target, % of its length (max / RMS, max in mm):")
        for name, devs in rows:
            for mode, what in (("best", "best rigid placement"),
                               ("clamped", "start clamped on the target")):
                if mode in devs:
                    mx, rms = devs[mode]
                    sel = " <- tol" if mode == self.placement_mode and name.startswith("pred") else ""
                    text.append(f"  {name:<34} {what:<29} {100 * mx:6.2f} / {100 * rms:5.2f} "
                                f"({mx * L * 1e3:.2f} mm){sel}")
        if not self.deviations:
            text.append(f"  all-snapped deviation: max {100 * self.max_deviation:.2f} %, RMS "
                        f"{100 * self.rms_deviation:.2f} % (max "
                        f"{self.max_deviation * L * 1e3:.2f} mm)")
        if self.tol is not None:
            text += self._verdict()
        if self.placement is not None:
            x0, y0, a = self.placement
            text.append(f"placement of unit 1's start: x0 = {x0 * 1e3:.2f} mm, y0 = {y0 * 1e3:.2f} "
                        f"mm, direction {math.degrees(a):.2f} deg")
        if self.refinement and "quantum_deg" not in self.refinement:
            r = self.refinement
            text.append(f"least-squares refinement: max {100 * r['max_before']:.2f} % -> "
                        f"{100 * r['max_after']:.2f} %, RMS {100 * r['rms_before']:.2f} % -> "
                        f"{100 * r['rms_after']:.2f} % ({r['nfev']} evaluations"
                        f"{'' if r['accepted'] else '; not better, kept the biarc design'})")
        text += [f"note: {n}" for n in self.notes]
        return "\n".join(text)


def _mark_missed(path, design) -> None:
    """Add comment lines to a written units.csv saying the tolerance was missed or the
    whole-array verification failed."""
    from pathlib import Path

    path = Path(path)
    lines = path.read_text().splitlines(keepends=True)
    notes = []
    if design.max_deviation > design.tol:
        notes.append(f"# TOLERANCE MISSED: best design found, deviation "
                     f"{100 * design.max_deviation:.2f} % > tol {100 * design.tol:.2f} % of the "
                     f"target length ({design.placement_mode} placement)\n")
    if design.verification_failure:
        notes.append(f"# VERIFICATION FAILED: {design.verification_failure}\n")
    k = 1 if lines and lines[0].startswith("# placement") else 0
    path.write_text("".join(lines[:k] + notes + lines[k:]))
