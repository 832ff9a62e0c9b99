"""The fuzz registry's entries for ``spotkin.plot`` (issue 18), the optional pictures (matplotlib).

``tests/fuzz/registry.py`` calls :func:`register_entries` once its own entries are made; without
matplotlib nothing is registered (and nothing of ``spotkin.plot`` is public there either). The workers
draw with the Agg backend, in memory; every case closes its figures.

Each function is called on real robots (Spot, Spot from its URDF, Go2, the six-legged robot), legs, arms,
chains, trajectories and a walk of Go2 in the simulator (when spotkin[sim] is installed), with hostile
poses, joints, targets, options, axes and figures. The probes read the drawings back: the drawn feet are
``body_fk``'s (of the walk's recorded pose and joints for its animation), each drawn branch is one that
``ik_all`` finds, the map's counts are ``ik_all``'s at sampled pixels, the curves are the trajectory's own
samples, the reachability's scatter is its reachable points and its robot stands on the feet it was given.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

import spotkin as sk

from .entry import register, seq_slot
from .objects import ROBOT_ARMS, STANCE_HEIGHT
from .outputs import close, describe
from .slots import ACCEPT, EITHER, REJECT, Arg, Array, Choice, Custom, Flag, Int, Real

PLOT_ARM_Q = np.array([0.0, -1.2, 1.9, 0.0, 0.4, 0.0])


def _pyplot():
    """matplotlib.pyplot on the Agg backend: the workers draw in memory only."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _close_figures(c):
    _pyplot().close("all")


def _gid_data(fig, gid):
    """(m, 3) (3D) or (m, 2) data of the artist with this id, or None."""
    for ax in fig.axes:
        for artist in ax.get_children():
            if artist.get_gid() == gid:
                if hasattr(artist, "get_data_3d"):
                    return np.array(artist.get_data_3d(), dtype=np.float64).T
                return np.asarray(artist.get_xydata(), dtype=np.float64)
    return None


