"""Instruction-set levels: every level the CPU has is listed, can be forced (sk.set_isa, sk.isa,
SPOTKIN_ISA) and runs every kernel family to the same answers as the best level.

The reference cross-checks of the kernels (test_leg, test_body, test_arm, test_chain_ik6,
test_dynamics, ...) run at every level through the ``every_isa`` fixture (tests/conftest.py)."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import spotkin as sk
from spotkin import robots

LEVELS = sk.available_isas()
X86_LEVELS = ("sse2", "avx2", "avx512")


def test_levels_are_listed_lowest_first_and_one_is_active():
    assert LEVELS, "at least the baseline level"
    assert sk.get_isa() in LEVELS
    if LEVELS[0] == "sse2":
        assert LEVELS == X86_LEVELS[: len(LEVELS)]
    else:  # one version, compiled for the target
        assert len(LEVELS) == 1


@pytest.mark.skipif(bool(os.environ.get("SPOTKIN_ISA")), reason="SPOTKIN_ISA forces a level")
def test_the_best_level_is_the_default():
    assert sk.get_isa() == LEVELS[-1]


def test_set_isa_and_the_block_restore_the_level():
    before = sk.get_isa()
    for level in LEVELS:
        with sk.isa(level):
            assert sk.get_isa() == level
        assert sk.get_isa() == before
    sk.set_isa(LEVELS[0])
    try:
        assert sk.get_isa() == LEVELS[0]
        sk.set_isa("best")
        assert sk.get_isa() == LEVELS[-1]
    finally:
        sk.set_isa(before)


def test_bad_levels_are_refused_by_name():
    with pytest.raises(TypeError, match="level must be a str"):
        sk.set_isa(2)
    with pytest.raises(TypeError, match="level must be a str"):
        sk.set_isa(None)
    with pytest.raises(ValueError, match="unknown instruction-set level 'avx3'"):
        sk.set_isa("avx3")
    with pytest.raises(ValueError, match="unknown instruction-set level"):
        sk.set_isa("AVX2")
    missing = [level for level in X86_LEVELS if level not in LEVELS] if LEVELS[0] == "sse2" else []
    for level in missing:
        with pytest.raises(ValueError, match=f"this CPU lacks {level}"):
            sk.set_isa(level)
        with pytest.raises(ValueError), sk.isa(level):
            pass
    assert sk.get_isa() in LEVELS


def _import_with(level: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "SPOTKIN_ISA": level}
    code = "import spotkin as sk; print(sk.get_isa())"
    return subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=120)


def test_the_environment_variable_forces_a_level_at_import():
    run = _import_with(LEVELS[0])
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == LEVELS[0]
    run = _import_with("")
    assert run.stdout.strip() == LEVELS[-1]
    run = _import_with("fast")
    assert run.returncode != 0
    assert "SPOTKIN_ISA=fast: unknown instruction-set level 'fast'" in run.stderr
    if LEVELS[0] == "sse2" and "avx512" not in LEVELS:
        run = _import_with("avx512")
        assert run.returncode != 0
        assert "SPOTKIN_ISA=avx512: this CPU lacks avx512" in run.stderr


# ---- every kernel family at every level, against the best level --------------------------------


def _battery(dtype) -> dict[str, np.ndarray]:
    """One call of each kernel family on fixed inputs (batches of 37: full lanes and a tail)."""
    rng = np.random.default_rng(7)
    spot = sk.Spot()
    go2 = sk.Robot.from_urdf(robots.path("go2"))
    ur5 = sk.Chain.from_urdf(robots.path("ur5"))
    n = 37
    out = {}
    leg = spot.leg("fl")
    q3 = np.column_stack([rng.uniform(lo, hi, n) for lo, hi in leg.limits]).astype(dtype)
    out["leg.fk"] = leg.fk(q3)
    out["leg.jacobian"] = leg.jacobian(q3)
    out["leg.ik"] = leg.ik(out["leg.fk"])[0]
    out["leg.ik_all"] = leg.ik_all(out["leg.fk"]).q
    pose = np.column_stack([rng.uniform(-0.05, 0.05, (n, 3)), rng.uniform(-0.1, 0.1, (n, 3))])
    pose = (pose + [0.0, 0.0, 0.5, 0.0, 0.0, 0.0]).astype(dtype)  # the body over Spot's stance
    body = spot.body_ik(pose, spot.stance_feet())
    out["body_ik"] = body.q
    out["body_fk"] = spot.body_fk(pose, body.q)
    q6 = rng.uniform(-1.0, 1.0, (n, 6)).astype(dtype)
    out["arm.fk"] = spot.arm.fk(q6)
    out["arm.ik_all"] = spot.arm.ik_all(out["arm.fk"]).q
    out["ur5.fk"] = ur5.fk(q6)
    out["ur5.jacobian"] = ur5.jacobian(q6)
    out["ur5.ik"] = ur5.ik_all(out["ur5.fk"]).q
    qd, qdd = rng.normal(size=(2, n, 6)).astype(dtype)
    out["ur5.rnea"] = ur5.inverse_dynamics(q6, qd, qdd)
    out["ur5.crba"] = ur5.mass_matrix(q6)
    out["ur5.aba"] = ur5.forward_dynamics(q6, qd, out["ur5.rnea"])
    stand = go2.body_ik([0.0, 0.0, 0.28, 0.0, 0.0, 0.0], go2.stance_feet(0.28)).q
    q12 = stand + rng.uniform(-0.2, 0.2, (n, 12))
    body_pose = np.column_stack([rng.uniform(-0.1, 0.1, (n, 3)), rng.uniform(-0.3, 0.3, (n, 3))])
    q19 = go2.floating_q(body_pose, q12).astype(dtype)
    floating = go2.floating_base
    v, a = rng.normal(size=(2, n, floating.nv)).astype(dtype)
    out["go2.crba"] = floating.mass_matrix(q19)
    out["go2.rnea"] = floating.inverse_dynamics(q19, v, a)
    out["go2.aba"] = floating.forward_dynamics(q19, v, out["go2.rnea"])
    return out


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_every_level_gives_the_best_level_s_answers(dtype):
    best = _battery(dtype)
    tolerance = 1e-9 if dtype == np.float64 else 2e-3
    for level in LEVELS:
        with sk.isa(level):
            got = _battery(dtype)
        for name, expected in best.items():
            assert got[name].dtype == expected.dtype, (level, name)
            np.testing.assert_array_equal(np.isnan(got[name]), np.isnan(expected), err_msg=f"{level} {name}")
            scale = max(1.0, float(np.nanmax(np.abs(expected))))
            np.testing.assert_allclose(
                got[name], expected, rtol=0, atol=tolerance * scale, equal_nan=True, err_msg=f"{level} {name}"
            )


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_sample_s_bits_are_the_same_alone_and_in_a_batch(dtype):
    """At each level, every sample of a batch answers bit for bit as it does alone (a few samples run
    a narrower model at AVX-512: its bits must be the same)."""
    rng = np.random.default_rng(3)
    go2 = sk.Robot.from_urdf(robots.path("go2"))
    arm = sk.Robot.from_urdf(robots.path("spot_with_arm")).chain("arm_hand")
    n = 11
    q6 = rng.uniform(-1.0, 1.0, (n, 6)).astype(dtype)
    qd, qdd = rng.normal(size=(2, n, 6)).astype(dtype)
    stand = go2.body_ik([0.0, 0.0, 0.28, 0.0, 0.0, 0.0], go2.stance_feet(0.28)).q
    q12 = (stand + rng.uniform(-0.2, 0.2, (n, 12))).astype(dtype)
    pose = np.column_stack([rng.uniform(-0.1, 0.1, (n, 3)), rng.uniform(-0.3, 0.3, (n, 3))]).astype(dtype)
    q19 = go2.floating_q(pose, q12).astype(dtype)
    fb = go2.floating_base
    v, a = rng.normal(size=(2, n, fb.nv)).astype(dtype)
    calls = {
        "rnea": lambda i: arm.inverse_dynamics(q6[i], qd[i], qdd[i]),
        "gravity": lambda i: arm.gravity(q6[i]),
        "crba": lambda i: arm.mass_matrix(q6[i]),
        "aba": lambda i: arm.forward_dynamics(q6[i], qd[i], qdd[i]),
        "floating rnea": lambda i: fb.inverse_dynamics(q19[i], v[i], a[i]),
        "floating gravity": lambda i: fb.gravity(q19[i]),
        "floating crba": lambda i: fb.mass_matrix(q19[i]),
        "com": lambda i: go2.center_of_mass(pose[i], q12[i]),
        "standing": lambda i: go2.standing_torques(pose[i], q12[i]).tau,
    }
    whole = slice(None)
    for level in LEVELS:
        with sk.isa(level):
            for name, call in calls.items():
                batch = call(whole)
                for i in range(n):
                    np.testing.assert_array_equal(call(i), batch[i], err_msg=f"{level} {name} sample {i}")


@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_a_lone_leg_target_answers_its_batch_row_at_every_level(dtype):
    """A single leg IK target runs unpadded (the kernel's loops run it alone), a batch's rows in the
    vector body: the same bits at every level, seeded or not, reachable, beyond the limits or not."""
    rng = np.random.default_rng(11)
    leg = sk.Robot.from_urdf(robots.path("go2")).leg("front_left")
    lo, hi = leg.limits[:, 0], leg.limits[:, 1]
    q = lo + (hi - lo) * rng.uniform(-0.1, 1.1, (300, 3))  # some beyond the limits
    p = (leg.fk(q) + rng.normal(0.0, 0.02, (300, 3))).astype(dtype)  # some out of reach
    seed = (q + rng.normal(0.0, 0.3, (300, 3))).astype(dtype)
    for level in LEVELS:
        with sk.isa(level):
            unseeded, seeded = leg.ik(p), leg.ik(p, seed)
            for i in range(len(p)):
                alone, alone_seeded = leg.ik(p[i]), leg.ik(p[i], seed[i])
                np.testing.assert_array_equal(alone[0], unseeded[0][i], err_msg=f"{level} target {i}")
                np.testing.assert_array_equal(alone_seeded[0], seeded[0][i], err_msg=f"{level} seeded {i}")
                assert alone[1] == unseeded[1][i] and alone_seeded[1] == seeded[1][i], (level, i)


def test_a_lone_arm_pose_answers_its_batch_row_at_every_level():
    """The Spot arm's IK of one pose runs its branches and slots in loops of their own, a batch its
    poses in lanes: the same operations (no fused multiply-adds in the arm's kernels, so none can be
    fused differently),
    the same bits at every level, for matrix and quaternion poses, seeded or not, singular or not."""
    rng = np.random.default_rng(5)
    arm = sk.Spot().arm
    lo, hi = arm.limits[:, 0], arm.limits[:, 1]
    q = lo + (hi - lo) * rng.uniform(-0.05, 1.05, (240, 6))  # some beyond the limits
    q[:30, 4] = 0.0  # the wrist singular
    T = arm.fk(q)
    T[30:60, :3, 3] *= 3.0  # out of reach
    quat = rng.normal(size=(240, 4))
    poses7 = np.concatenate([T[:, :3, 3], quat / np.linalg.norm(quat, axis=1, keepdims=True)], axis=1)
    seeds = q + rng.normal(0.0, 0.2, q.shape)
    for level in LEVELS:
        with sk.isa(level):
            for poses in (T, poses7):
                batch, seeded, nearest = arm.ik_all(poses), arm.ik_all(poses, seeds), arm.ik(poses, seeds)
                for i in range(len(poses)):
                    alone, alone_seeded = arm.ik_all(poses[i]), arm.ik_all(poses[i], seeds[i])
                    for got, row in ((alone, batch), (alone_seeded, seeded)):
                        for name in got._fields:
                            np.testing.assert_array_equal(
                                getattr(got, name), getattr(row, name)[i], err_msg=f"{level} {name} pose {i}"
                            )
                    q_one, status_one = arm.ik(poses[i], seeds[i])
                    np.testing.assert_array_equal(q_one, nearest[0][i], err_msg=f"{level} ik pose {i}")
                    assert status_one == nearest[1][i], (level, i)
