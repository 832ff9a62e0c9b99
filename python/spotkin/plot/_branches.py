"""Every IK branch of one target side by side (:func:`branches`): a leg's four in side and front views, the
Spot arm's eight and a 3- or 6-joint chain's in 3D, each with its joints and its status."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from numpy.typing import ArrayLike

from .. import Status, body_transform
from ._common import (
    _BLOCKED,
    _VALID,
    SLOT_NAMES,
    _check_fig,
    _equal_3d,
    _frame_axes,
    _label_3d,
    _limits_2d,
    _near,
    _sparse_ticks,
    as_real,
)
from ._solvers import (
    _beyond_limits,
    _default_q,
    _drawable,
    _is_leg,
    _is_solver,
    _joint_labels,
    _joint_origins,
    _revolute,
)

_LEG_JOINTS = ("hip roll", "hip pitch", "knee")


def _slot_names(solver, slots: int) -> tuple[str, ...]:
    """What each of ``ik_all``'s slots means, where the solver's branches have a fixed meaning: a leg's
    (hip normal or flipped, knee back or forward), the Spot arm's (shoulder, elbow, wrist); else
    "solution K"."""
    names = getattr(solver, "slot_names", None)  # the solver's own, where its slots have a fixed meaning
    if names is None and _is_leg(solver):  # a leg's geometry: its slots are a leg's
        names = SLOT_NAMES
    if names is not None and len(names) == slots:
        return tuple(names)
    return tuple(f"solution {k}" for k in range(slots))


def _solve_all(solver, target: ArrayLike):
    """(solutions, target as drawn (3,) point or (4, 4) pose, slot names): every branch by the solver's
    ``ik_all``; a 3-joint solver's target is a point, a 6-joint one's a pose."""
    value = as_real(target, "target", np.float64)
    if not (_is_solver(solver) and _drawable(solver)):
        raise TypeError(
            f"solver must be an sk.Leg, an sk.SpotArm or an sk.Chain, got {type(solver).__name__}"
        )
    if solver.dof == 3:
        if value.shape != (3,):
            raise ValueError(f"target must be one foot or tool point of shape (3,), got {value.shape}")
        sol = solver.ik_all(value)
        return sol, value, _slot_names(solver, sol.q.shape[-2])
    if solver.dof == 6:
        if value.shape not in ((4, 4), (7,)):
            raise ValueError(f"target must be one pose of shape (4, 4) or (7,), got {value.shape}")
        sol = solver.ik_all(value)
        with np.errstate(all="ignore"):
            pose = (
                body_transform(np.where(np.isfinite(value), value, np.nan)) if value.shape == (7,) else value
            )
        return sol, pose, _slot_names(solver, sol.q.shape[-2])
    raise ValueError(
        f"branches draws 3- and 6-joint chains (closed-form IK), this chain has {solver.dof} joints"
    )


def _panel_state(sol, slot: int, solver, names) -> tuple[str, bool, bool]:
    """(text, exists, valid) of one slot."""
    if not sol.exists[slot]:
        return "no solution", False, False
    if sol.valid[slot]:
        return "valid", True, True
    outside = _beyond_limits(sol.q[slot], solver.limits, _revolute(solver))
    joints = ", ".join(name for name, out in zip(names, outside) if out) or "a joint"
    return f"beyond limits: {joints}", True, False


def _q_text(solver, q: np.ndarray) -> str:
    """A branch's joints as its panel prints them: revolute joints in degrees (0.1°), prismatic ones in
    metres (1 mm)."""
    values = [f"{math.degrees(v):.1f}°" if turn else f"{v:.3f} m" for v, turn in zip(q, _revolute(solver))]
    return "q = (" + ", ".join(values) + ")"


def _q_label(ax, solver, q: np.ndarray, slot: int, valid: bool) -> None:
    """The branch's joints (:func:`_q_text`) at the top of its panel (a 3D panel), or just above it
    (below its title, a 2D panel), id ``"q:SLOT"``."""
    three_d = getattr(ax, "name", "") == "3d"
    (ax.text2D if three_d else ax.text)(
        0.5,
        1.0 if three_d else 1.015,
        _q_text(solver, q),
        transform=ax.transAxes,
        ha="center",
        va="top" if three_d else "bottom",
        fontsize=6.5,
        color=_VALID if valid else "#525252",
        gid=f"q:{slot}",
    )


def branches(solver, target: ArrayLike, fig=None) -> Figure:
    """Every IK branch of one target, side by side, with its status.

    ``solver`` is an :class:`spotkin.Leg` (``target``: a foot point (3,) in the leg frame; the 4
    slots, each in a side view x–z and a front view y–z), an :class:`spotkin.SpotArm` (``target``: a
    tool pose (4, 4) or (7,) in the body frame; the 8 slots in 3D), or an :class:`spotkin.Chain` with a
    closed form: 3 joints (``target`` (3,)) or 6 (``target`` (4, 4) or (7,)). The branches are the
    solver's ``ik_all`` (the interface every solver shares). Valid branches are drawn solid and marked "✓";
    branches beyond the joint limits dashed, naming the joints; a slot without a solution says so. The
    figure's title gives the status (:class:`spotkin.Status`): an unreachable target, or NaN in it, is
    drawn with its status and no branch.

    ``fig``: a Figure to draw in (its contents are replaced); default: a new figure. Returns the figure.
    Each branch's line has the id ``"slot:K"``.

    Raises ``TypeError`` for another solver, non-numeric targets or a non-Figure ``fig``, and
    ``ValueError`` for a target of another shape (one target only) or beyond 1e6 from the origin, or a
    chain without a closed form.
    """
    sol, drawn_target, names = _solve_all(solver, target)
    point = drawn_target if drawn_target.shape == (3,) else drawn_target[:3, 3]
    _near(point[np.isfinite(point)], "target", "the target")
    fig = _check_fig(fig)
    arm = solver.dof != 3  # a pose target: the branches in 3D
    if fig is None:
        fig = plt.figure(figsize=(12, 6.5) if not arm else (13, 7))
    if arm:
        _branches_arm(fig, solver, sol, drawn_target, names)
        what = f"tool position ({', '.join(f'{v:.3f}' for v in drawn_target[:3, 3])}) m"
    else:
        if _is_leg(solver):  # side and front views of the leg
            _branches_leg(fig, solver, sol, drawn_target, names)
        else:
            _branches_chain3(fig, solver, sol, drawn_target, names)
        what = f"target ({', '.join(f'{v:.3f}' for v in drawn_target)}) m"
    status = Status(int(sol.status))
    label = getattr(solver, "name", None) or type(solver).__name__  # a leg's name
    count = f"{int(sol.valid.sum())} of {int(sol.exists.sum())} solutions within the limits"
    fig.suptitle(f"{label} IK, every branch: {what}; status {status.name}, {count}", fontsize=10)
    fig.subplots_adjust(bottom=0.12, top=0.86, wspace=0.35, hspace=0.45)
    return fig


def _branches_leg(fig, solver, sol, target: np.ndarray, names) -> None:
    slots = sol.q.shape[0]
    axes = fig.subplots(2, slots, squeeze=False)
    points = [_joint_origins(solver, sol.q[k])[0] for k in range(slots) if sol.exists[k]]
    everything = np.concatenate([np.zeros((1, 3)), target[None], *points]) if points else target[None]
    h = abs(solver.hip_offset)
    circle = h * np.array([[math.cos(t), math.sin(t)] for t in np.linspace(0, 2 * math.pi, 121)])
    views = (((0, 2), "side view (x–z)", "x (m)"), ((1, 2), "front view (y–z)", "y (m)"))
    for row, ((i, j), view, xlabel) in enumerate(views):
        low, high = _limits_2d(
            np.concatenate([everything[:, [i, j]], circle if i == 1 else np.zeros((0, 2))])
        )
        for slot in range(slots):
            ax = axes[row, slot]
            text, exists, valid = _panel_state(sol, slot, solver, _LEG_JOINTS)
            if i == 0:
                ax.axhline(0.0, color="black", linewidth=0.8, linestyle="-.", label="hip-roll axis")
            else:
                ax.plot(*circle.T, color="black", linewidth=0.8, linestyle=":", label="hip-roll cylinder")
            if exists:
                p = _joint_origins(solver, sol.q[slot])[0][:, [i, j]]
                ax.plot(
                    *p.T,
                    color=_VALID if valid else _BLOCKED,
                    linestyle="-" if valid else "--",
                    linewidth=2.5 if valid else 1.8,
                    marker="o",
                    markerfacecolor="white",
                    label="valid branch" if valid else "beyond the limits",
                    gid=f"slot:{slot}",
                )
            else:
                ax.text(0.5, 0.5, "no solution", transform=ax.transAxes, ha="center", va="center", fontsize=9)
            ax.plot(
                *target[[i, j]],
                linestyle="none",
                marker="*",
                markersize=13,
                markerfacecolor="none",
                markeredgecolor="black",
                label="target",
            )
            ax.plot(0.0, 0.0, linestyle="none", marker="+", markersize=9, color="black")
            ax.set_xlim(low[0], high[0])
            ax.set_ylim(low[1], high[1])
            ax.set_aspect("equal", adjustable="box")
            ax.tick_params(labelsize=7)
            ax.set_xlabel(xlabel, fontsize=8)
            if slot == 0:
                ax.set_ylabel(f"{view}\nz (m)", fontsize=8)
            if row == 0:
                mark = "✓ " if valid else ""
                ax.set_title(
                    f"slot {slot}: {names[slot]}\n{mark}{text}",
                    fontsize=8,
                    fontweight="bold" if valid else "normal",
                    pad=14,
                )
                if exists:
                    _q_label(ax, solver, sol.q[slot], slot, valid)
    handles = [
        Line2D(
            [], [], color=_VALID, linewidth=2.5, marker="o", markerfacecolor="white", label="valid branch"
        ),
        Line2D(
            [],
            [],
            color=_BLOCKED,
            linestyle="--",
            linewidth=1.8,
            marker="o",
            markerfacecolor="white",
            label="branch beyond the joint limits",
        ),
        Line2D(
            [],
            [],
            linestyle="none",
            marker="*",
            markersize=12,
            markerfacecolor="none",
            markeredgecolor="black",
            label="target foot",
        ),
        Line2D([], [], color="black", linestyle="-.", linewidth=0.8, label="hip-roll axis"),
        Line2D([], [], color="black", linestyle=":", linewidth=0.8, label="hip-roll cylinder (singular)"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8, frameon=False)


def _branches_arm(fig, solver, sol, T: np.ndarray, names) -> None:
    slots = sol.q.shape[0]
    columns = min(4, slots)
    rows = -(-slots // columns)
    joint_names = _joint_labels(solver)
    points = {k: _joint_origins(solver, sol.q[k])[0] for k in range(slots) if sol.exists[k]}
    base = _joint_origins(solver, _default_q(solver))[0][0]
    cloud = [base[None], T[:3, 3][None], *points.values()]
    cloud = np.concatenate(cloud)
    cloud = cloud[np.isfinite(cloud).all(axis=1)]
    span = float(np.ptp(cloud, axis=0).max()) if len(cloud) else 1.0
    for slot in range(slots):
        ax = fig.add_subplot(rows, columns, slot + 1, projection="3d")
        text, exists, valid = _panel_state(sol, slot, solver, joint_names)
        if exists:
            p = points[slot]
            ax.plot(
                *p.T,
                color=_VALID if valid else _BLOCKED,
                linestyle="-" if valid else "--",
                linewidth=2.5 if valid else 1.8,
                marker="s",
                markersize=3.5,
                markerfacecolor="white",
                gid=f"slot:{slot}",
            )
            hand = solver.fk(sol.q[slot])
            _frame_axes(ax, hand, 0.12 * span, "-", "hand")
        else:
            ax.text2D(0.5, 0.5, "no solution", transform=ax.transAxes, ha="center", va="center", fontsize=9)
        _frame_axes(ax, T, 0.2 * span, ":", "target")
        ax.plot(*base[:, None], linestyle="none", marker="^", markersize=7, color="black")
        _equal_3d(ax, cloud)
        _label_3d(ax, 7)
        ax.tick_params(labelsize=6)
        _sparse_ticks(ax)
        if exists:
            _q_label(ax, solver, sol.q[slot], slot, valid)
        mark = "✓ " if valid else ""
        ax.set_title(
            f"slot {slot}: {names[slot]}\n{mark}{text}", fontsize=8, fontweight="bold" if valid else "normal"
        )
    handles = [
        Line2D(
            [], [], color=_VALID, linewidth=2.5, marker="s", markerfacecolor="white", label="valid solution"
        ),
        Line2D(
            [],
            [],
            color=_BLOCKED,
            linestyle="--",
            linewidth=1.8,
            marker="s",
            markerfacecolor="white",
            label="solution beyond the joint limits",
        ),
        Line2D([], [], color="black", linestyle=":", label="target frame (x, y, z)"),
        Line2D([], [], color="black", linestyle="-", label="the solution's tool frame"),
        Line2D([], [], color="black", linestyle="none", marker="^", label="base (mount)"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=5, fontsize=8, frameon=False)


def _branches_chain3(fig, solver, sol, target: np.ndarray, names) -> None:
    slots = sol.q.shape[0]
    joint_names = _joint_labels(solver)
    points = {k: _joint_origins(solver, sol.q[k])[0] for k in range(slots) if sol.exists[k]}
    base = _joint_origins(solver, _default_q(solver))[0][0]  # the base frame's origin
    cloud = np.concatenate([base[None], target[None], *points.values()])
    cloud = cloud[np.isfinite(cloud).all(axis=1)]
    for slot in range(slots):
        ax = fig.add_subplot(1, slots, slot + 1, projection="3d")
        text, exists, valid = _panel_state(sol, slot, solver, joint_names)
        if exists:
            ax.plot(
                *points[slot].T,
                color=_VALID if valid else _BLOCKED,
                linestyle="-" if valid else "--",
                linewidth=2.5 if valid else 1.8,
                marker="o",
                markerfacecolor="white",
                gid=f"slot:{slot}",
            )
        else:
            ax.text2D(0.5, 0.5, "no solution", transform=ax.transAxes, ha="center", va="center", fontsize=9)
        ax.plot(
            *target[:, None],
            linestyle="none",
            marker="*",
            markersize=13,
            markerfacecolor="none",
            markeredgecolor="black",
        )
        ax.plot(*base[:, None], linestyle="none", marker="^", markersize=7, color="black")
        _equal_3d(ax, cloud)
        _label_3d(ax, 7)
        ax.tick_params(labelsize=6)
        _sparse_ticks(ax)
        if exists:
            _q_label(ax, solver, sol.q[slot], slot, valid)
        mark = "✓ " if valid else ""
        ax.set_title(f"{names[slot]}\n{mark}{text}", fontsize=8, fontweight="bold" if valid else "normal")
    handles = [
        Line2D(
            [], [], color=_VALID, linewidth=2.5, marker="o", markerfacecolor="white", label="valid solution"
        ),
        Line2D(
            [],
            [],
            color=_BLOCKED,
            linestyle="--",
            linewidth=1.8,
            marker="o",
            markerfacecolor="white",
            label="solution beyond the joint limits",
        ),
        Line2D(
            [],
            [],
            linestyle="none",
            marker="*",
            markersize=12,
            markerfacecolor="none",
            markeredgecolor="black",
            label="target",
        ),
        Line2D([], [], color="black", linestyle="none", marker="^", label="base"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8, frameon=False)
