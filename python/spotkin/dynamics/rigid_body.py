"""The rigid-body dynamics of :mod:`spotkin.dynamics` (documented there): serial chains and a floating body
carrying chains, on the C++ models."""

from __future__ import annotations

import math
from collections import OrderedDict

import numpy as np
from numpy.typing import ArrayLike

from .. import _core
from .._support.boundary import as_real, broadcast_lead, check_trailing, quiet_float_errors, real_dtype
from .inertia import LinkInertials

__all__ = [
    "FloatingBase",
    "LinkInertials",
    "center_of_mass",
    "center_of_mass_jacobian",
    "coriolis_matrix",
    "forward_dynamics",
    "gravity",
    "inertials_of",
    "inverse_dynamics",
    "kinetic_energy",
    "mass_matrix",
    "nonlinear_effects",
    "potential_energy",
    "unpack_symmetric",
]

GRAVITY = (0.0, 0.0, -9.81)


def inertials_of(chain, inertials=None) -> LinkInertials:
    """The chain's ``LinkInertials``: ``inertials`` when given, else ``chain.inertials``."""
    if inertials is None:
        inertials = getattr(chain, "inertials", None)
    if inertials is None:
        raise ValueError(
            "this chain carries no inertial parameters: give it some with "
            "chain.with_inertials(mass, com, inertia) (a chain from a URDF with <inertial> elements has "
            "them), or pass inertials=LinkInertials(mass, com, inertia) to a spotkin.dynamics function"
        )
    try:
        mass, com, inertia = inertials
    except (TypeError, ValueError):
        raise TypeError(
            "inertials must be a LinkInertials(mass, com, inertia) or a (mass, com, inertia) triple, "
            f"got {type(inertials).__name__}"
        ) from None
    return LinkInertials(
        as_real(mass, "inertials.mass", np.float64),
        as_real(com, "inertials.com", np.float64),
        as_real(inertia, "inertials.inertia", np.float64),
    )


_CACHE: OrderedDict = OrderedDict()
_CACHE_SIZE = 16


def _cached(kind: str, chain, inertials, make):
    """``make()`` for (kind, chain, inertials), kept for the last few (keyed on identity)."""
    raw = inertials if inertials is not None else getattr(chain, "inertials", None)
    key = (kind, id(chain), id(raw))
    hit = _CACHE.get(key)
    if hit is not None and hit[0] is chain and hit[1] is raw:
        _CACHE.move_to_end(key)
        return hit[2]
    value = make()
    _CACHE[key] = (chain, raw, value)
    if len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return value


def _core_of(chain, inertials) -> _core.ChainDynamics:
    """The C++ model of (chain, inertials)."""

    if getattr(chain, "full_chain", None) is not None:
        raise ValueError(
            "this chain has mimic joints: call its own methods (chain.inverse_dynamics, chain.mass_matrix, "
            "...), which map q to its full chain; the functions here and FloatingBase take chains without"
        )

    def make():
        mass, com, inertia = inertials_of(chain, inertials)
        return _core.ChainDynamics(chain._core, mass, com, inertia)

    return _cached("core", chain, inertials, make)


