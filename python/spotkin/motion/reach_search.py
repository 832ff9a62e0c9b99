"""The batched reach search: :mod:`spotkin.reference.reach`'s steps (C), (E), (A), (R) and (F), each
over every target of a batch at once. Targets, candidates, options, Gauss-Newton steps and repair
starts are rows of arrays, and the IK, FK and centre of mass are the robot's batched kernels: Python
loops over the search's rounds and steps, never over targets."""

from __future__ import annotations

import numpy as np

from ..reference import reach as ref
from .reach_geometry import (
    Batch,
    arm_targets,
    body_T,
    collisions,
    legs,
    margins,
    residuals,
    wrap,
)


class Options:
    """Flat options (one per valid arm branch at a pose): their target row, pose, joints, branch,
    candidate order and cost; margins and collisions filled as they are needed."""

    def __init__(self, row, p, q, slot, order, cost):
        self.row, self.p, self.q, self.slot, self.order, self.cost = row, p, q, slot, order, cost
        self.margin = np.full(len(row), np.nan)
        self.collides = np.zeros(len(row), bool)
        self.checked = np.zeros(len(row), bool)

    def check(self, batch: Batch, which: np.ndarray) -> None:
        which = which & ~self.checked
        if which.any():
            rows, p, q = self.row[which], self.p[which], self.q[which]
            self.margin[which] = margins(batch, rows, body_T(batch, rows, p), q)
            self.collides[which] = collisions(batch, q)
            self.checked |= which


class Misses:
    """Branches that exist outside the arm's limits, flat: target row, violation, order, slot, p, q_a."""

    def __init__(self, row, violation, order, slot, p, q_arm):
        self.row, self.violation, self.order, self.slot, self.p, self.q_arm = (
            row,
            violation,
            order,
            slot,
            p,
            q_arm,
        )


def evaluate(batch: Batch, rows: np.ndarray, p: np.ndarray, order: np.ndarray) -> tuple[Options, Misses]:
    """(E) at the poses p (M, 6) of targets ``rows`` (M,): every valid branch as flat options, and the
    branches outside the arm's limits."""
    T = body_T(batch, rows, p)
    q_legs, legs_ok = legs(batch, rows, T)
    sols = batch.arm.ik_all(arm_targets(batch, rows, T))
    q_arm, valid = np.asarray(sols.q, float), np.asarray(sols.valid) & legs_ok[:, None]
    pose, slot = np.nonzero(valid)
    q = np.concatenate([q_legs[pose], q_arm[pose, slot]], axis=-1)
    r = residuals(batch, rows[pose], p[pose], q)
    options = Options(rows[pose], p[pose], q, slot, order[pose], 0.5 * (r * r).sum(-1))
    outside = np.asarray(sols.exists) & ~np.asarray(sols.valid) & legs_ok[:, None]
    pose, slot = np.nonzero(outside)
    q_out = q_arm[pose, slot]
    lo, hi = batch.q_lower[-6:], batch.q_upper[-6:]
    excess = (np.maximum(lo - q_out, 0.0) + np.maximum(q_out - hi, 0.0)).sum(-1)
    return options, Misses(rows[pose], excess, order[pose], slot, p[pose], q_out)


