"""Assembly of the global energy, gradient and reduced banded tangent stiffness.

The element arrays travel together as one tuple ``elements``:

``(stretch_nodes (ne, 2) int, stretch_params (ne, 2) [EA, rest length],
   bend_nodes (nb, 3) int, bend_params (nb, 2) [EI / l_bar, kappa_bar],
   spring_nodes (ns, 2) int, spring_params (ns, 3) [k, rest offset x, rest offset z])``

Constraints enter through ``dof_map`` (the paper's constraint matrix W in index form): full
DOF ``j = 2 node + c`` (c = 0 for x, 1 for z) maps to reduced DOF ``dof_map[j] >= 0``, or
to ``-1`` when it is fixed or prescribed. Nodes that are tied or translate together share
reduced DOFs, so ``K_red = W^T K W`` is assembled by scattering straight into the band.

Dead loads (`assemble_dead_loads`, planar and 3-D alike) travel as one record ``loads`` =
``(full DOFs (m,) int, reduced DOFs (m,) int (-1 held), forces (m,) N, stress-free
coordinates (m,) m)``, one entry per loaded position coordinate: their potential
``-f (x - X)`` joins the energy and ``-f`` the gradients, through the same DOF map, so the
load on a tied or rigid-group node goes to its group's reduced DOF (``W^T f``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from snapmorph.solver.banded import written_extent
from snapmorph.solver.energies import (bending_lower, bending_scales, dead_load_terms,
                                       edge_turn, spring_lower, stretch_force, stretch_jet,
                                       stretch_lower, turning_jet_edges, turning_lower)


@njit(cache=True)
def _add_gradient(nodes, dofs, nloc, g, grad_red, grad_full):
    """Add an element's gradient ``g`` (nloc,) to the full and the reduced gradient."""
    for a in range(nloc):
        grad_full[2 * nodes[a >> 1] + (a & 1)] += g[a]
        ra = dofs[a]
        if ra >= 0:
            grad_red[ra] += g[a]


@njit(cache=True)
def _reduce_gradient(dof_map, grad_full, grad_red):
    """grad_red = W^T grad_full: the same terms as scattering every element's gradient
    into both, summed per reduced DOF in another order where DOFs are tied (in the same
    order, so bit for bit, elsewhere). One pass instead of a second scatter per element."""
    grad_red[:] = 0.0
    for j in range(dof_map.shape[0]):
        r = dof_map[j]
        if r >= 0:
            grad_red[r] += grad_full[j]


@njit(cache=True)
def _add_lower(dofs, nloc, hl, band):
    """Add an element's Hessian, its lower triangle packed by rows in ``hl``, to the band of
    K_red = W^T K W (any memory order). The pair (a, b) and its mirror (b, a) land on one
    entry of the lower band; on the diagonal when a and b share a reduced DOF (tied), which
    then receives both."""
    k = 0
    for a in range(nloc):
        ra = dofs[a]
        for b in range(a + 1):
            rb = dofs[b]
            v = hl[k]
            k += 1
            if ra < 0 or rb < 0:
                continue
            if ra > rb:
                band[ra - rb, rb] += v
            elif rb > ra:
                band[rb - ra, ra] += v
            elif a == b:
                band[0, ra] += v
            else:
                band[0, ra] += v + v