def register_entries() -> None:
    try:
        from matplotlib.animation import FuncAnimation
        from matplotlib.figure import Figure

        from spotkin import plot
    except ImportError:  # the spotkin[plot] extra is not installed: spotkin.plot is not public here
        return
    _pyplot()

    def const(value, expect=ACCEPT, why=""):
        return lambda c, r, b: Arg(value(c) if callable(value) else value, expect, why)

    def axes_table(three_d):
        def axes(projection):
            return lambda c: _pyplot().figure(figsize=(3, 2)).add_subplot(projection=projection)

        return {
            "3d": const(axes("3d"), ACCEPT if three_d else REJECT, "" if three_d else "value"),
            "2d": const(axes(None), REJECT if three_d else ACCEPT, "value" if three_d else ""),
            "none": const(None),
            "figure": const(lambda c: _pyplot().figure(figsize=(3, 2)), REJECT, "type"),
            "str": const("ax", REJECT, "type"),
        }

    fig_table = {
        "figure": const(lambda c: _pyplot().figure(figsize=(4, 3))),
        "none": const(None),
        "axes": const(lambda c: _pyplot().figure(figsize=(3, 2)).add_subplot(), REJECT, "type"),
        "str": const("fig", REJECT, "type"),
    }

    def robot_table(key):
        return {
            "valid": const(lambda c: c.robot(key)),
            "leg": const(lambda c: c.leg, REJECT, "type"),
            "str": const("spot", REJECT, "type"),
            "none": const(None, REJECT, "type"),
        }

    def feet_probe(key, fig_of, pose_of, q_of):
        def probe(result, kw, c):
            fig = fig_of(result)
            if not isinstance(fig, Figure):
                return f"not a drawing: {describe(result)}"
            robot = c.robot(key)
            pose, q = pose_of(kw), q_of(kw)
            if pose is None or q is None:
                nominal = plot._nominal_stance(robot)
                pose = nominal[0] if pose is None else pose
                q = nominal[1] if q is None else q
            want = robot.body_fk(
                np.asarray(pose, np.float64), np.asarray(q, np.float64), kw.get("seq", "XYZ")
            )
            view = kw.get("view", "3d")
            if view != "3d":  # a 2D view draws the feet's projection
                want = want[:, list({"side": (0, 2), "front": (1, 2), "top": (0, 1)}[view])]
            got = _gid_data(fig, "feet")
            if got is None or not close(got, want, False):
                return f"drawn feet {describe(got)} are not body_fk's {describe(want)}"
            return None

        return probe

    def view_axes(plan):
        """A 2D view draws into a 2D Axes and refuses a 3D one (the other way round for "3d")."""
        flat = plan["view"] in ("choice:side", "choice:front", "choice:top")
        if flat and plan["ax"] == "3d":
            return REJECT
        if flat and plan["ax"] == "2d":
            return ACCEPT
        return None

    # plot.robot on Spot (SpotArm), Spot from its URDF (a Chain arm), Go2 and the hexapod (no arm)
    for key in ("spot", "spot_urdf", "go2", "hexapod"):
        arm = ROBOT_ARMS[key]
        height = STANCE_HEIGHT[key]
        if arm:
            q_arm = Array("q_arm", lambda c: PLOT_ARM_Q, optional=True, default="omit")
        else:
            q_arm = Custom(
                "q_arm", {"none": const(None), "given": const(PLOT_ARM_Q, REJECT, "value")}, default="omit"
            )
        register(
            name=f"plot.robot[{key}]",
            covers="spotkin.plot.robot",
            call=lambda c, **k: plot.robot(**k),
            slots=[
                Custom("robot", robot_table(key)),
                Array(
                    "body_pose", lambda c, h=height: [0.02, -0.01, h - 0.02, 0.05, -0.1, 0.2], optional=True
                ),
                Array("q", lambda c, key=key: c.nominal(key), optional=True),
                q_arm,
                seq_slot(),
                Custom("ax", axes_table(True), default="omit"),
                Custom(
                    "title",
                    {"text": const("a title"), "none": const(None), "int": const(3, REJECT, "type")},
                    default="omit",
                ),
                Choice("view", "3d", ("3d", "side", "front", "top"), default="omit"),
            ],
            probe=feet_probe(key, lambda fig: fig, lambda kw: kw.get("body_pose"), lambda kw: kw.get("q")),
            pair_rule=view_axes,
            after=_close_figures,
            combos=(),
            pairs=8 if key in ("spot", "go2") else 4,
        )

    # plot.branches: legs (3,) targets; arms and 6R chains (4, 4) targets
    def branches_probe(solve):
        def probe(fig, kw, c):
            if not isinstance(fig, Figure):
                return f"not a Figure: {describe(fig)}"
            solver, target = kw["solver"], np.asarray(kw["target"], dtype=np.float64)
            sol = solve(solver, target)
            drawn = sorted(  # a leg's slot is drawn twice (side and front views)
                {
                    int(line.get_gid()[5:])
                    for ax in fig.axes
                    for line in ax.get_lines()
                    if (line.get_gid() or "").startswith("slot:")
                }
            )
            if drawn != sorted(set(np.flatnonzero(sol.exists).tolist())):
                return f"slots drawn {drawn}, but the existing ones are {np.flatnonzero(sol.exists).tolist()}"
            return None

        return probe

    def solve_point(solver, p):
        return solver.ik_all(p)  # every solver's branches (the solver interface)

    def solve_pose(solver, T):
        return solver.ik_all(T)

    def poke(value):
        def make(c, v):
            v.reshape(-1)[0] = value
            return v

        return make

    drawn_anyway = {
        "nan": (poke(math.nan), ACCEPT, ""),
        "inf": (poke(math.inf), ACCEPT, ""),
    }  # status in the title
    register(
        name="plot.branches[leg]",
        covers="spotkin.plot.branches",
        call=lambda c, **k: plot.branches(**k),
        slots=[
            Custom(
                "solver",
                {
                    "valid": const(lambda c: c.leg),
                    "go2": const(lambda c: c.robot("go2").legs[1]),
                    "hexapod": const(lambda c: c.robot("hexapod").legs[3]),
                    "chain3": const(lambda c: c.chain("mdh3")),
                    "chain2": const(lambda c: sk.Chain.from_dh([(0, 0.3, 0, 0, 0)] * 2), REJECT, "value"),
                    "str": const("leg", REJECT, "type"),
                    "none": const(None, REJECT, "type"),
                },
            ),
            Array("target", lambda c: c.leg.fk([0.05, 1.04, -1.8]), extra=drawn_anyway),
            Custom("fig", fig_table, default="omit"),
        ],
        probe=branches_probe(solve_point),
        after=_close_figures,
        combos=(),
        pairs=8,
    )
    register(
        name="plot.branches[arm]",
        covers="spotkin.plot.branches",
        call=lambda c, **k: plot.branches(**k),
        slots=[
            Custom(
                "solver",
                {
                    "valid": const(lambda c: c.arm),
                    "chain6": const(lambda c: c.chain("mdh6")),
                    "urdf_arm": const(lambda c: c.robot("spot_urdf").arm),
                    "leg": const(lambda c: c.leg, REJECT, "value"),  # a (4, 4) target for a leg
                    "str": const("arm", REJECT, "type"),
                },
            ),
            Array("target", lambda c: c.arm.fk([0.4, -1.2, 1.9, 0.3, -0.6, 0.8]), extra=drawn_anyway),
            Custom("fig", fig_table, default="omit"),
        ],
        probe=branches_probe(solve_pose),
        after=_close_figures,
        combos=(),
        pairs=8,
    )

    # plot.workspace: the map's counts against ik_all at sampled pixels
    def workspace_probe(fig, kw, c):
        if not isinstance(fig, Figure):
            return f"not a Figure: {describe(fig)}"
        solver = kw["solver"]
        ax = next(a for a in fig.axes if a.images)
        counts = np.asarray(ax.images[0].get_array())
        n = counts.shape[0]
        i, j, k = {"xz": (0, 2, 1), "yz": (1, 2, 0), "xy": (0, 1, 2)}[kw.get("plane", "xz")]
        offset = kw.get("offset")
        if offset is None:
            leg = solver if isinstance(solver, sk.Leg) else None
            offset = (
                0.0
                if leg is None
                else {"xz": leg.hip_offset, "yz": leg.a[0], "xy": -0.75 * leg.reach[1]}[kw.get("plane", "xz")]
            )
        u, v = np.linspace(*ax.get_xlim(), n), np.linspace(*ax.get_ylim(), n)
        rows, cols = np.arange(n) % n, (np.arange(n) * 7) % n
        points = np.empty((n, 3))
        points[:, i], points[:, j], points[:, k] = u[cols], v[rows], float(offset)
        sol = solve_point(solver, points)
        valid = sol.valid.sum(axis=-1)
        want = np.where(valid > 0, np.minimum(valid, 3), np.where(sol.exists.any(axis=-1), -1, -2))
        if not np.array_equal(counts[rows, cols], want):
            return f"map counts {counts[rows, cols].tolist()} are not ik_all's {want.tolist()}"
        return None

    register(
        name="plot.workspace",
        covers="spotkin.plot.workspace",
        call=lambda c, **k: plot.workspace(**k),
        slots=[
            Custom(
                "solver",
                {
                    "valid": const(lambda c: c.leg),
                    "go2": const(lambda c: c.robot("go2").legs[0]),
                    "chain3": const(lambda c: c.chain("dh3")),
                    "chain6": const(lambda c: c.chain("mdh6"), REJECT, "value"),
                    "arm": const(lambda c: c.arm, REJECT, "value"),  # a 6-joint chain
                    "str": const("leg", REJECT, "type"),
                },
            ),
            Choice("plane", "xz", ("xz", "yz", "xy"), default="omit"),
            Real("offset", 0.11, "finite", optional=True, default="omit"),
            Int("resolution", 12, 2, 1001),
            Array("extent", lambda c: [-0.7, 0.7, -0.8, 0.6], optional=True, default="omit"),
            Custom("ax", axes_table(False), default="omit"),
        ],
        probe=workspace_probe,
        after=_close_figures,
        combos=(),
        pairs=12,
    )

    # plot.trajectory: point-to-point motions and Cartesian paths
    def trajectory_probe(fig, kw, c):
        if not isinstance(fig, Figure):
            return f"not a Figure: {describe(fig)}"
        traj = kw["traj"]
        t = kw.get("t")
        t = np.linspace(0.0, traj.duration, 400) if t is None else np.asarray(t, dtype=np.float64)
        if isinstance(traj, sk.trajectory.PointToPoint):
            got, want = _gid_data(fig, "q:0"), traj.sample(t)[0][:, 0]
        else:
            got, want = _gid_data(fig, "x"), traj.sample(t)[:, 0, 3]
        if got is None or not close(got[:, 1], want, False) or not close(got[:, 0], t, False):
            return f"the curve {describe(got)} is not the trajectory's samples {describe(want)}"
        return None

    def cartesian_extras(plan):
        if plan["traj"] in ("linear", "via") and (
            plan["limits"] not in ("omit", "none") or plan["names"] not in ("omit", "none")
        ):
            return REJECT
        return None

    register(
        name="plot.trajectory",
        covers="spotkin.plot.trajectory",
        call=lambda c, **k: plot.trajectory(**k),
        slots=[
            Custom(
                "traj",
                {
                    "valid": const(lambda c: c.p2p("trapezoid")),
                    "cubic": const(lambda c: c.p2p("cubic")),
                    "quintic": const(lambda c: c.p2p("quintic")),
                    "linear": const(lambda c: c.path("linear")),
                    "via": const(lambda c: c.path("via")),
                    "str": const("traj", REJECT, "type"),
                    "array": const(np.zeros((3, 3)), REJECT, "type"),
                },
            ),
            Array(
                "t",
                lambda c: np.linspace(-0.1, 2.0, 7),
                optional=True,
                default="omit",
                extra={"wrong_shape": (lambda c, v: np.linspace(0.0, 1.0, 8), ACCEPT, "")},  # any count
            ),
            Array(
                "limits",
                lambda c: [(-1.0, 1.0), (-2.0, 2.0), (-3.0, 3.0)],
                inf_ok=True,
                optional=True,
                default="omit",
            ),
            Custom(
                "names",
                {
                    "three": const(("hx", "hy", "kn")),
                    "list": const(["a", "b", "c"]),
                    "none": const(None),
                    "str": const("abc", REJECT, "type"),
                    "ints": const((1, 2, 3), REJECT, "type"),
                    "two": const(("a", "b"), REJECT, "value"),
                },
                default="omit",
            ),
            Custom("fig", fig_table, default="omit"),
        ],
        probe=trajectory_probe,
        pair_rule=cartesian_extras,
        after=_close_figures,
        combos=(),
        pairs=12,
    )

    # plot.animate: three frames of Spot on a small body path
    def animate_poses(c):
        return np.array(
            [
                [0.0, 0.0, 0.5, 0.0, 0.0, 0.0],
                [0.02, 0.01, 0.48, 0.05, -0.05, 0.08],
                [0.01, -0.02, 0.49, -0.05, 0.05, 0.0],
            ]
        )

    def rendered(anim):
        """The animation's figure. The harness drops the animation unplayed on purpose: marked as
        started, so that matplotlib does not warn when it is collected (in a later case)."""
        if not isinstance(anim, FuncAnimation):
            return None
        anim._draw_was_started = True
        return anim.figure

    register(
        name="plot.animate",
        covers="spotkin.plot.animate",
        call=lambda c, **k: plot.animate(**k),
        slots=[
            Custom("robot", robot_table("spot")),
            Array("body_poses", animate_poses),
            Array("q", lambda c: np.tile(c.nominal("spot"), (3, 1))),
            Array("q_arm", lambda c: np.tile(PLOT_ARM_Q, (3, 1)), optional=True, default="omit"),
            seq_slot(),
            Real("interval", 100.0, default="omit"),
            Custom("fig", fig_table, default="omit"),
        ],
        probe=feet_probe(
            "spot",
            rendered,
            lambda kw: np.asarray(kw["body_poses"], dtype=np.float64)[0],
            lambda kw: np.asarray(kw["q"], dtype=np.float64)[0],
        ),
        after=_close_figures,
        combos=(),
        pairs=8,
    )

    # plot.gait_diagram and plot.foot_paths: a short trot of Go2
    def trot(c):
        return c.robot("go2").plan_gait("trot", velocity=[0.3, 0.0, 0.0], duration=0.4, rate=50)

    def diagram_probe(fig, kw, c):
        if not isinstance(fig, Figure):
            return f"not a Figure: {describe(fig)}"
        contact = np.asarray(kw["contact"], dtype=bool)
        bars = next((a for ax in fig.axes for a in ax.get_children() if a.get_gid() == "stance:0"), None)
        if bars is None:
            return "no bars for the first leg"
        runs = int(np.count_nonzero(np.diff(np.r_[0, contact[:, 0].astype(int), 0]) == 1))
        if len(bars.get_paths()) != runs:
            return f"{len(bars.get_paths())} bars for {runs} stances"
        return None

    legs_table = {
        "names": const(("FL", "FR", "RL", "RR")),
        "none": const(None),
        "str": const("FLFRRLRR", REJECT, "type"),
        "two": const(("a", "b"), REJECT, "value"),
        "ints": const((1, 2, 3, 4), REJECT, "type"),
    }
    register(
        name="plot.gait_diagram",
        covers="spotkin.plot.gait_diagram",
        call=lambda c, **k: plot.gait_diagram(**k),
        slots=[
            Custom(
                "contact",
                {
                    "valid": const(lambda c: trot(c).contact),
                    "ints": const(lambda c: trot(c).contact.astype(np.int64)),
                    "floats": const(lambda c: trot(c).contact.astype(float), REJECT, "type"),
                    "one_leg": const(lambda c: trot(c).contact[:, :1]),
                    "flat": const(lambda c: trot(c).contact[:, 0], REJECT, "value"),
                    "empty": const(np.zeros((0, 4), dtype=bool), REJECT, "value"),
                    "none": const(None, REJECT, "type"),
                },
            ),
            Array("t", lambda c: trot(c).t, optional=True, default="omit"),
            Custom("legs", legs_table, default="omit"),
            Custom(
                "measured",
                {
                    "names": const(lambda c: trot(c).contact),
                    "none": const(None),
                    "short": const(lambda c: trot(c).contact[:3], REJECT, "value"),
                    "floats": const(lambda c: trot(c).contact.astype(float), REJECT, "type"),
                },
                default="omit",
            ),
            Custom("ax", axes_table(False), default="omit"),
            Custom(
                "title",
                {"text": const("a title"), "none": const(None), "int": const(3, REJECT, "type")},
                default="omit",
            ),
        ],
        probe=diagram_probe,
        pair_rule=lambda plan: (  # one leg's contacts with four legs' names or measured contacts
            REJECT if plan["contact"] == "one_leg" and "names" in (plan["legs"], plan["measured"]) else None
        ),
        after=_close_figures,
        combos=(),
        pairs=12,
    )

    def paths_probe(fig, kw, c):
        if not isinstance(fig, Figure):
            return f"not a Figure: {describe(fig)}"
        robot = kw["robot"]
        q = np.asarray(kw["q"], dtype=np.float64)
        leg = robot.legs[0]
        names = list(robot.leg_joint_names)
        feet = np.asarray(leg.fk(q[:, [names.index(j) for j in leg.joint_names]])) - leg.a
        got = _gid_data(fig, "path:0")
        if got is None or not close(got, feet[:, [0, 2]], False):
            return f"the first path {describe(got)} is not the foot's {describe(feet)}"
        return None

    register(
        name="plot.foot_paths",
        covers="spotkin.plot.foot_paths",
        call=lambda c, **k: plot.foot_paths(**k),
        slots=[
            Custom("robot", robot_table("go2")),
            Array("q", lambda c: trot(c).q),
            Custom("ax", axes_table(False), default="omit"),
            Custom(
                "title",
                {"text": const("a title"), "none": const(None), "int": const(3, REJECT, "type")},
                default="omit",
            ),
        ],
        probe=paths_probe,
        after=_close_figures,
        combos=(),
        pairs=8,
    )

    # plot.walk_animation: a short trot of Go2 in the simulator (spotkin[sim]); without MuJoCo there is no
    # SimResult to give it, and every call is refused (a plan in its place)
    try:
        from spotkin import sim
    except ImportError:
        sim = None

    def simulated(c, record=True):
        def make():
            go2 = c.robot("go2")
            return sim.run(
                go2, sk.GaitController(go2, "trot"), duration=0.2, velocity=(0.2, 0.0, 0.0), record=record
            )

        return c._get(("plot-walk", record), make)

    def poked_q(c):
        result = simulated(c)
        q = result.q.copy()
        q[1, 0] = math.nan
        return dataclasses.replace(result, q=q)

    if sim is not None:
        results = {
            "valid": const(simulated),
            "unrecorded": const(lambda c: simulated(c, record=False), REJECT, "value"),
            "fewer_joints": const(
                lambda c: dataclasses.replace(simulated(c), q=simulated(c).q[:, :9]), REJECT, "value"
            ),
            "nan_q": const(poked_q, REJECT, "value"),
        }
    else:
        results = {"valid": const(lambda c: trot(c), REJECT, "type")}
    results.update({"plan": const(trot, REJECT, "type"), "str": const("walk", REJECT, "type")})
    results["none"] = const(None, REJECT, "type")

    def walk_probe(anim, kw, c):
        fig = rendered(anim)
        if fig is None:
            return f"not an animation: {describe(anim)}"
        result, robot, tick = kw["result"], kw["robot"], int(anim.ticks[0])
        pose = np.concatenate([result.position[tick], result.quaternion[tick]])  # [x, y, z, qx, qy, qz, qw]
        want = robot.body_fk(pose, result.q[tick])
        view = str(kw.get("view", "3d"))
        if view != "3d":  # a 2D view draws the feet's projection
            want = want[:, list({"side": (0, 2), "front": (1, 2), "top": (0, 1)}[view])]
        got = _gid_data(fig, "feet")
        if got is None or not close(got, want, False):
            return f"drawn feet {describe(got)} are not the recorded walk's {describe(want)}"
        return None

    walk_robots = robot_table("go2")
    walk_robots["hexapod"] = const(lambda c: c.robot("hexapod"), REJECT, "value")  # another robot's walk
    register(
        name="plot.walk_animation",
        covers="spotkin.plot.walk_animation",
        call=lambda c, **k: plot.walk_animation(**k),
        slots=[
            Custom("robot", walk_robots),
            Custom("result", results),
            Custom(
                "q_arm", {"none": const(None), "given": const(PLOT_ARM_Q, REJECT, "value")}, default="omit"
            ),
            Real("fps", 20.0, default="omit"),
            Int("max_frames", 300, 1, default="omit"),
            Choice("view", "3d", ("3d", "side", "front", "top"), default="omit"),
            Flag("follow", True, default="omit"),
            Custom("fig", fig_table, default="omit"),
            Custom(
                "title",
                {"text": const("a title"), "none": const(None), "int": const(3, REJECT, "type")},
                default="omit",
            ),
        ],
        probe=walk_probe,
        after=_close_figures,
        combos=(),
        pairs=8,
        expect=ACCEPT if sim is not None else REJECT,
        why="" if sim is not None else "type",
    )

    # plot.reachability: small reachabilities of Spot (a 0.25 m grid, a third of a second once per worker)
    # and of Go2 carrying an arm (three points); the scatter is the reachable points, the robot stands on
    # the nominal feet or on those given
    def reach_of(key, points=None, **options):
        def make(c):
            label = (key, None if points is None else np.asarray(points).tolist(), sorted(options.items()))
            return c._get(
                ("plot-reachability", repr(label)), lambda: c.robot(key).reachability(points, **options)
            )

        return make

    spot_grid = reach_of("spot", spacing=0.25)
    reach_points = [[0.8, 0.0, 0.5], [0.6, 0.2, 0.3], [3.0, 0.0, 0.0], [0.7, -0.1, math.nan]]

    def altered(make, **fields):
        """The result of ``make`` with fields replaced (each a function of the result)."""
        return lambda c: make(c)._replace(**{k: f(make(c)) for k, f in fields.items()})

    def marked_nan(r):
        points = r.points.copy()
        points[r.reachable] = math.nan
        return points

    def nominal_feet(c, key):
        from spotkin.motion.reach import _scales

        return _scales(c.robot(key))[2]

    def reach_probe(fig, kw, c):
        if not isinstance(fig, Figure):
            return f"not a Figure: {describe(fig)}"
        result = kw["result"]
        want = np.asarray(result.points, np.float64)[np.asarray(result.reachable)]
        ax = next(a for a in fig.axes if getattr(a, "name", "") == "3d")
        scatter = next((a for a in ax.collections if a.get_gid() == "reachable"), None)
        got = None if scatter is None else np.column_stack([np.ma.getdata(v) for v in scatter._offsets3d])
        if got is None or not close(got.astype(np.float64).reshape(-1, 3), want, False):
            return f"the scatter {describe(got)} is not the reachable points {describe(want)}"
        robot = kw.get("robot")
        if robot is not None:
            feet = kw.get("feet")
            key = "spot" if robot is c.robot("spot") else "go2_z1"
            want = nominal_feet(c, key) if feet is None else np.asarray(feet, np.float64)
            drawn = _gid_data(fig, "feet")
            if drawn is None or not close(drawn, want, False):
                return f"drawn feet {describe(drawn)} are not the feet stood on {describe(want)}"
        return None

    def reach_pairs(plan):
        feet = plan["feet"] not in ("omit", "none")
        if feet and plan["robot"] == "none":
            return REJECT  # the feet stand the drawn robot: without one, a ValueError naming feet
        if feet and plan["robot"] == "go2_z1":
            return EITHER  # Spot's feet, moved: within Go2's legs or not
        return None

    register(
        name="plot.reachability",
        covers="spotkin.plot.reachability",
        call=lambda c, **k: plot.reachability(**k),
        slots=[
            Custom(
                "result",
                {
                    "valid": const(spot_grid),
                    "points": const(reach_of("spot", reach_points, approach=[1.0, 0.0, 0.0])),
                    "nothing": const(reach_of("spot", [[3.0, 0.0, 0.0]])),
                    "go2_z1": const(reach_of("go2_z1", [[0.5, 0.0, 0.4], [0.4, 0.2, 0.5], [2.0, 0.0, 0.0]])),
                    "tuple": const(lambda c: tuple(spot_grid(c)), REJECT, "type"),
                    "int_reachable": const(
                        altered(spot_grid, reachable=lambda r: r.reachable.astype(np.int64)), REJECT, "type"
                    ),
                    "short_points": const(altered(spot_grid, points=lambda r: r.points[:1]), REJECT, "value"),
                    "nan_reachable": const(altered(spot_grid, points=marked_nan), REJECT, "value"),
                    "far": const(altered(spot_grid, points=lambda r: r.points + 1e7), REJECT, "value"),
                    "str_volume": const(altered(spot_grid, volume=lambda r: "big"), REJECT, "type"),
                    "str": const("result", REJECT, "type"),
                    "none": const(None, REJECT, "type"),
                },
            ),
            Custom(
                "robot",
                {
                    "valid": const(lambda c: c.robot("spot")),
                    "none": const(None),
                    "go2_z1": const(lambda c: c.robot("go2_z1")),  # as many joints: drawn
                    "go2": const(lambda c: c.robot("go2"), REJECT, "value"),  # no arm: not the result's
                    "hexapod": const(lambda c: c.robot("hexapod"), REJECT, "value"),
                    "str": const("spot", REJECT, "type"),
                },
            ),
            Array(
                "feet",
                lambda c: nominal_feet(c, "spot") + [0.05, -0.03, 0.01],
                optional=True,
                default="omit",
            ),
            Custom("ax", axes_table(True), default="omit"),
            Custom(
                "title",
                {"text": const("a title"), "none": const(None), "int": const(3, REJECT, "type")},
                default="omit",
            ),
        ],
        probe=reach_probe,
        pair_rule=reach_pairs,
        after=_close_figures,
        combos=(),
        pairs=12,
    )