def choose(batch: Batch, options: Options, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(A) per target: (index into ``options`` or -1, status). The feasible option of least cost is
    found by checking each target's options in cost order, in chunks that double."""
    best = np.full(n, -1)
    status = np.full(n, ref.UNREACHABLE, np.int8)
    if len(options.row) == 0:
        return best, status
    by_cost = np.lexsort((options.slot, options.order, options.cost, options.row))
    rows = options.row[by_cost]
    first = np.searchsorted(rows, rows, side="left")
    rank = np.empty(len(rows), np.int64)
    rank[by_cost] = np.arange(len(rows)) - first
    resolved = np.zeros(n, bool)
    lo, hi, most = 0, 1, int(rank.max()) + 1
    while lo < most:
        chunk = (rank >= lo) & (rank < hi) & ~resolved[options.row]
        if not chunk.any():
            break
        options.check(batch, chunk)
        good = chunk & ~options.collides & (options.margin >= batch.margin[options.row])
        if good.any():
            found = np.nonzero(good)[0]
            found = found[np.lexsort((rank[found], options.row[found]))]
            targets, at = np.unique(options.row[found], return_index=True)
            best[targets] = found[at]
            status[targets] = ref.OK
            resolved[targets] = True
        lo, hi = hi, 2 * hi
    # no feasible option: the reaching one of largest margin (UNSTABLE)
    rest = ~resolved[options.row]
    options.check(batch, rest)
    reaching = np.nonzero(rest & ~options.collides)[0]
    if len(reaching):
        o = options
        order = np.lexsort(
            (o.slot[reaching], o.order[reaching], o.cost[reaching], -o.margin[reaching], o.row[reaching])
        )
        reaching = reaching[order]
        targets, at = np.unique(o.row[reaching], return_index=True)
        best[targets] = reaching[at]
        status[targets] = ref.UNSTABLE
    return best, status


def follow(batch: Batch, rows, p, q_now):
    """The option at p on the branch of q_now (legs seeded): (q, slot, ok)."""
    n3 = 3 * batch.robot.n_legs
    T = body_T(batch, rows, p)
    q_legs, legs_ok = legs(batch, rows, T, seed=q_now[:, :n3])
    sols = batch.arm.ik_all(arm_targets(batch, rows, T))
    q_all, valid = np.asarray(sols.q, float), np.asarray(sols.valid)
    move = np.where(valid, np.abs(wrap(q_all - q_now[:, None, n3:])).max(axis=-1), np.inf)
    slot = np.argmin(move, axis=1)
    ok = legs_ok & np.isfinite(move[np.arange(len(rows)), slot])
    q = np.concatenate([q_legs, q_all[np.arange(len(rows)), slot]], axis=-1)
    return q, slot, ok


def _cost(batch, rows, p, q):
    r = residuals(batch, rows, p, q)
    return 0.5 * (r * r).sum(-1), r


def refine(batch: Batch, rows, p, q, slot, cost, margin):
    """(R) for the OK targets ``rows``: their refined (p, q, slot, cost, margin)."""
    p, q, slot, cost, margin = p.copy(), q.copy(), slot.copy(), cost.copy(), margin.copy()
    active = np.ones(len(rows), bool)
    eye = np.eye(6)
    for _ in range(ref.REFINE_STEPS):
        idx = np.nonzero(active)[0]
        if len(idx) == 0:
            break
        r_rows, P, Q = rows[idx], p[idx], q[idx]
        _, r0 = _cost(batch, r_rows, P, Q)
        # forward differences: 6 poses per target
        shifted = (P[:, None, :] + ref.FD_STEP * eye).reshape(-1, 6)
        rep = np.repeat(r_rows, 6)
        q_fd, _, ok_fd = follow(batch, rep, shifted, np.repeat(Q, 6, axis=0))
        ok = ok_fd.reshape(-1, 6).all(axis=1)
        r_fd = residuals(batch, rep, shifted, q_fd).reshape(len(idx), 6, -1)
        J = np.transpose((r_fd - r0[:, None, :]) / ref.FD_STEP, (0, 2, 1))  # (R, k, 6)
        JtJ = np.einsum("rki,rkj->rij", J, J) + ref.GN_DAMPING * eye
        delta = np.linalg.solve(JtJ, -np.einsum("rki,rk->ri", J, r0)[..., None])[..., 0]
        taken = np.zeros(len(idx), bool)
        for alpha in (1.0, 0.5, 0.25):
            trying = ok & ~taken
            if not trying.any():
                break
            t_idx = np.nonzero(trying)[0]
            t_rows = r_rows[t_idx]
            p_new = np.clip(P[t_idx] + alpha * delta[t_idx], batch.lower, batch.upper)
            q_new, s_new, ok_new = follow(batch, t_rows, p_new, Q[t_idx])
            c_new, _ = _cost(batch, t_rows, p_new, q_new)
            m_new = np.full(len(t_idx), np.nan)
            hit = np.ones(len(t_idx), bool)
            if ok_new.any():
                m_new[ok_new] = margins(
                    batch, t_rows[ok_new], body_T(batch, t_rows[ok_new], p_new[ok_new]), q_new[ok_new]
                )
                hit[ok_new] = collisions(batch, q_new[ok_new])
            good = ok_new & ~hit & (m_new >= batch.margin[t_rows]) & (c_new < cost[idx[t_idx]])
            g = idx[t_idx[good]]
            p[g], q[g], slot[g], cost[g], margin[g] = (
                p_new[good],
                q_new[good],
                s_new[good],
                c_new[good],
                m_new[good],
            )
            taken[t_idx[good]] = True
        stopped = ~(ok & taken)
        active[idx[stopped]] = False
    return p, q, slot, cost, margin


def hand_errors(batch: Batch, rows, z) -> np.ndarray:
    """(F)'s e for each row of z (M, 12) = (p, q_a): (M, 6)."""
    T_hand = body_T(batch, rows, z[:, :6]) @ batch.mount @ np.asarray(batch.arm.fk(z[:, 6:]), float)
    target = batch.target[rows]
    R = target[:, :3, :3] @ np.transpose(T_hand[:, :3, :3], (0, 2, 1))
    return np.concatenate([target[:, :3, 3] - T_hand[:, :3, 3], batch.scale * rotation_logs(R)], axis=-1)


def rotation_logs(R) -> np.ndarray:
    """Row-wise :func:`ref.rotation_log`."""
    w = np.stack([R[:, 2, 1] - R[:, 1, 2], R[:, 0, 2] - R[:, 2, 0], R[:, 1, 0] - R[:, 0, 1]], -1)
    s = 0.5 * np.sqrt((w * w).sum(-1))
    c = 0.5 * (np.trace(R, axis1=1, axis2=2) - 1.0)
    angle = np.arctan2(s, c)
    out = angle[:, None] * w / np.where(s > 0.0, 2.0 * s, 1.0)[:, None]
    small = s < 1e-9
    if small.any():
        for m in np.nonzero(small)[0]:  # rare: the identity or a half turn
            out[m] = ref.rotation_log(R[m])
    return out


def repair_starts(batch: Batch, rows, misses: Misses) -> np.ndarray:
    """(F)'s starts for the targets ``rows`` (sorted): (len(rows), S, 12), as :func:`ref.repair_starts`."""
    S = ref.REPAIR_STARTS
    lo, hi = batch.q_lower[-6:], batch.q_upper[-6:]
    lo, hi = np.where(np.isfinite(lo), lo, -np.pi), np.where(np.isfinite(hi), hi, np.pi)
    F = len(rows)
    starts = np.empty((F, S, 12))
    starts[:, :, :6] = batch.nominal
    starts[:, 0, 6:] = np.clip(np.zeros(6), lo, hi)
    idx = np.nonzero(np.isin(misses.row, rows))[0]
    idx = idx[np.lexsort((misses.slot[idx], misses.order[idx], misses.violation[idx], misses.row[idx]))]
    target = np.searchsorted(rows, misses.row[idx])
    rank = np.arange(len(idx)) - np.searchsorted(target, target, side="left")
    use = rank < S - 1
    idx, target, rank = idx[use], target[use], rank[use]
    starts[target, rank + 1, :6] = misses.p[idx]
    starts[target, rank + 1, 6:] = np.clip(misses.q_arm[idx], lo, hi)
    count = 1 + np.bincount(target, minlength=F)  # starts filled so far, per target
    units = ref.candidate_units(S)
    for k in range(1, S):
        fill = count <= k
        starts[fill, k, 6:] = lo + units[k - count[fill]] * (hi - lo)
    return starts


def repair(batch: Batch, rows, misses: Misses) -> tuple[np.ndarray, np.ndarray]:
    """(F) for the targets ``rows``: (z (len(rows), S, 12), e (len(rows), S, 6)) from each start."""
    S = ref.REPAIR_STARTS
    arm_lower, arm_upper = batch.q_lower[-6:] + ref.REPAIR_INSET, batch.q_upper[-6:] - ref.REPAIR_INSET
    lower = np.concatenate([batch.lower, arm_lower])
    upper = np.concatenate([batch.upper, arm_upper])
    R = len(rows) * S
    rr = np.repeat(rows, S)
    z = np.clip(repair_starts(batch, rows, misses).reshape(R, 12), lower, upper)
    e = hand_errors(batch, rr, z)
    lam = np.full(R, ref.REPAIR_DAMPING)
    eye6, eye12 = np.eye(6), np.eye(12)
    for _ in range(ref.REPAIR_ITERATIONS):
        going = np.nonzero((e * e).sum(-1) >= 1e-24)[0]
        if len(going) == 0:
            break
        g_rows, Z, E = rr[going], z[going], e[going]
        G = len(going)
        steps = ref.FD_STEP * eye12
        plus = hand_errors(batch, np.repeat(g_rows, 12), (Z[:, None, :] + steps).reshape(-1, 12)).reshape(
            G, 12, 6
        )
        minus = hand_errors(batch, np.repeat(g_rows, 12), (Z[:, None, :] - steps).reshape(-1, 12)).reshape(
            G, 12, 6
        )
        J = -np.transpose(plus - minus, (0, 2, 1)) / (2.0 * ref.FD_STEP)  # (G, 6, 12)
        toward = np.concatenate([ref.NULL_GAIN * (batch.nominal - Z[:, :6]), np.zeros((G, 6))], -1)
        free = np.ones((G, 12), bool)
        delta = np.zeros((G, 12))
        open_ = np.ones(G, bool)
        damp = (lam[going] ** 2)[:, None, None] * eye6
        for _ in range(ref.ACTIVE_SET_PASSES):
            Jf = J * free[:, None, :]
            pinv = np.transpose(Jf, (0, 2, 1)) @ np.linalg.inv(Jf @ np.transpose(Jf, (0, 2, 1)) + damp)
            d = np.einsum("gij,gj->gi", pinv, E) + np.einsum("gij,gj->gi", eye12 - pinv @ Jf, toward * free)
            delta[open_] = d[open_]
            held = free & (((Z <= lower) & (d < 0.0)) | ((Z >= upper) & (d > 0.0)))
            closing = open_ & ~held.any(-1)
            open_ &= ~closing
            free[open_] &= ~held[open_]
            if not open_.any():
                break
        z_new = np.clip(Z + delta, lower, upper)
        e_new = hand_errors(batch, g_rows, z_new)
        legs_ok = legs(batch, g_rows, body_T(batch, g_rows, z_new[:, :6]))[1]
        before = (E * E).sum(-1)
        better = legs_ok & ((e_new * e_new).sum(-1) < np.maximum(before, 1e-24))
        z[going[better]], e[going[better]] = z_new[better], e_new[better]
        lam[going] = np.where(better, lam[going] / 3.0, lam[going] * 3.0)
    return z.reshape(len(rows), S, 12), e.reshape(len(rows), S, 6)


def poses_of(T) -> np.ndarray:
    """Row-wise :func:`ref.pose_of`: [x, y, z, a, b, c] (Euler "XYZ")."""
    R = T[:, :3, :3]
    b = np.arcsin(np.clip(R[:, 0, 2], -1.0, 1.0))
    a = np.arctan2(-R[:, 1, 2], R[:, 2, 2])
    c = np.arctan2(-R[:, 0, 1], R[:, 0, 0])
    return np.concatenate([T[:, :3, 3], np.stack([a, b, c], -1)], -1)


def candidates(batch: Batch) -> np.ndarray:
    """(C): (N, K, 6) poses in S."""
    units = ref.candidate_units()
    fixed = np.concatenate([batch.nominal[None], batch.lower + units * (batch.upper - batch.lower)])
    P = np.broadcast_to(fixed, (len(batch.target), *fixed.shape))
    if batch.seed_pose is not None:
        seed = np.clip(batch.seed_pose, batch.lower, batch.upper)[:, None, :]
        P = np.concatenate([seed, P], axis=1)
    return P


def search(batch: Batch, valid: np.ndarray) -> dict:
    """Every target's answer, as :func:`ref.reach` gives it, for the targets where ``valid`` (N,) (the
    others get :func:`ref.nan_result`'s)."""
    N = len(batch.target)
    m = len(batch.q_lower)
    out = {
        "body_pose": np.full((N, 6), np.nan),
        "q": np.full((N, m), np.nan),
        "status": np.full(N, ref.INVALID_INPUT, np.int8),
        "margin": np.full(N, np.nan),
        "distance": np.full(N, np.nan),
        "angle": np.full(N, np.nan),
        "slot": np.full(N, -1, np.int64),
        "branches": np.full((N, 8, 6), np.nan),
        "valid": np.zeros((N, 8), bool),
    }
    targets = np.nonzero(valid)[0]
    if len(targets) == 0:
        return out
    P = candidates(batch)[targets]
    K = P.shape[1]
    rows = np.repeat(targets, K)
    options, misses = evaluate(batch, rows, P.reshape(-1, 6), np.tile(np.arange(K), len(targets)))
    best, status = choose(batch, options, N)
    p, q = np.full((N, 6), np.nan), np.full((N, m), np.nan)
    slot, cost, margin = np.full(N, -1), np.full(N, np.nan), np.full(N, np.nan)

    def take(opts, best, status, where):
        w = where[best[where] >= 0]
        b = best[w]
        p[w], q[w], slot[w], cost[w], margin[w] = (
            opts.p[b],
            opts.q[b],
            opts.slot[b],
            opts.cost[b],
            opts.margin[b],
        )
        out["status"][w] = status[w]

    take(options, best, status, targets)
    failed = targets[best[targets] < 0]
    if len(failed):
        S = ref.REPAIR_STARTS
        z, e = repair(batch, failed, misses)
        ends = z[:, :, :6].reshape(-1, 6)
        repaired, _ = evaluate(batch, np.repeat(failed, S), ends, np.tile(np.arange(S), len(failed)))
        best2, status2 = choose(batch, repaired, N)
        take(repaired, best2, status2, failed)
        still = failed[best2[failed] < 0]
        if len(still):
            local = np.searchsorted(failed, still)
            nearest = np.argmin((e[local] ** 2).sum(-1), axis=1)  # ties to the earlier start
            zs, es = z[local, nearest], e[local, nearest]
            T = body_T(batch, still, zs[:, :6])
            q_legs, _ = legs(batch, still, T)
            p[still], q[still] = zs[:, :6], np.concatenate([q_legs, zs[:, 6:]], -1)
            margin[still] = margins(batch, still, T, q[still])
            out["status"][still] = ref.UNREACHABLE
            out["distance"][still] = np.sqrt((es[:, :3] ** 2).sum(-1))
            out["angle"][still] = np.sqrt((es[:, 3:] ** 2).sum(-1)) / batch.scale
    good = targets[out["status"][targets] == ref.OK]
    if len(good):
        p[good], q[good], slot[good], cost[good], margin[good] = refine(
            batch, good, p[good], q[good], slot[good], cost[good], margin[good]
        )
    reached = targets[out["status"][targets] != ref.UNREACHABLE]
    out["distance"][reached] = 0.0
    out["angle"][reached] = 0.0
    T = body_T(batch, targets, p[targets])
    sols = batch.arm.ik_all(arm_targets(batch, targets, T))
    out["body_pose"][targets] = poses_of(T)
    out["q"][targets], out["margin"][targets], out["slot"][targets] = (
        q[targets],
        margin[targets],
        slot[targets],
    )
    out["branches"][targets], out["valid"][targets] = np.asarray(sols.q, float), np.asarray(sols.valid)
    return out
