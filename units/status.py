"""How a unit simulation ended: one table for the unit results, the design maps and the CLI.

A result's ``status`` is text: a name of this table, possibly followed by ": why" (e.g.
"timeout: time_limit 2 s reached at d = ..."); the maps store its ``code``. ``answered``
statuses are physical answers (the command line exits 0 on them); the others say that the
computation failed, never what the unit does.
"""

from __future__ import annotations

from types import MappingProxyType

#: name -> (code, answered, meaning); -1 "pending" exists only in a map being built
TABLE = MappingProxyType({
    "pending": (-1, False, "not computed yet"),
    "ok": (0, True, "bistable: the second state exists and is stable"),
    "monostable": (1, True, "no second state: F does not fall below zero"),
    "not_converged": (2, False, "the computation failed"),
    "invalid_geometry": (3, False, "the geometry is outside the model's domain"),
    "timeout": (4, False, "the time limit was reached"),
    "second_state_unstable": (5, True, "the second state exists but is unstable"),
})

#: name -> code and code -> name (pending included)
CODE = MappingProxyType({name: row[0] for name, row in TABLE.items()})
NAME = MappingProxyType({row[0]: name for name, row in TABLE.items()})
PENDING, OK, MONOSTABLE, NOT_CONVERGED, INVALID_GEOMETRY, TIMEOUT, SECOND_STATE_UNSTABLE = (
    CODE[n] for n in ("pending", "ok", "monostable", "not_converged", "invalid_geometry",
                      "timeout", "second_state_unstable"))
#: codes of points solved and found not bistable (F_cr and d_cr exist)
NOT_BISTABLE = (MONOSTABLE, SECOND_STATE_UNSTABLE)
#: codes of points whose computation failed (no value exists)
FAILED = (NOT_CONVERGED, INVALID_GEOMETRY, TIMEOUT)


def status_code(status: str) -> int:
    """The code of a status text: its name, or the name its words start with ("timeout: ...",
    "second state unstable: ...", "monostable: unit 2: ..."); anything else is a failed
    computation (not_converged)."""
    if status in CODE:
        return CODE[status]
    for name in ("timeout", "second_state_unstable", "monostable", "invalid_geometry"):
        if status.startswith(name.replace("_", " ")):
            return CODE[name]
    return NOT_CONVERGED


def answered(status: str) -> bool:
    """Is the status a physical answer (ok, monostable, second state unstable)?"""
    return TABLE[NAME[status_code(status)]][1]


def exit_status(status: str) -> int:
    """The command line's exit status for a simulation that ended so: 0 for an answer, 1 for a
    failed computation."""
    return 0 if answered(status) else 1
