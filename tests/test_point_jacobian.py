"""Preferential Jacobians J_k(j) (Chain.jacobian with point= and frame=): the C++ against the
plain reference, central finite differences, the change-of-frame identity and the course's PRPRR
exercise derived by hand."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given
from hypothesis import strategies as st

import spotkin as sk
from conftest import BATCH_SHAPES, random_rigid, random_table, vee_so3
from spotkin.reference import chain as ref
from spotkin.reference import course_robots as course

# the reference cross-checks run at every instruction-set level the CPU has (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("every_isa")

TOLERANCE = {np.float64: 1e-12, np.float32: 2e-5}


def reference_batch(chain: sk.Chain, q: np.ndarray, point: int, frame) -> np.ndarray:
    flat = q.reshape(-1, chain.dof).astype(np.float64)
    out = [
        ref.point_jacobian(chain.rows, chain.convention, qi, point, frame, chain.base, chain.tool)
        for qi in flat
    ]
    return np.array(out).reshape(*q.shape[:-1], 6, chain.dof)


def random_chain(rng, dof, convention):
    rows = random_table(rng, dof)
    return sk.Chain(rows, convention=convention, base=random_rigid(rng), tool=random_rigid(rng))


@pytest.mark.parametrize("convention", ["mdh", "dh"])
@pytest.mark.parametrize("dof", [1, 3, 6, 9])
def test_every_point_and_frame_matches_the_reference(rng, convention, dof):
    for _ in range(3):
        chain = random_chain(rng, dof, convention)
        q = rng.uniform(-np.pi, np.pi, (7, dof))
        for point in range(dof + 2):
            for frame in ["base", *range(dof + 2)]:
                expected = reference_batch(chain, q, point, frame)
                got = chain.jacobian(q, point=point, frame=frame)
                np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12, err_msg=f"{point=} {frame=}")
                np.testing.assert_allclose(
                    chain.position_jacobian(q, point=point, frame=frame),
                    expected[..., :3, :],
                    rtol=0,
                    atol=1e-12,
                )


def test_tool_and_base_words_are_the_end_indices(rng):
    chain = random_chain(rng, 5, "mdh")
    q = rng.uniform(-np.pi, np.pi, (4, 5))
    last = chain.dof + 1
    np.testing.assert_allclose(chain.jacobian(q, point=last), chain.jacobian(q), rtol=0, atol=1e-13)
    np.testing.assert_allclose(
        chain.jacobian(q, point=last, frame="tool"), chain.jacobian(q, frame="tool"), rtol=0, atol=1e-13
    )
    np.testing.assert_allclose(
        chain.jacobian(q, point="tool", frame=last), chain.jacobian(q, frame="tool"), rtol=0, atol=1e-13
    )
    # frame 0 is the base transform's frame: the reference axes rotated by base^T
    R0 = chain.base[:3, :3]
    J = chain.jacobian(q, point=3)
    J0 = chain.jacobian(q, point=3, frame=0)
    np.testing.assert_allclose(J0[..., :3, :], R0.T @ J[..., :3, :], rtol=0, atol=1e-12)
    np.testing.assert_allclose(J0[..., 3:, :], R0.T @ J[..., 3:, :], rtol=0, atol=1e-12)


@given(
    dof=st.integers(1, 7),
    convention=st.sampled_from(["mdh", "dh"]),
    batch=st.sampled_from(BATCH_SHAPES + [(0,), (2, 0, 3)]),
    dtype=st.sampled_from([np.float64, np.float32]),
    seed=st.integers(0, 2**32 - 1),
    data=st.data(),
)
def test_batch_shapes_and_dtypes(dof, convention, batch, dtype, seed, data):
    rng = np.random.default_rng(seed)
    chain = random_chain(rng, dof, convention)
    point = data.draw(st.integers(0, dof + 1))
    frame = data.draw(st.sampled_from(["base", "tool", *range(dof + 2)]))
    q = rng.uniform(-np.pi, np.pi, (*batch, dof)).astype(dtype)
    J = chain.jacobian(q, point=point, frame=frame)
    assert J.shape == (*batch, 6, dof) and J.dtype == dtype
    index = frame if not isinstance(frame, str) else (-1 if frame == "base" else dof + 1)
    expected = reference_batch(chain, q, point, "base" if index == -1 else index)
    np.testing.assert_allclose(
        J, expected, rtol=0, atol=TOLERANCE[dtype] * (1 + np.abs(expected).max(initial=0))
    )


def test_non_contiguous_input_and_nan_in_one_sample(rng):
    chain = random_chain(rng, 6, "mdh")
    q = rng.uniform(-np.pi, np.pi, (5, 12))[:, ::2]
    assert not q.flags.c_contiguous
    np.testing.assert_allclose(
        chain.jacobian(q, point=4, frame=2), reference_batch(chain, q, 4, 2), atol=1e-12
    )
    q = np.ascontiguousarray(q)
    q[2, 1] = np.nan
    J = chain.jacobian(q, point=4, frame=2)
    assert np.isnan(J[2]).any() and np.isfinite(J[[0, 1, 3, 4]]).all()


def frame_jacobian_by_differences(chain, q, point, h=1e-6):
    """Central differences of frame `point`: [d O_k / dq; vee(dR_k/dq R_k^T)] in the reference axes."""
    J = np.zeros((6, chain.dof))
    for i in range(chain.dof):
        step = np.zeros(chain.dof)
        step[i] = h
        plus, minus = chain.frames(q + step)[point], chain.frames(q - step)[point]
        J[:3, i] = (plus[:3, 3] - minus[:3, 3]) / (2 * h)
        dR = (plus[:3, :3] - minus[:3, :3]) / (2 * h)
        J[3:, i] = vee_so3(dR @ chain.frames(q)[point][:3, :3].T)
    return J


@pytest.mark.parametrize("convention", ["mdh", "dh"])
def test_central_differences(rng, convention):
    for _ in range(5):
        chain = random_chain(rng, 6, convention)
        q = rng.uniform(-np.pi, np.pi, 6)
        for point in range(8):
            J_fd = frame_jacobian_by_differences(chain, q, point)
            np.testing.assert_allclose(chain.jacobian(q, point=point), J_fd, rtol=0, atol=1e-8)


@given(seed=st.integers(0, 2**32 - 1), near=st.sampled_from([0.0, 1e-9, 1e-6]))
@example(seed=0, near=0.0)
def test_change_of_frame_identity_near_singular_configurations(seed, near):
    """J_k(j) = diag(R_j^T, R_j^T) J_k(base), R_j from Chain.frames, also at (near) singular q."""
    rng = np.random.default_rng(seed)
    rows = random_table(rng, 6, prismatic=False)
    rows[2, 4] = 0.0
    chain = sk.Chain(rows, convention="mdh", base=random_rigid(rng))
    q = rng.uniform(-np.pi, np.pi, (4, 6))
    q[:, 2] = near  # a joint at (or next to) an aligned configuration
    frames = chain.frames(q)
    for point in range(8):
        J = chain.jacobian(q, point=point)
        for frame in range(8):
            Rt = np.swapaxes(frames[:, frame, :3, :3], -1, -2)
            Jj = chain.jacobian(q, point=point, frame=frame)
            np.testing.assert_allclose(Jj[:, :3], Rt @ J[:, :3], rtol=0, atol=1e-12)
            np.testing.assert_allclose(Jj[:, 3:], Rt @ J[:, 3:], rtol=0, atol=1e-12)


def test_columns_after_the_point_are_zero(rng):
    chain = random_chain(rng, 7, "dh")
    q = rng.uniform(-np.pi, np.pi, (3, 7))
    for point in range(9):
        J = chain.jacobian(q, point=point, frame=min(point, 8))
        assert not J[..., :, point:].any()


def test_urdf_style_chain_matches_its_frames_by_differences(rng):
    placements = np.stack([random_rigid(rng) for _ in range(5)])
    axes = rng.normal(size=(5, 3))
    chain = sk.Chain.from_joints(placements, axes, [0, 1, 0, 0, 1], tool=random_rigid(rng))
    q = rng.uniform(-1, 1, 5)
    for point in range(7):
        np.testing.assert_allclose(
            chain.jacobian(q, point=point), frame_jacobian_by_differences(chain, q, point), rtol=0, atol=1e-8
        )


# -- the course's PRPRR exercise -----------------------------------------------------------------


def prprr_chain(params=course.PRPRR_004_PARAMS):
    rows, tool = course.prprr_004_mdh(params)
    return sk.Chain.from_mdh(rows, tool=tool)


def test_prprr_rebuilt_arm_frames_are_its_table(rng):
    chain = prprr_chain()
    assert "".join("RP"[s] for s in chain.sigma) == "PRPRR"
    for q in rng.uniform(-1.5, 1.5, (10, 5)):
        np.testing.assert_allclose(chain.frames(q), np.array(course.prprr_004_frames(q)), rtol=0, atol=1e-12)


def test_prprr_j32_is_the_hand_derivation(rng):
    chain = prprr_chain()
    q = rng.uniform(-1.5, 1.5, (50, 5))
    expected = np.array([course.prprr_004_jacobian_3_in_2(qi) for qi in q])
    np.testing.assert_allclose(chain.jacobian(q, point=3, frame=2), expected, rtol=0, atol=1e-12)


def test_prprr_j32_by_hand_at_a_written_configuration():
    """q = (0.2, 0.3, 0.5, *, *): v = (q3 q2', -q3', q1'), w = (0, 0, q2') read off by hand."""
    chain = prprr_chain()
    J = chain.jacobian([0.2, 0.3, 0.5, -0.7, 0.4], point=3, frame=2)
    expected = np.zeros((6, 5))
    expected[0, 1] = 0.5
    expected[1, 2] = -1.0
    expected[2, 0] = 1.0
    expected[5, 1] = 1.0
    np.testing.assert_allclose(J, expected, rtol=0, atol=1e-15)


def test_prprr_j32_hand_formula_for_other_twists_and_lengths(rng):
    for _ in range(20):
        params = dict(course.PRPRR_004_PARAMS)
        params.update(
            alpha2=rng.uniform(-np.pi, np.pi),
            theta2=rng.uniform(-np.pi, np.pi),
            alpha3=rng.uniform(-np.pi, np.pi),
            d3=rng.uniform(-1, 1),
            r3=rng.uniform(-1, 1),
            d1=rng.uniform(-1, 1),
        )
        chain = prprr_chain(params)
        q = rng.uniform(-1.5, 1.5, (10, 5))
        expected = np.array([course.prprr_004_jacobian_3_in_2(qi, params) for qi in q])
        np.testing.assert_allclose(chain.jacobian(q, point=3, frame=2), expected, rtol=0, atol=1e-12)
        # and J_3(2) is J_3(0) rotated by R_02^T, J_3(0) by differences of frame 3
        for qi in q[:3]:
            R02 = chain.frames(qi)[2][:3, :3]
            J0 = frame_jacobian_by_differences(chain, qi, 3)
            hand = course.prprr_004_jacobian_3_in_2(qi, params)
            np.testing.assert_allclose(R02.T @ J0[:3], hand[:3], rtol=0, atol=1e-8)
            np.testing.assert_allclose(R02.T @ J0[3:], hand[3:], rtol=0, atol=1e-8)


# -- bad input -------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"point": 9}, ValueError, r"point must be a frame index in \[0, 7\]"),
        ({"point": -1}, ValueError, "point"),
        ({"frame": 8}, ValueError, r"frame must be a frame index in \[0, 7\]"),
        ({"frame": "world", "point": 2}, ValueError, "frame must be"),
        ({"point": "base"}, ValueError, "point must be"),
        ({"point": 2.0}, TypeError, "point must be an integer"),
        ({"frame": True, "point": 1}, TypeError, "frame must be an integer"),
        ({"frame": None, "point": 1}, TypeError, "frame"),
    ],
)
def test_bad_point_or_frame(rng, kwargs, error, match):
    chain = random_chain(rng, 6, "mdh")
    with pytest.raises(error, match=match):
        chain.jacobian(np.zeros(6), **kwargs)


def test_bad_q_shape_names_q(rng):
    chain = random_chain(rng, 6, "mdh")
    with pytest.raises(ValueError, match="q"):
        chain.jacobian(np.zeros(5), point=2, frame=1)
    with pytest.raises(TypeError):
        chain.jacobian("abc", point=2, frame=1)
