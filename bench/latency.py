"""Single-call latency from Python against Pinocchio, in one plain interpreter.

Run it as ``python bench/latency.py`` (``bench/bench_latency.py`` runs it in a fresh process under
pytest). Each call is timed with ``timeit`` (best of 7 repeats); every target is a ratio to a Pinocchio
call timed in the same process, since machines differ by 3x and more in Python call overhead.

"pin FK(n)" is ``pin.forwardKinematics`` on an n-joint fixed-base model of the same robot: Go2 for 12
joints, one Go2 leg for 3, Spot's arm for 6.
"""

from __future__ import annotations

import itertools
import timeit
from pathlib import Path

import numpy as np

import spotkin as sk

try:
    import pinocchio as pin
except ImportError as error:  # pragma: no cover
    raise SystemExit("the latency bench needs Pinocchio: pip install pin") from error

ROBOTS = Path(sk.__file__).parent / "robots"
NUMBER = 20_000
ROUNDS = 7  # rounds of every (call, reference) pair, timed one after the other


def best_us(call, number: int = NUMBER, repeat: int = 7) -> float:
    return min(timeit.repeat(call, number=number, repeat=repeat)) / number * 1e6


def reduced(urdf: str, keep, free_flyer: bool = False):
    full = (
        pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
        if free_flyer
        else pin.buildModelFromUrdf(urdf)
    )
    lock = [full.getJointId(n) for n in full.names[1:] if n not in keep and n != "root_joint"]
    return pin.buildReducedModel(full, lock, pin.neutral(full)) if lock else full