def band_slots(dofs, ld):
    """Where the lower triangle of every element's Hessian goes in a Fortran-order band with
    leading dimension ``ld`` (bandwidth + 1), for the element DOFs ``dofs`` of
    `element_dofs`: a tuple of (n_elements, k (k + 1) / 2) int64 arrays, the pairs packed by
    rows as `solver.energies.bending_lower` packs them. Entry 2 s + t: add the value to
    ``band.T.ravel()[s]``, twice when t = 1 (a pair of distinct coordinates sharing one
    reduced DOF: both (a, b) and (b, a) reach that diagonal entry); -1: held, skipped.
    Computed once per system, so that the assembly does no index arithmetic."""
    out = []
    for d in dofs:
        d = np.ascontiguousarray(d, dtype=np.int64)
        k = d.shape[1]
        slots = np.empty((d.shape[0], k * (k + 1) // 2), dtype=np.int64)
        _fill_slots(d, ld, slots)
        out.append(slots)
    return tuple(out)


@njit(cache=True)
def _fill_slots(dofs, ld, slots):
    """`band_slots` of one element array (a compiled loop: computed for every new DOF
    ordering, several per unit)."""
    for e in range(dofs.shape[0]):
        p = 0
        for a in range(dofs.shape[1]):
            ra = dofs[e, a]
            for b in range(a + 1):
                rb = dofs[e, b]
                if ra < 0 or rb < 0:
                    slots[e, p] = -1
                else:
                    lo, hi = min(ra, rb), max(ra, rb)
                    slots[e, p] = 2 * (lo * ld + hi - lo) + (1 if ra == rb and a != b else 0)
                p += 1


@njit(cache=True)
def _add_slots(slots, npairs, hl, flat):
    """Add a packed lower triangle ``hl`` at its `band_slots` ``slots`` of the flat band."""
    for k in range(npairs):
        s = slots[k]
        if s >= 0:
            v = hl[k]
            flat[s >> 1] += v + v if s & 1 else v


def element_dofs(elements, dof_map):
    """Reduced DOF of every local coordinate of every element: (stretch (ne, 4),
    bend (nb, 6), spring (ns, 4)) int arrays, -1 where fixed. Computed once per DOF
    ordering."""
    dof_map = np.ascontiguousarray(dof_map, dtype=np.int64)
    return tuple(_connectivity_dofs(np.ascontiguousarray(conn, dtype=np.int64), dof_map)
                 for conn in (elements[0], elements[2], elements[4]))


@njit(cache=True)
def _connectivity_dofs(conn, dof_map):
    """(n_elements, 2 k): the reduced DOFs (x, z per node, in the element's node order) of
    the elements' nodes ``conn`` (n_elements, k) under ``dof_map`` (a compiled gather: the
    index arithmetic in numpy cost 15 us per ordering)."""
    out = np.empty((conn.shape[0], 2 * conn.shape[1]), dtype=np.int64)
    for e in range(conn.shape[0]):
        for a in range(conn.shape[1]):
            out[e, 2 * a] = dof_map[2 * conn[e, a]]
            out[e, 2 * a + 1] = dof_map[2 * conn[e, a] + 1]
    return out


@njit(cache=True, inline="always")
def _gather(q, nodes, k, x):
    """x = the positions (x, z per node) of an element's first ``k`` ``nodes`` in the flat
    ``q`` (k a constant at each call: the loop unrolls)."""
    for a in range(k):
        x[2 * a] = q[2 * nodes[a]]
        x[2 * a + 1] = q[2 * nodes[a] + 1]


@njit(cache=True)
def assemble_system(q, elements, dofs, band, grad_red, grad_full):
    """Energy (J); writes the reduced band K, reduced gradient and full gradient (N).

    ``q`` is the flat (2 n_nodes,) array of current positions in metres; ``dofs`` comes
    from `element_dofs` for the system's DOF map. Any band of the bandwidth (the systems'
    Fortran-order bands: `assemble_banded`, faster).
    """
    stretch_nodes, stretch_params, bend_nodes, bend_params, spring_nodes, spring_params = elements
    stretch_dofs, bend_dofs, spring_dofs = dofs
    band[:, :] = 0.0
    grad_red[:] = 0.0
    grad_full[:] = 0.0
    energy = 0.0
    x4, g4, h10 = np.empty(4), np.empty(4), np.empty(10)
    x6, g6, h21 = np.empty(6), np.empty(6), np.empty(21)
    for e in range(stretch_nodes.shape[0]):
        nodes = stretch_nodes[e]
        _gather(q, nodes, 2, x4)
        energy += stretch_lower(x4, stretch_params[e, 0], stretch_params[e, 1], g4, h10)
        _add_gradient(nodes, stretch_dofs[e], 4, g4, grad_red, grad_full)
        _add_lower(stretch_dofs[e], 4, h10, band)
    for e in range(bend_nodes.shape[0]):
        nodes = bend_nodes[e]
        _gather(q, nodes, 3, x6)
        energy += bending_lower(x6, bend_params[e, 0], bend_params[e, 1], g6, h21)
        _add_gradient(nodes, bend_dofs[e], 6, g6, grad_red, grad_full)
        _add_lower(bend_dofs[e], 6, h21, band)
    for e in range(spring_nodes.shape[0]):
        nodes = spring_nodes[e]
        _gather(q, nodes, 2, x4)
        k, ox, oz = spring_params[e, 0], spring_params[e, 1], spring_params[e, 2]
        energy += spring_lower(x4, k, ox, oz, g4, h10)
        _add_gradient(nodes, spring_dofs[e], 4, g4, grad_red, grad_full)
        _add_lower(spring_dofs[e], 4, h10, band)
    return energy


@njit(cache=True, inline="always")
def _put(flat, s, v):
    """Add ``v`` at the `band_slots` entry ``s`` of the flat band (twice when s is odd,
    nothing when s < 0)."""
    if s >= 0:
        flat[s >> 1] += v + v if s & 1 else v


@njit(cache=True, inline="always")
def _put_pair(flat, sl, hxx, hxz, hzz):
    """`_add_slots` of the lower triangle of [[H, -H], [-H, H]] (`pair_lower`) at the slots
    ``sl`` (10,) of a two-node element, from its three values."""
    _put(flat, sl[0], hxx)
    _put(flat, sl[1], hxz)
    _put(flat, sl[2], hzz)
    _put(flat, sl[3], -hxx)
    _put(flat, sl[4], -hxz)
    _put(flat, sl[5], hxx)
    _put(flat, sl[6], -hxz)
    _put(flat, sl[7], -hzz)
    _put(flat, sl[8], hxz)
    _put(flat, sl[9], hzz)


@njit(cache=True, inline="always")
def _put_lower21(flat, sl, h):
    """`_add_slots` of a packed lower triangle of 21 (a bending stencil's), the tuple ``h``,
    at the slots ``sl``: written out, with constant indices (a loop over the tuple compiles
    to a jump table, one indirect jump per entry)."""
    _put(flat, sl[0], h[0])
    _put(flat, sl[1], h[1])
    _put(flat, sl[2], h[2])
    _put(flat, sl[3], h[3])
    _put(flat, sl[4], h[4])
    _put(flat, sl[5], h[5])
    _put(flat, sl[6], h[6])
    _put(flat, sl[7], h[7])
    _put(flat, sl[8], h[8])
    _put(flat, sl[9], h[9])
    _put(flat, sl[10], h[10])
    _put(flat, sl[11], h[11])
    _put(flat, sl[12], h[12])
    _put(flat, sl[13], h[13])
    _put(flat, sl[14], h[14])
    _put(flat, sl[15], h[15])
    _put(flat, sl[16], h[16])
    _put(flat, sl[17], h[17])
    _put(flat, sl[18], h[18])
    _put(flat, sl[19], h[19])
    _put(flat, sl[20], h[20])


@njit(cache=True, inline="always")
def _clear_written(band, heights):
    """Zero what the assembly and the factor write of the Fortran-order ``band``
    (`solver.banded.written_extent`): column by column, or the whole band in one sweep when
    that is half of it or more (one memset instead of one per column, 0.7 -> 0.3 us on the
    specimen; a zero outside the envelope stays a zero)."""
    bw = band.shape[0] - 1
    n = band.shape[1]
    total = 0
    for j in range(n):
        total += written_extent(heights, j, bw) + 1
    if 2 * total >= band.size:
        flat = band.T.reshape(band.size)
        flat[:] = 0.0
        return
    for j in range(n):
        for k in range(written_extent(heights, j, bw) + 1):
            band[k, j] = 0.0


@njit(cache=True)
def _stretch_jets(q, stretch_nodes, stretch_params, jets, energy):
    """The stretching terms of every edge (`solver.energies.stretch_jet`) into ``jets``:
    per edge (gx, gz, hxx, hxz, hzz); returns ``energy`` (J) plus theirs, added in edge
    order (the assemblers' running sum)."""
    for e in range(stretch_nodes.shape[0]):
        a = 2 * stretch_nodes[e, 0]
        b = 2 * stretch_nodes[e, 1]
        en, gx, gz, hxx, hxz, hzz = stretch_jet(q[a], q[a + 1], q[b], q[b + 1],
                                                stretch_params[e, 0], stretch_params[e, 1])
        energy += en
        jets[e, 0] = gx
        jets[e, 1] = gz
        jets[e, 2] = hxx
        jets[e, 3] = hxz
        jets[e, 4] = hzz
    return energy


@njit(cache=True)
def _bending_jets(q, bend_nodes, bend_params, jets, energy):
    """The bending terms of every stencil into ``jets``: per stencil (alpha = dE/dphi,
    beta = d2E/dphi2, then the turning angle's P (6), u0, v0, u1, v1 of
    `solver.energies.turning_jet_edges`); returns ``energy`` (J) plus theirs, added in
    stencil order. A stencil whose first edge is the last one's second (along a rod) takes
    its `edge_turn` from it (the same bits: one square root and two divisions fewer)."""
    last0 = -1
    last1 = -1
    a1 = b1 = 0.0
    t1 = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    for e in range(bend_nodes.shape[0]):
        n0 = bend_nodes[e, 0]
        n1 = bend_nodes[e, 1]
        n2 = bend_nodes[e, 2]
        if n0 == last0 and n1 == last1:
            a0 = a1
            b0 = b1
            t0 = t1
        else:
            a0 = q[2 * n1] - q[2 * n0]
            b0 = q[2 * n1 + 1] - q[2 * n0 + 1]
            t0 = edge_turn(a0, b0)
        a1 = q[2 * n2] - q[2 * n1]
        b1 = q[2 * n2 + 1] - q[2 * n1 + 1]
        t1 = edge_turn(a1, b1)
        last0 = n1
        last1 = n2
        jet = turning_jet_edges(a0, b0, t0, a1, b1, t1)
        en, alpha, beta = bending_scales(jet, bend_params[e, 0], bend_params[e, 1])
        energy += en
        jets[e, 0] = alpha
        jets[e, 1] = beta
        for k in range(3, 13):  # P (6), u0, v0, u1, v1
            jets[e, k - 1] = jet[k]
    return energy


@njit(cache=True)
def assemble_banded(q, elements, dofs, slots, dof_map, band, heights, grad_red, grad_full):
    """`assemble_system` into a Fortran-order band whose entries outside the envelope
    ``heights`` (`solver.banded.envelope_heights`) are zero: only what the assembly and the
    factor write (`solver.banded.written_extent`) is cleared. ``slots``: `band_slots` of
    ``dofs`` for this band; ``dof_map`` the system's (full -> reduced DOF, -1 held).
    Energy (J); writes the band, the reduced and the full gradient (N).

    The same operations in the same order as `assemble_system` (the same bits): each
    element's terms go from scalars straight to their slots, with no small arrays between
    (whose reference counts cost more than the arithmetic)."""
    stretch_nodes, stretch_params, bend_nodes, bend_params, spring_nodes, spring_params = elements
    stretch_slots, bend_slots, spring_slots = slots
    _clear_written(band, heights)
    grad_full[:] = 0.0
    flat = band.T.reshape(band.size)  # band[k, j] = flat[j ld + k]
    energy = 0.0
    # each kind in two passes: the elements' terms into ``jets``, then their scatter. In
    # one pass the scatter waits on the long chain of each element's arithmetic and the
    # processor cannot look far enough ahead to overlap the next element's (2.9 us of 12)
    ne = stretch_nodes.shape[0]
    nb = bend_nodes.shape[0]
    jets = np.empty((max(ne, nb), 12))
    energy = _stretch_jets(q, stretch_nodes, stretch_params, jets, energy)
    for e in range(ne):
        a = 2 * stretch_nodes[e, 0]
        b = 2 * stretch_nodes[e, 1]
        gx = jets[e, 0]
        gz = jets[e, 1]
        grad_full[a] += -gx
        grad_full[a + 1] += -gz
        grad_full[b] += gx
        grad_full[b + 1] += gz
        _put_pair(flat, stretch_slots[e], jets[e, 2], jets[e, 3], jets[e, 4])
    energy = _bending_jets(q, bend_nodes, bend_params, jets, energy)
    for e in range(nb):
        i0 = 2 * bend_nodes[e, 0]
        i1 = 2 * bend_nodes[e, 1]
        i2 = 2 * bend_nodes[e, 2]
        alpha = jets[e, 0]
        beta = jets[e, 1]
        jet = (0.0, 0.0, 0.0, jets[e, 2], jets[e, 3], jets[e, 4], jets[e, 5], jets[e, 6],
               jets[e, 7], jets[e, 8], jets[e, 9], jets[e, 10], jets[e, 11])
        grad_full[i0] += alpha * jet[3]
        grad_full[i0 + 1] += alpha * jet[4]
        grad_full[i1] += alpha * jet[5]
        grad_full[i1 + 1] += alpha * jet[6]
        grad_full[i2] += alpha * jet[7]
        grad_full[i2 + 1] += alpha * jet[8]
        _put_lower21(flat, bend_slots[e], turning_lower(jet, alpha, beta))
    for e in range(spring_nodes.shape[0]):
        k = spring_params[e, 0]
        energy += _spring_gradient(q, spring_nodes, spring_params, e, grad_full)
        _put_pair(flat, spring_slots[e], k, 0.0, k)
    _reduce_gradient(dof_map, grad_full, grad_red)
    return energy


@njit(cache=True, inline="always")
def _spring_gradient(q, spring_nodes, spring_params, e, grad_full):
    """Tie spring ``e``'s gradient (N) added into the full gradient at the full state
    ``q``; returns its energy (J). The full and the gradient-only assembly's spring term."""
    a = 2 * spring_nodes[e, 0]
    b = 2 * spring_nodes[e, 1]
    k, ox, oz = spring_params[e, 0], spring_params[e, 1], spring_params[e, 2]
    dx = q[a] - q[b] - ox
    dz = q[a + 1] - q[b + 1] - oz
    grad_full[a] += k * dx
    grad_full[a + 1] += k * dz
    grad_full[b] += -k * dx
    grad_full[b + 1] += -k * dz
    return 0.5 * k * (dx * dx + dz * dz)


@njit(cache=True, inline="always")
def _spring_force(q, nodes, k, ox, oz):
    """dE/dx_b (N) of the tie spring between ``nodes`` in the flat state ``q``:
    E = k/2 |x_a - x_b - offset|^2."""
    a, b = 2 * nodes[0], 2 * nodes[1]
    return -k * (q[a] - q[b] - ox), -k * (q[a + 1] - q[b + 1] - oz)


@njit(cache=True)
def _add_pair_force(rd, gx, gz, weight, out):
    """Add ``weight`` times the gradient (-g, g), g = (gx, gz) (N), of a two-node element
    at its reduced DOFs ``rd`` (4,)."""
    for a in range(4):
        r = rd[a]
        if r >= 0:
            g = gx if (a & 1) == 0 else gz
            out[r] += weight * (g if a >= 2 else -g)


@njit(cache=True)
def stiff_second_difference(q, q_plus, q_minus, elements, dofs, out):
    """The second difference g(q+) + g(q-) - 2 g(q) of the stiff terms' reduced gradient
    (N): stretching and bond springs, whose energies are quadratic in the edge lengths and
    so dominate the path's second-order term (`solver.mgdc`); bending, 10^4-10^6 times
    softer for a thin rod, is left out. Written into ``out`` (n,)."""
    stretch_nodes, stretch_params, _, _, spring_nodes, spring_params = elements
    stretch_dofs, _, spring_dofs = dofs
    out[:] = 0.0
    # gradients only (no Hessians): dE/dx_b = g = -dE/dx_a for both kinds of element
    for e in range(stretch_nodes.shape[0]):
        nodes, rd = stretch_nodes[e], stretch_dofs[e]
        EA, rest = stretch_params[e, 0], stretch_params[e, 1]
        # (the three states written out: a loop over a tuple of arrays costs 3x here)
        gx, gz = stretch_force(q_plus, nodes, EA, rest)
        _add_pair_force(rd, gx, gz, 1.0, out)
        gx, gz = stretch_force(q_minus, nodes, EA, rest)
        _add_pair_force(rd, gx, gz, 1.0, out)
        gx, gz = stretch_force(q, nodes, EA, rest)
        _add_pair_force(rd, gx, gz, -2.0, out)
    for e in range(spring_nodes.shape[0]):
        nodes, rd = spring_nodes[e], spring_dofs[e]
        k, ox, oz = spring_params[e, 0], spring_params[e, 1], spring_params[e, 2]
        gx, gz = _spring_force(q_plus, nodes, k, ox, oz)
        _add_pair_force(rd, gx, gz, 1.0, out)
        gx, gz = _spring_force(q_minus, nodes, k, ox, oz)
        _add_pair_force(rd, gx, gz, 1.0, out)
        gx, gz = _spring_force(q, nodes, k, ox, oz)
        _add_pair_force(rd, gx, gz, -2.0, out)


@njit(cache=True)
def assemble_dead_loads(q, loads, grad_red, grad_full):
    """Energy (J) of the dead loads ``loads`` (the record of the module doc) at the full
    state ``q``; adds their gradient -f (N) into the reduced and the full gradient. No
    stiffness: K is the elastic one. Loaded coordinates are positions (3-D rods: reduced
    position DOFs are unscaled, ``dof_scale`` 1)."""
    full, red, force, ref = loads
    energy = 0.0
    for k in range(full.shape[0]):
        j = full[k]
        e, g = dead_load_terms(q[j], force[k], ref[k])
        energy += e
        grad_full[j] += g
        r = red[k]
        if r >= 0:
            grad_red[r] += g
    return energy


def no_loads():
    """The empty dead-load record (a structure without loads)."""
    none = np.zeros(0, dtype=np.int64)
    return none, none.copy(), np.zeros(0), np.zeros(0)


def load_record(full_dofs, forces, ref, dof_map):
    """The dead-load record of `assemble_dead_loads` for the full DOFs ``full_dofs`` with
    forces ``forces`` (N) and stress-free coordinates ``ref`` (m) under ``dof_map``."""
    full = np.ascontiguousarray(full_dofs, dtype=np.int64)
    red = np.ascontiguousarray(np.asarray(dof_map)[full], dtype=np.int64)
    return (full, red, np.ascontiguousarray(forces, dtype=float),
            np.ascontiguousarray(ref, dtype=float))


def total_energy(q, elements):
    """Total elastic energy (J) of the positions ``q``: the gradient-only assembler
    (`assemble_gradient`, no stiffness) run with every DOF marked fixed."""
    q = np.ascontiguousarray(q, dtype=float)
    held = np.full(q.shape[0], -1, dtype=np.int64)
    return assemble_gradient(q, elements, held, np.zeros(1), np.zeros(q.shape[0]))


@njit(cache=True)
def assemble_gradient(q, elements, dof_map, grad_red, grad_full):
    """`assemble_banded` without the stiffness: the energy (J), the full and the reduced
    gradient (N) at ``q`` (the same bits), the band untouched (a third of the full
    assembly's time: what a state Newton has converged to needs, `solver.system.
    BandedSystem.settle`). ``dof_map``: the system's (full -> reduced DOF, -1 held)."""
    stretch_nodes, stretch_params, bend_nodes, bend_params, spring_nodes, spring_params = elements
    grad_full[:] = 0.0
    energy = 0.0
    # the terms as `assemble_banded` computes them (`_stretch_jets`, `_bending_jets`), their
    # gradients added in the same order
    jets = np.empty((max(stretch_nodes.shape[0], bend_nodes.shape[0]), 12))
    energy = _stretch_jets(q, stretch_nodes, stretch_params, jets, energy)
    for e in range(stretch_nodes.shape[0]):
        a = 2 * stretch_nodes[e, 0]
        b = 2 * stretch_nodes[e, 1]
        grad_full[a] += -jets[e, 0]
        grad_full[a + 1] += -jets[e, 1]
        grad_full[b] += jets[e, 0]
        grad_full[b + 1] += jets[e, 1]
    energy = _bending_jets(q, bend_nodes, bend_params, jets, energy)
    for e in range(bend_nodes.shape[0]):
        alpha = jets[e, 0]
        for c in range(3):
            i = 2 * bend_nodes[e, c]
            grad_full[i] += alpha * jets[e, 2 + 2 * c]
            grad_full[i + 1] += alpha * jets[e, 3 + 2 * c]
    for e in range(spring_nodes.shape[0]):
        energy += _spring_gradient(q, spring_nodes, spring_params, e, grad_full)
    _reduce_gradient(dof_map, grad_full, grad_red)
    return energy
