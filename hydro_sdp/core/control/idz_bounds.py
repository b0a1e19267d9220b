"""
The IDZ's edges where the data leave the model's dead-zone undetermined.

A dead-zone edge below every command the runs held lies somewhere between rest and the
innermost command that moved the joint (:mod:`hydro_sdp.core.model.undetermined`). The
design says which value its IDZ takes there, and why (docs/methods.md section 13.9).

"""

from __future__ import annotations

from dataclasses import replace

from hydro_sdp.core.control.idz import InverseDeadZone
from hydro_sdp.core.control.idz_table import TableInverseDeadZone
from hydro_sdp.core.model.joint_model import JointModel

#: Share of its fastest speed below which the joint barely moves at a command: an edge
#: bounded there is taken at that command.
BARELY = 0.1


def design_edges(model: JointModel) -> tuple[tuple[float, float] | None, tuple[str, ...]]:
    """
    Return the edges the IDZ takes (None: the model's), and why, edge by edge.

    Where the joint barely moved at the end of the bound (:data:`BARELY`), the IDZ's edge
    is that command: the true edge lies inside it, so any over-compensation is held to
    the speed seen there, while the model's own edge would leave a band of commands
    that do nothing. Otherwise the model's value stands, an extrapolation, and is said
    to be one.
    """
    if not model.undetermined or model.dead_zone is None:
        return None, ()
    edges = list(model.dead_zone)
    notes = []
    for entry in model.undetermined:
        value, end = edges[entry.side], entry.moving_end
        span = f'[{entry.bound[0]:.4g}, {entry.bound[1]:.4g}]'
        if entry.motion <= BARELY:
            if (end - value) * (1 if entry.side else -1) > 0.0:
                edges[entry.side] = end
            notes.append(f'{entry.parameter} is undetermined in {span}: the IDZ takes {end:.4g}, '
                         f'where the joint moved at {100 * entry.motion:.0f} % of its fastest '
                         f'(the model extrapolates {value:.4g})')
        else:
            notes.append(f'{entry.parameter} is undetermined in {span}: the IDZ takes the '
                         f"model's extrapolated {value:.4g}; at {end:.4g} the joint already "
                         f'moved at {100 * entry.motion:.0f} % of its fastest')
    return (edges[0], edges[1]), tuple(notes)


def _outer(idz: InverseDeadZone | TableInverseDeadZone,
           edges: tuple[float, float]) -> tuple[float, float]:
    return min(edges[0], idz.dead_zone[0]), max(edges[1], idz.dead_zone[1])


def chord_with_edges_out(idz: InverseDeadZone, edges: tuple[float, float]) -> InverseDeadZone:
    """Return the chord IDZ with its edges moved out to ``edges`` (never in), its slopes kept."""
    low, high = _outer(idz, edges)
    return replace(idz, dead_zone=(low, high), rest=min(max(idz.rest, low), high))


def table_with_edges_out(idz: TableInverseDeadZone,
                         edges: tuple[float, float]) -> TableInverseDeadZone:
    """Return the table with its edges moved out to ``edges``: the points in between dropped."""
    low, high = _outer(idz, edges)
    if (low, high) == idz.dead_zone:
        return idz
    pairs = list(zip(idz.u, idz.v))
    negative = [(u, v) for u, v in pairs if u < 0.0 and v < low] + [(0.0, low)]
    positive = [(0.0, high)] + [(u, v) for u, v in pairs if u > 0.0 and v > high]
    return TableInverseDeadZone.from_branches(
        ([u for u, _ in negative], [v for _, v in negative]),
        ([u for u, _ in positive], [v for _, v in positive]),
        beta=idz.beta, mode=idz.mode, rest=min(max(idz.rest, low), high))