def inverse_dynamics(
    chain,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    gravity: ArrayLike = GRAVITY,
    *,
    inertials=None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Joint torques tau = A(q) qdd + C(q, qd) qd + G(q), (..., n): recursive Newton-Euler.

    ``out``: an array of the result's shape and dtype (C-contiguous, writeable) to write into
    and return, as every function here takes: a control loop then allocates nothing."""
    return _core_of(chain, inertials).rnea(q, qd, qdd, gravity, out)


def mass_matrix(
    chain, q: ArrayLike, *, inertials=None, layout: str = "full", out: np.ndarray | None = None
) -> np.ndarray:
    """The joint-space inertia matrix A(q), (..., n, n): composite-rigid-body algorithm.
    ``layout`` ``"lower"`` or ``"packed"`` (..., n (n + 1) / 2): see the module's notes."""
    return _core_of(chain, inertials).crba(q, layout, out)


def unpack_symmetric(packed: ArrayLike) -> np.ndarray:
    """The symmetric (..., n, n) matrices of packed lower triangles (..., n (n + 1) / 2), as
    ``mass_matrix(..., layout="packed")`` gives them (``A[i, j]``, ``j <= i``, at ``i (i + 1) / 2 + j``)."""
    packed = as_real(packed, "packed")
    if packed.ndim < 1:
        raise ValueError("packed must have shape (..., n (n + 1) / 2), got a scalar")
    width = packed.shape[-1]
    n = round((math.sqrt(8 * width + 1) - 1) / 2)
    if n < 1 or n * (n + 1) // 2 != width:
        raise ValueError(
            f"packed must have shape (..., n (n + 1) / 2) (1, 3, 6, 10, ... values), got {packed.shape}"
        )
    rows, cols = np.tril_indices(n)  # row by row
    out = np.empty((*packed.shape[:-1], n, n), dtype=packed.dtype)
    out[..., rows, cols] = packed
    out[..., cols, rows] = packed
    return out


def _check_layout(layout) -> str:
    """``layout`` as the C++ binding checks it, for the chains computed in Python."""
    if not isinstance(layout, str):
        raise TypeError(f"layout must be a str, 'full', 'lower' or 'packed', got {type(layout).__name__}")
    if layout not in ("full", "lower", "packed"):
        raise ValueError(f"layout must be 'full', 'lower' or 'packed', got {layout!r}")
    return layout


def _in_layout(A: np.ndarray, layout: str) -> np.ndarray:
    """A full (..., n, n) symmetric matrix in a checked ``layout``."""
    n = A.shape[-1]
    if layout == "lower":  # a NaN sample stays NaN in every element, as the C++ layouts leave it
        bad = np.isnan(A).any(axis=(-2, -1), keepdims=True)
        return np.where(np.tri(n, dtype=bool), A, np.where(bad, A.dtype.type(np.nan), A.dtype.type(0)))
    if layout == "packed":
        rows, cols = np.tril_indices(n)
        return np.ascontiguousarray(A[..., rows, cols])
    return A


def gravity(
    chain, q: ArrayLike, gravity: ArrayLike = GRAVITY, *, inertials=None, out: np.ndarray | None = None
) -> np.ndarray:
    """The gravity torques G(q), (..., n)."""
    return _core_of(chain, inertials).gravity(q, gravity, out)


def nonlinear_effects(
    chain,
    q: ArrayLike,
    qd: ArrayLike,
    gravity: ArrayLike = GRAVITY,
    *,
    inertials=None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """h = C(q, qd) qd + G(q), (..., n)."""
    return _core_of(chain, inertials).nonlinear_effects(q, qd, gravity, out)


def coriolis_matrix(
    chain, q: ArrayLike, qd: ArrayLike, *, inertials=None, out: np.ndarray | None = None
) -> np.ndarray:
    """C(q, qd), (..., n, n), with dA/dt - 2 C skew-symmetric."""
    return _core_of(chain, inertials).coriolis_matrix(q, qd, out)


def forward_dynamics(
    chain,
    q: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    gravity: ArrayLike = GRAVITY,
    *,
    inertials=None,
    out: np.ndarray | None = None,
) -> np.ndarray:
    """Joint accelerations qdd = A^-1 (tau - C qd - G), (..., n): articulated-body algorithm."""
    return _core_of(chain, inertials).aba(q, qd, tau, gravity, out)


def _carried(chain, inertials) -> FloatingBase:
    """The chain on a massless floating body held at its root frame: the floating-base kernels then give
    the chain's centre of mass and its Jacobian (the body adds nothing)."""
    return _cached(
        "carried",
        chain,
        inertials,
        lambda: FloatingBase((0.0, np.zeros(3), np.zeros((3, 3))), [chain], [inertials]),
    )


def _held(chain, q: ArrayLike) -> np.ndarray:
    """Floating coordinates (..., 7 + n) with the body at the origin, then ``q`` (..., n)."""
    q = as_real(q, "q")
    lead = check_trailing(q, "q", (chain.dof,))
    body = np.zeros((*lead, 7), dtype=q.dtype)
    body[..., 6] = 1.0
    return np.concatenate([body, q], axis=-1)


def center_of_mass(chain, q: ArrayLike, *, inertials=None) -> np.ndarray:
    """The centre of mass of the chain's links, (..., 3), in its root frame (the frame before ``base``)."""
    return _carried(chain, inertials).center_of_mass(_held(chain, q))


def center_of_mass_jacobian(chain, q: ArrayLike, *, inertials=None) -> np.ndarray:
    """J_com (..., 3, n) with d com / dt = J_com qd, root-frame axes."""
    return np.ascontiguousarray(_carried(chain, inertials).center_of_mass_jacobian(_held(chain, q))[..., 6:])


def _quadratic(A: np.ndarray, v: np.ndarray, name: str) -> np.ndarray:
    """v^T A v / 2 per sample: A (..., n, n) and v (..., n) broadcast over their leading dimensions."""
    n = A.shape[-1]
    lead = broadcast_lead(q=(A.shape[:-2], A.shape), **{name: (check_trailing(v, name, (n,)), v.shape)})
    dtype = real_dtype(A, v)
    A = np.broadcast_to(A, (*lead, n, n)).astype(dtype, copy=False)
    v = np.broadcast_to(v, (*lead, n)).astype(dtype, copy=False)
    energy = 0.5 * np.einsum("...i,...ij,...j->...", v, A, v)
    return np.where(np.isfinite(v).all(axis=-1) & np.isfinite(A).all(axis=(-2, -1)), energy, np.nan).astype(
        dtype, copy=False
    )


def _weight_potential(mass: float, com: np.ndarray, gravity: ArrayLike) -> np.ndarray:
    """U = -m g . c (zero at the root frame's origin): com (..., 3), gravity (3,) or (..., 3). The dtype is
    com's (q's), as the kernels' gravity never changes theirs; a NaN or Inf sample gives NaN."""
    g = as_real(gravity, "gravity")
    lead = broadcast_lead(
        q=(com.shape[:-1], com.shape), gravity=(check_trailing(g, "gravity", (3,)), g.shape)
    )
    dtype = com.dtype
    com, g = np.broadcast_to(com, (*lead, 3)), np.broadcast_to(g, (*lead, 3))
    potential = -mass * np.einsum("...i,...i->...", com, g)
    finite = np.isfinite(com).all(axis=-1) & np.isfinite(g).all(axis=-1)
    return np.where(finite, potential, np.nan).astype(dtype, copy=False)


@quiet_float_errors
def kinetic_energy(chain, q: ArrayLike, qd: ArrayLike, *, inertials=None) -> np.ndarray:
    """T = qd^T A(q) qd / 2, (...): the links' kinetic energy (J)."""
    return _quadratic(mass_matrix(chain, q, inertials=inertials), as_real(qd, "qd"), "qd")


@quiet_float_errors
def potential_energy(chain, q: ArrayLike, gravity: ArrayLike = GRAVITY, *, inertials=None) -> np.ndarray:
    """U = -m g . c, (...): the links' potential energy (J) in ``gravity``, zero with the centre of mass
    at the root frame's origin; G(q) = dU/dq."""
    mass = float(np.sum(inertials_of(chain, inertials).mass))
    com = center_of_mass(chain, q, inertials=inertials)
    return _weight_potential(mass, com, gravity)


class FloatingBase:
    """A floating body (free-flyer) carrying chains, each mounted at its ``base`` on the body.

    Coordinates follow Pinocchio's free-flyer: ``q`` (..., 7 + n) is the body's position and
    unit quaternion ``[x, y, z, qx, qy, qz, qw]`` in the world, then the chains' joints in the
    order the chains were given; ``v`` (..., 6 + n) is the body's linear then angular velocity
    in the body frame, then the joint rates; ``a`` = dv/dt; ``tau`` (..., 6 + n) the force then
    moment on the body (body frame), then the joint torques. ``gravity`` is a world vector.

    Results are bit-identical for any thread count and any chunking of a batch into calls, a
    single sample included (each instruction-set level, :func:`spotkin.get_isa`, runs one
    register width). Pickles (rebuilt from its body, chains and inertials). Every batched
    method takes ``out=``, an array of its result's shape and dtype to write into and return.
    """

    __slots__ = ("_args", "_chains", "_core", "_mass")

    def __init__(self, body: tuple, chains, inertials=None) -> None:
        """``body`` = (mass, com (3,), inertia (3, 3) about the com), in the body frame;
        ``chains`` a sequence of chains (their ``base`` is their mount on the body);
        ``inertials`` their ``LinkInertials`` (default: each chain's ``inertials``)."""
        chains = tuple(chains)
        inertials = (None,) * len(chains) if inertials is None else tuple(inertials)
        cores = [_core_of(c, i) for c, i in zip(chains, inertials)]
        mass, com, inertia = body
        self._core = _core.FloatingDynamics(np.asarray(mass, float), com, inertia, cores)
        self._chains = chains
        self._args = (body, chains, inertials)  # what a pickle rebuilds it from
        self._mass = float(mass) + sum(
            float(np.sum(inertials_of(c, i).mass)) for c, i in zip(chains, inertials)
        )

    def __reduce__(self):
        return (FloatingBase, self._args)

    @property
    def nq(self) -> int:
        return self._core.nq

    @property
    def nv(self) -> int:
        return self._core.nv

    def inverse_dynamics(self, q, v, a, gravity=GRAVITY, *, out=None) -> np.ndarray:
        """Generalised forces tau = A(q) a + h(q, v), (..., 6 + n)."""
        return self._core.rnea(q, v, a, gravity, out)

    def mass_matrix(self, q, layout: str = "full", *, out=None) -> np.ndarray:
        """A(q), (..., 6 + n, 6 + n); invariant to the body's pose. ``layout`` ``"lower"`` or
        ``"packed"`` (..., m) with m = (6 + n) (7 + n) / 2, as :func:`mass_matrix`."""
        return self._core.crba(q, layout, out)

    def gravity(self, q, gravity=GRAVITY, *, out=None) -> np.ndarray:
        return self._core.gravity(q, gravity, out)

    def nonlinear_effects(self, q, v, gravity=GRAVITY, *, out=None) -> np.ndarray:
        return self._core.nonlinear_effects(q, v, gravity, out)

    def coriolis_matrix(self, q, v, *, out=None) -> np.ndarray:
        """C(q, v), (..., 6 + n, 6 + n), with dA/dt - 2 C skew-symmetric (as Pinocchio's
        ``computeCoriolisMatrix`` for its free-flyer: the body's velocity in the body frame)."""
        return self._core.coriolis_matrix(q, v, out)

    def forward_dynamics(self, q, v, tau, gravity=GRAVITY, *, out=None) -> np.ndarray:
        """a = A^-1 (tau - h), (..., 6 + n): articulated-body algorithm."""
        return self._core.aba(q, v, tau, gravity, out)

    def center_of_mass(self, q, *, out=None) -> np.ndarray:
        """The whole system's centre of mass in the world, (..., 3)."""
        return self._core.com(q, out)

    def center_of_mass_jacobian(self, q, *, out=None) -> np.ndarray:
        """(..., 3, 6 + n): d com / dt = J v."""
        return self._core.com_jacobian(q, out)

    @property
    def mass(self) -> float:
        """The total mass (kg): the body's and the chains' links'."""
        return self._mass

    @quiet_float_errors
    def kinetic_energy(self, q, v) -> np.ndarray:
        """T = v^T A(q) v / 2, (...), in J."""
        return _quadratic(self.mass_matrix(q), as_real(v, "v"), "v")

    @quiet_float_errors
    def potential_energy(self, q, gravity=GRAVITY) -> np.ndarray:
        """U = -m g . c, (...), in J: zero with the centre of mass at the world origin."""
        return _weight_potential(self._mass, self.center_of_mass(q), gravity)