def main() -> list[tuple[str, float, float, str, float | None]]:
    rng = np.random.default_rng(0)
    go2_urdf, spot_urdf = str(ROBOTS / "go2.urdf"), str(ROBOTS / "spot_with_arm.urdf")
    go2 = sk.Robot.from_urdf(go2_urdf)
    leg = go2.legs[0]
    arm_chain = sk.Robot.from_urdf(spot_urdf).chain("arm_hand")
    spot = sk.Spot()
    spot_arm = spot.arm

    # Pinocchio models: Go2 fixed base (12), one Go2 leg (3), Spot's arm (6), Go2 free flyer
    pin12 = pin.buildModelFromUrdf(go2_urdf)
    pin3 = reduced(go2_urdf, set(go2.leg_joint_names[:3]))
    pin6 = reduced(spot_urdf, set(arm_chain.joint_names))
    pin_ff = pin.buildModelFromUrdf(go2_urdf, pin.JointModelFreeFlyer())
    assert list(pin6.names[1:]) == list(arm_chain.joint_names)
    data12, data3, data6, data_ff = (m.createData() for m in (pin12, pin3, pin6, pin_ff))
    q12 = pin.neutral(pin12) + rng.uniform(-0.3, 0.3, 12)
    q3, q6 = pin.neutral(pin3) + 0.2, pin.neutral(pin6) + 0.3
    v6, a6 = rng.normal(size=6), rng.normal(size=6)
    q_ff = pin.randomConfiguration(pin_ff, -np.ones(19), np.ones(19))
    frame6 = pin6.getFrameId("arm_hand")

    # spotkin inputs
    feet = go2.stance_feet(0.3)
    pose = np.array([0.01, -0.01, 0.29, 0.03, -0.04, 0.05])
    ik = go2.body_ik(pose, feet)
    q_legs = ik.q
    seed = q_legs + 0.01
    p_leg = leg.fk(q_legs[:3])
    T_arm = spot_arm.fk(np.array([0.1, -1.0, 1.5, 0.2, 0.5, 0.0]))
    q_arm = np.array([0.1, -1.0, 1.5, 0.2, 0.5, 0.0])
    qd_arm, qdd_arm = rng.normal(size=6), rng.normal(size=6)
    arm_chain.gravity(q_arm)  # builds the inertials once
    go2.standing_torques(pose, q_legs)
    leg_chain = go2.chain(go2._specs[0][0].foot)
    leg_chain.gravity(q_legs[:3])

    # out= buffers for the control tick
    out_q, out_status = np.empty(12), np.empty(4, np.int8)
    out_J = np.empty((12, 18))
    out_g = np.empty(3)
    out_standing = (np.empty(12), np.empty((4, 3)), np.empty((), np.int8), np.empty(()), np.empty(6))

    # the gait controller's tick: one robot, its state standing (the controller walks on)
    controller = sk.GaitController(go2, "trot")
    state = sk.motion.RobotState(
        pose[:3], np.array([0.0, 0.0, 0.0, 1.0]), np.zeros(3), np.zeros(3), q_legs, np.zeros(12)
    )
    clock = (0.002 * k for k in itertools.count())  # the 500 Hz clock, made as it is read

    def gait_step():
        controller.step(next(clock), state, (0.2, 0.0, 0.0))

    def pin_tick():
        pin.forwardKinematics(pin_ff, data_ff, q_ff)
        pin.computeJointJacobians(pin_ff, data_ff, q_ff)
        pin.computeGeneralizedGravity(pin_ff, data_ff, q_ff)

    def sk_tick():
        go2.body_ik(pose, feet, seed, out=(out_q, out_status))
        go2.body_jacobian(pose, out_q, out=out_J)
        leg_chain.gravity(out_q[:3], out=out_g)
        go2.standing_torques(pose, out_q, out=out_standing)

    pins = {
        "pin FK(12)": lambda: pin.forwardKinematics(pin12, data12, q12),
        "pin FK(3)": lambda: pin.forwardKinematics(pin3, data3, q3),
        "pin FK(6)": lambda: pin.forwardKinematics(pin6, data6, q6),
        "pin FK+frames(6)": lambda: (
            pin.forwardKinematics(pin6, data6, q6),
            pin.updateFramePlacements(pin6, data6),
        ),
        "pin frameJacobian(6)": lambda: pin.computeFrameJacobian(pin6, data6, q6, frame6),
        "pin rnea(6)": lambda: pin.rnea(pin6, data6, q6, v6, a6),
        "pin gravity(6)": lambda: pin.computeGeneralizedGravity(pin6, data6, q6),
        "pin crba(6)": lambda: pin.crba(pin6, data6, q6),
        "pin gravity(ff)": lambda: pin.computeGeneralizedGravity(pin_ff, data_ff, q_ff),
        "pin centerOfMass(ff)": lambda: pin.centerOfMass(pin_ff, data_ff, q_ff),
        "pin tick(ff)": pin_tick,
    }
    # (name, call, reference, target ratio: spotkin time / reference time at most)
    calls = [
        ("body_ik", lambda: go2.body_ik(pose, feet), "pin FK(12)", 1.0),
        ("body_ik, seeded", lambda: go2.body_ik(pose, feet, seed), "pin FK(12)", 1.0),
        ("leg.ik", lambda: leg.ik(p_leg), "pin FK(3)", 1.0),
        ("Spot arm ik_all", lambda: spot_arm.ik_all(T_arm), "pin FK(6)", 1.5),
        ("chain.fk (arm)", lambda: arm_chain.fk(q_arm), "pin FK+frames(6)", 1.0),
        ("chain.jacobian (arm)", lambda: arm_chain.jacobian(q_arm), "pin frameJacobian(6)", 1.0),
        ("arm RNEA", lambda: arm_chain.inverse_dynamics(q_arm, qd_arm, qdd_arm), "pin rnea(6)", 1 / 1.2),
        ("arm gravity", lambda: arm_chain.gravity(q_arm), "pin gravity(6)", 1 / 1.2),
        ("arm mass_matrix", lambda: arm_chain.mass_matrix(q_arm), "pin crba(6)", 1 / 1.2),
        ("standing_torques (Go2)", lambda: go2.standing_torques(pose, q_legs), "pin gravity(ff)", 2.0),
        ("center_of_mass (Go2)", lambda: go2.center_of_mass(pose, q_legs), "pin centerOfMass(ff)", 1.0),
        ("body_transform", lambda: sk.body_transform(pose), "pin FK(12)", 1.0),
        ("control tick (Go2, out=)", sk_tick, "pin tick(ff)", 1.5),
        ("GaitController.step (Go2)", gait_step, "pin tick(ff)", 2.0),
    ]
    # Each call and its reference timed in turn, round after round, best of the rounds: this
    # machine's speed drifts within a run, and a ratio must compare times taken under one load.
    ref_us = dict.fromkeys(pins, float("inf"))
    us = dict.fromkeys((name for name, *_ in calls), float("inf"))
    for _ in range(ROUNDS):
        for name, call, ref, _target in calls:
            ref_us[ref] = min(ref_us[ref], best_us(pins[ref], repeat=1))
            us[name] = min(us[name], best_us(call, repeat=1))
    return [(name, us[name], ref_us[ref], ref, target) for name, _call, ref, target in calls]


def report(rows) -> str:
    lines = [
        "single-call latency from Python, one thread (timeit: best of 7 rounds of 20,000 calls,"
        " each call and its reference in turn)",
        f"  {'call':<26}{'spotkin':>10}{'reference':>31}{'ratio':>8}{'target':>9}",
    ]
    for name, us, ref, ref_name, target in rows:
        ratio = us / ref
        mark = "" if target is None else ("  met" if ratio <= target else "  NOT MET")
        bound = f"<= {target:.2f}"
        lines.append(f"  {name:<26}{us:7.2f} us{ref_name:>22}{ref:6.2f} us{ratio:7.2f}x{bound:>9}{mark}")
    return "\n".join(lines)


if __name__ == "__main__":
    print(f"spotkin {sk.__version__} at {sk.get_isa()}; Pinocchio {pin.__version__}")
    print(report(main()))
