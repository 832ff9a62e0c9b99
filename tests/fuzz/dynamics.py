"""Registry entries of the dynamics: the chains' methods and the whole robot's statics, against the
pure-Python reference."""

from __future__ import annotations

import math

import numpy as np

from .batch import Batch
from .entry import angle_slot, register, seq_slot
from .objects import ROBOT_LEGS, STANCE_HEIGHT, URDF_CHAINS, body_poses, in_limits, pose_matrix
from .oracles import all_nan, tol_for
from .outputs import Out, OutSlot, describe, outs
from .slots import INVALID, Array, Choice, finite, pose_validity

G0 = np.array([0.0, 0.0, -9.81])


def laid_out(A, layout):
    """One sample's full symmetric matrix in a mass-matrix layout (lower: upper triangle zero;
    packed: the lower triangle row by row)."""
    if layout == "lower":
        return np.tril(A)
    if layout == "packed":
        return A[np.tril_indices(A.shape[-1])]
    return A


def dynamics_entries():
    from spotkin import inertia
    from spotkin.reference import dynamics as rd

    trees = {}

    def tree(c, key, chain):
        if key not in trees:
            trees[key] = inertia.tree_of(chain)
        return trees[key]

    def against(reference, tol_base=1e-8):
        """A check of one valid sample: the output within tol (relative to its size) of the reference's."""

        def check(x, out, kw, c, reference=reference):
            want = np.asarray(reference(c, {k: np.asarray(v, dtype=np.float64) for k, v in x.items()}, kw))
            if not np.isfinite(want).all():
                return None  # the reference overflows (1e300 rates): nothing to compare
            (got,) = out
            biggest = max(float(np.abs(np.asarray(v, np.float64)).max()) for v in x.values())
            dtype = np.asarray(got).dtype if np.asarray(got).dtype.kind == "f" else np.dtype(np.float64)
            if not finite(got) and biggest > 1e-4 * math.sqrt(float(np.finfo(dtype).max)):
                # squares of rates beyond the square root of the dtype's range overflow to Inf (1e150 in
                # float64, 2e15 in float32): never a plausible finite number
                return None
            tol = tol_for(*x.values(), base=tol_base, f32=2e-3) * max(1.0, float(np.abs(want).max()))
            if not finite(got) or np.abs(np.asarray(got, dtype=np.float64) - want).max() > tol:
                return f"got {describe(got)}, the reference gives {describe(want)}"
            return None

        return check

    for key in URDF_CHAINS:
        dof = URDF_CHAINS[key][2]

        def get(c, key=key):
            return c.chain(key)

        def base(c, rng, n, get=get, dof=dof):
            chain = get(c)
            return {
                "q": in_limits(np.stack([chain.lower, chain.upper], axis=1), rng, n, margin=0.1),
                "qd": rng.normal(0.0, 1.0, (n, dof)),
                "qdd": rng.normal(0.0, 1.0, (n, dof)),
                "tau": rng.normal(0.0, 5.0, (n, dof)),
                "gravity": np.tile([0.0, 0.0, -9.81], (n, 1)) + rng.normal(0.0, 0.5, (n, 3)),
                "forces": rng.normal(0.0, 10.0, (n, 6)),
            }

        def t(c, get=get, key=key):
            return tree(c, key, get(c))

        q_slot, qd, qdd = angle_slot("q", dof), Batch("qd", (dof,)), Batch("qdd", (dof,))
        tau_slot, gravity = Batch("tau", (dof,)), Batch("gravity", (3,), default="omit")

        def g(x):
            return x.get("gravity", G0)

        methods = {
            "inverse_dynamics": (
                [q_slot, qd, qdd, gravity],
                (dof,),
                lambda c, x, kw, t=t: rd.rnea(t(c), x["q"], x["qd"], x["qdd"], g(x)),
            ),
            "mass_matrix": (
                [q_slot, Choice("layout", "full", ("full", "lower", "packed"), default="omit")],
                None,  # (dof, dof), or (dof (dof + 1) / 2,) packed
                lambda c, x, kw, t=t: laid_out(rd.crba(t(c), x["q"]), kw.get("layout", "full")),
            ),
            "gravity": (
                [q_slot, gravity],
                (dof,),
                lambda c, x, kw, t=t: rd.gravity_torques(t(c), x["q"], g(x)),
            ),
            "nonlinear_effects": (
                [q_slot, qd, gravity],
                (dof,),
                lambda c, x, kw, t=t: rd.nonlinear_effects(t(c), x["q"], x["qd"], g(x)),
            ),
            "coriolis_matrix": (
                [q_slot, qd],
                (dof, dof),
                lambda c, x, kw, t=t: rd.coriolis_matrix(t(c), x["q"], x["qd"]),
            ),
            "forward_dynamics": (
                [q_slot, qd, tau_slot, gravity],
                (dof,),
                lambda c, x, kw, t=t: rd.aba(t(c), x["q"], x["qd"], x["tau"], g(x)),
            ),
            "center_of_mass": ([q_slot], (3,), lambda c, x, kw, t=t: rd.center_of_mass(t(c), x["q"])),
            "center_of_mass_jacobian": (
                [q_slot],
                (3, dof),
                lambda c, x, kw, t=t: rd.center_of_mass_jacobian(t(c), x["q"]),
            ),
            "kinetic_energy": (
                [q_slot, qd],
                (),
                lambda c, x, kw, t=t: rd.kinetic_energy(t(c), x["q"], x["qd"]),
            ),
            "potential_energy": (
                [q_slot, gravity],
                (),
                lambda c, x, kw, t=t: rd.potential_energy(t(c), x["q"], g(x)),
            ),
            "joint_torques_from_forces": (
                [q_slot, Batch("forces", (6,))],
                (dof,),
                lambda c, x, kw, get=get: get(c).jacobian(x["q"]).T @ x["forces"],
            ),
        }

        def symmetric_out(args, kw, dof=dof):
            packed = kw.get("layout") == "packed"
            return [Out("float", (dof * (dof + 1) // 2,) if packed else (dof, dof))]

        def out_of(trailing, dof=dof):
            if trailing is not None:
                return OutSlot(("float", trailing), drivers=["q", "qd", "qdd", "tau"])

            def leaves(args, dof=dof):  # the mass matrix: its layout decides the shape
                layout = args["layout"].value
                packed = layout == "packed"
                return [("float", (dof * (dof + 1) // 2,) if packed else (dof, dof))]

            return OutSlot(leaves, drivers=["q"])

        with_out = (
            "inverse_dynamics",
            "mass_matrix",
            "gravity",
            "nonlinear_effects",
            "coriolis_matrix",
            "forward_dynamics",
        )
        for method, (slots, trailing, reference) in methods.items():
            if method in with_out:
                slots = [*slots, out_of(trailing)]
            register(
                name=f"Chain.{method}[{key}]",
                covers=f"spotkin.Chain.{method}",
                call=lambda c, get=get, method=method, **k: getattr(get(c), method)(**k),
                slots=slots,
                baseline=base,
                outputs=outs(("float", trailing)) if trailing is not None else symmetric_out,
                check=against(reference),
                overflow_ok=True,
            )

    # the whole robot: Spot (sk.Spot) and Go2 (sk.Robot)
    for key, cls in (("spot", "Spot"), ("go2", "Robot")):
        legs = ROBOT_LEGS[key]

        def robot_of(c, key=key):
            return c.robot(key)

        def body_base(c, rng, n, key=key, legs=legs):
            height = STANCE_HEIGHT[key]
            pose = body_poses(rng, n, height)
            q = c.nominal(key) + rng.uniform(-0.1, 0.1, (n, 3 * legs))
            stance = rng.uniform(size=(n, legs)) < 0.8
            return {"body_pose": pose, "q": q, "stance": stance}

        def whole_tree(c, key=key):
            if ("robot", key) not in trees:
                trees[("robot", key)] = inertia.tree_of(c.robot(key))
            return trees[("robot", key)]

        def full_q(c, q, key=key):
            return np.concatenate([q, np.zeros(len(c.robot(key).arm_joint_names))])

        euler = np.array([False] * 3 + [True] * 3)
        pose_slot = Batch("body_pose", (6,), pose="body", angles=euler)
        q_slot = angle_slot("q", 3 * legs)
        names = {rd.STANCE_OK: 0, rd.STANCE_PULLING: 1, rd.STANCE_OUTSIDE: 2, rd.STANCE_UNBALANCED: 4}

        def standing_check(x, out, kw, c, whole_tree=whole_tree, full_q=full_q, names=names):
            tau, forces, status, margin, residual = out
            ok = pose_validity(x["body_pose"])
            stance = np.asarray(x.get("stance", np.ones(len(tau) // 3)), dtype=np.float64)
            if ok is None:
                return None
            if not ok or not finite(x["q"]) or not np.isin(stance, (0.0, 1.0)).all():
                if (
                    int(status) != INVALID
                    or not all_nan(tau)
                    or not all_nan(forces)
                    or not all_nan(margin)
                    or not all_nan(residual)
                ):
                    return f"invalid input but status {status}, tau {describe(tau)}"
                return None
            T = pose_matrix(x["body_pose"], kw.get("seq", "XYZ"))
            T[:3, 3] = 0.0  # the statics do not depend on where the body is
            q = np.asarray(x["q"], dtype=np.float64)
            gravity = np.asarray(kw.get("gravity", G0), dtype=np.float64)
            want = rd.standing_torques(whole_tree(c), T, full_q(c, q), np.flatnonzero(stance), gravity)
            if int(status) != names[want.status]:
                return f"status {status}, the reference's {want.status}"
            tol = tol_for(*x.values(), base=1e-7, f32=5e-2)
            if np.isfinite(want.margin) and abs(float(margin) - want.margin) > tol:
                return f"margin {margin}, the reference's {want.margin}"
            scale = max(1.0, float(np.abs(want.tau).max()))
            if (
                not finite(tau)
                or np.abs(np.asarray(tau, np.float64) - want.tau[: tau.shape[-1]]).max() > tol * scale
            ):
                return f"tau {describe(tau)}, the reference's {describe(want.tau)}"
            weight = float(np.linalg.norm(gravity)) * float(np.abs(want.residual).max() + 1.0)
            if (
                not finite(residual)
                or np.abs(np.asarray(residual, np.float64) - want.residual).max() > tol * weight
            ):
                return f"residual {describe(residual)}, the reference's {describe(want.residual)}"
            return None

        stance_slot = Batch(
            "stance",
            (legs,),
            valid=lambda s: bool(np.isin(np.asarray(s, np.float64), (0.0, 1.0)).all()),
            optional=True,
        )
        register(
            name=f"{cls}.standing_torques[{key}]",
            covers=f"spotkin.{cls}.standing_torques",
            call=lambda c, robot_of=robot_of, **k: robot_of(c).standing_torques(**k),
            slots=[
                pose_slot,
                q_slot,
                stance_slot,
                Array("gravity", lambda c: np.array([0.0, 0.0, -9.81]), default="omit"),
                seq_slot(),
                OutSlot(
                    ("float", (3 * legs,)),
                    ("float", (legs, 3)),
                    ("stance", ()),
                    ("float", ()),
                    ("float", (6,)),
                    drivers=["body_pose", "q"],
                ),
            ],
            baseline=body_base,
            outputs=outs(
                ("float", (3 * legs,)), ("float", (legs, 3)), ("stance", ()), ("float", ()), ("float", (6,))
            ),
            nan_rule="check",
            check=standing_check,
            overflow_ok=True,
        )

        def com_check(x, out, kw, c, whole_tree=whole_tree, full_q=full_q):
            (com,) = out
            T = pose_matrix(x["body_pose"], kw.get("seq", "XYZ"))
            want = rd.center_of_mass(whole_tree(c), full_q(c, np.asarray(x["q"], np.float64)), T)
            tol = tol_for(*x.values(), base=1e-9, f32=1e-3)
            if not np.isfinite(want).all():
                return None  # the reference overflows at a body 1e308 m away
            if not finite(com) or np.abs(np.asarray(com, np.float64) - want).max() > tol * max(
                1.0, np.abs(want).max()
            ):
                return f"centre of mass {describe(com)}, the reference's {describe(want)}"
            return None

        def floating_q_check(x, out, kw, c):
            (qf,) = out
            T = pose_matrix(x["body_pose"], kw.get("seq", "XYZ"))
            x_, y_, z_, w_ = (float(v) for v in qf[3:7])
            R = np.array(
                [
                    [1 - 2 * (y_ * y_ + z_ * z_), 2 * (x_ * y_ - z_ * w_), 2 * (x_ * z_ + y_ * w_)],
                    [2 * (x_ * y_ + z_ * w_), 1 - 2 * (x_ * x_ + z_ * z_), 2 * (y_ * z_ - x_ * w_)],
                    [2 * (x_ * z_ - y_ * w_), 2 * (y_ * z_ + x_ * w_), 1 - 2 * (x_ * x_ + y_ * y_)],
                ]
            )
            # a rotation accepted within 1e-6 of orthonormal is read as its nearby rotation
            if (
                not finite(qf)
                or np.abs(R - T[:3, :3]).max() > 1e-5
                or np.abs(qf[:3] - T[:3, 3]).max() > 1e-12
            ):
                return f"the pose part {describe(qf[:7])} is not the body pose"
            return None

        n_arm = 6 if key == "spot" else 0
        register(
            name=f"{cls}.center_of_mass[{key}]",
            covers=f"spotkin.{cls}.center_of_mass",
            call=lambda c, robot_of=robot_of, **k: robot_of(c).center_of_mass(**k),
            slots=[pose_slot, q_slot, seq_slot(), OutSlot(("float", (3,)), drivers=["body_pose", "q"])],
            baseline=body_base,
            outputs=outs(("float", (3,))),
            check=com_check,
            light=key == "go2",
        )
        register(
            name=f"{cls}.floating_q[{key}]",
            covers=f"spotkin.{cls}.floating_q",
            call=lambda c, robot_of=robot_of, **k: robot_of(c).floating_q(**k),
            slots=[pose_slot, Batch("q", (3 * legs,)), seq_slot()],  # copied: no angle is read
            baseline=body_base,
            outputs=outs(("f64", (7 + 3 * legs + n_arm,))),
            check=floating_q_check,
            mixed="f64",
            light=key == "go2",
        )
