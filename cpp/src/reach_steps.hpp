// The Gauss-Newton steps (R) and the repair (F) of the reach search (cpp/src/reach_search.hpp):
// python/spotkin/reference/reach.py's sensitivities, refine, hand_error and descend. Included by
// cpp/src/reach.cpp alone, whose level-specific entry points inline them.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "reach_search.hpp"

namespace spotkin::motion::search {

// ref.sensitivities: dq/dp (m, 6), row-major, at the answer, from the legs' Jacobians J_legs[l]
// (3 x 3) and the arm's J_arm (6 x 6) there; false where a Jacobian is singular.
template <typename Model>
bool sensitivities(const Search<Model>& s, const Answer& a, const double* const* J_legs,
                   const double* J_arm, double* dq) {
  const int n3 = 3 * s.legs;
  const double* S = s.in.stance;  // world <- S: points into S by R_S^T (x - t_S)
  const auto to_stance = [&](const double* x, double* out) {
    const double d[3] = {x[0] - S[3], x[1] - S[7], x[2] - S[11]};
    for (int i = 0; i < 3; ++i) out[i] = S[i] * d[0] + S[4 + i] * d[1] + S[8 + i] * d[2];
  };
  const double* T = a.L;
  const double ca = std::cos(a.p[3]), sa = std::sin(a.p[3]), cb = std::cos(a.p[4]),
               sb = std::sin(a.p[4]);
  const double E[3][3] = {{1.0, 0.0, sb}, {0.0, ca, -sa * cb}, {0.0, sa, ca * cb}};
  // column j of (v, w): p_j' = 1
  const auto motion = [&](int j, double* v, double* w) {
    for (int i = 0; i < 3; ++i) v[i] = j == i ? 1.0 : 0.0, w[i] = j >= 3 ? E[i][j - 3] : 0.0;
  };
  // -R^T (v + w x (x - t)) for the 6 columns: rhs (3, 6)
  const auto held = [&](const double* x, double* rhs) {
    const double d[3] = {x[0] - T[3], x[1] - T[7], x[2] - T[11]};
    for (int j = 0; j < 6; ++j) {
      double v[3], w[3];
      motion(j, v, w);
      const double u[3] = {v[0] + w[1] * d[2] - w[2] * d[1], v[1] + w[2] * d[0] - w[0] * d[2],
                           v[2] + w[0] * d[1] - w[1] * d[0]};
      for (int i = 0; i < 3; ++i)
        rhs[6 * i + j] = -(T[i] * u[0] + T[4 + i] * u[1] + T[8 + i] * u[2]);
    }
  };
  for (int l = 0; l < s.legs; ++l) {
    const auto& col = s.robot.body.columns[std::size_t(l)];
    double J[9], foot[3], rhs[18];
    std::copy_n(J_legs[l], 9, J);
    to_stance(s.in.feet + 3 * l, foot);
    held(foot, rhs);
    if (!lu_solve<3, 6>(J, rhs)) return false;
    for (int i = 0; i < 3; ++i) std::copy_n(rhs + 6 * i, 6, dq + 6 * col[i]);
  }
  double J[36], target[3], rhs[36];
  std::copy_n(J_arm, 36, J);
  {  // the target's position in S (its column 3)
    const double p_t[3] = {s.in.target[3], s.in.target[7], s.in.target[11]};
    to_stance(p_t, target);
  }
  held(target, rhs);
  for (int j = 0; j < 6; ++j) {  // -R^T w
    double v[3], w[3];
    motion(j, v, w);
    for (int i = 0; i < 3; ++i)
      rhs[6 * (3 + i) + j] = -(T[i] * w[0] + T[4 + i] * w[1] + T[8 + i] * w[2]);
  }
  if (!lu_solve<6, 6>(J, rhs)) return false;
  std::copy_n(rhs, 36, dq + 6 * n3);
  return true;
}

// (R): Gauss-Newton steps on p, for every active target at once: each step's line search tries
// alpha = 1, 1/2, 1/4 in turn, the targets still without a step evaluated together.
template <typename Model>
void refine(const Search<Model>* S, Answer* A, const int* active_in, int count) {
  const int m = S[0].m;
  std::vector<int> active(active_in, active_in + count), pending, taken;
  static thread_local Evaluation ev;  // kept from call to call
  double r0[6 + kReachMaxQ], dq[6 * kReachMaxQ], q_new[kReachBlock * kReachMaxQ];
  double g[kReachBlock][6];
  bool ok_new[kReachBlock];
  const int legs = S[0].legs, n3 = 3 * legs;
  double leg_q[3 * kReachBlock], J_legs[9 * Body::kMaxLegs * kReachBlock];
  double arm_q[6 * kReachBlock], J_arm[36 * kReachBlock];
  static thread_local Checks checks;
  for (int step = 0; step < S[0].sh.refine_steps && !active.empty(); ++step) {
    pending.clear(), taken.clear();
    const int n_active = int(active.size());
    for (int l = 0; l < legs; ++l) {  // the Jacobians of every active target, one call each
      const auto& col = S[0].robot.body.columns[std::size_t(l)];
      for (int i = 0; i < n_active; ++i)
        for (int j = 0; j < 3; ++j)
          leg_q[std::size_t(3 * i + j)] = A[active[std::size_t(i)]].q[col[j]];
      kernels::leg_jacobian(S[0].robot.body.legs[std::size_t(l)], leg_q,
                            &J_legs[std::size_t(9 * n_active * l)], n_active);
    }
    for (int i = 0; i < n_active; ++i)
      std::copy_n(A[active[std::size_t(i)]].q + n3, 6, &arm_q[std::size_t(6 * i)]);
    kernels::chain_jacobian(*S[0].arm.chain, arm_q, J_arm, n_active, 6, false);
    for (int i = 0; i < n_active; ++i) {
      const int t = active[std::size_t(i)];
      const Search<Model>& s = S[t];
      const Answer& a = A[t];
      residual(s, a.p, a.q, r0);
      const double* J_leg[Body::kMaxLegs];
      for (int l = 0; l < legs; ++l) J_leg[l] = &J_legs[std::size_t(9 * (n_active * l + i))];
      if (!sensitivities(s, a, J_leg, &J_arm[std::size_t(36 * i)], dq)) continue;
      // J = [diag(1 / w_p); dq / w_q]: J^T J + mu I and -J^T r0
      double M[36], *gt = g[t];
      for (int i = 0; i < 6; ++i) {
        gt[i] = -r0[std::size_t(i)] / s.sh.w_p[i];
        for (int j = 0; j < 6; ++j)
          M[6 * i + j] = (i == j ? 1.0 / (s.sh.w_p[i] * s.sh.w_p[i]) + kReachGnDamping : 0.0);
      }
      for (int k = 0; k < m; ++k) {  // the rows u = dq_k / w_q: M += u u^T (its upper half)
        const double* row = &dq[std::size_t(6 * k)];
        const double inv = 1.0 / s.sh.w_q[k], r = r0[std::size_t(6 + k)];
        double u[6];
        for (int i = 0; i < 6; ++i) u[i] = row[i] * inv, gt[i] -= u[i] * r;
        for (int i = 0; i < 6; ++i)
          for (int j = i; j < 6; ++j) M[6 * i + j] += u[i] * u[j];
      }
      for (int i = 1; i < 6; ++i)
        for (int j = 0; j < i; ++j) M[6 * i + j] = M[6 * j + i];
      if (cholesky_solve<6>(M, gt)) pending.push_back(t);
    }
    for (const double alpha : {1.0, 0.5, 0.25}) {
      if (pending.empty()) break;
      const int n = int(pending.size());
      ev.resize(n, S[0].legs);
      for (int i = 0; i < n; ++i) {
        const int t = pending[std::size_t(i)];
        ev.owner[std::size_t(i)] = t;
        for (int k = 0; k < 6; ++k)
          ev.p[std::size_t(6 * i + k)] =
              std::min(std::max(A[t].p[k] + alpha * g[t][k], S[t].sh.lower[k]), S[t].sh.upper[k]);
      }
      follow(S, A, ev, q_new, ok_new);
      // cheaper, then within the margin (one call for all), then free of collisions (one call)
      double cost[kReachBlock], margin[kReachBlock];
      int index[kReachBlock], n_cheaper = 0, n_stable = 0;
      checks.resize(n, m, arm_dof(S[0]));
      for (int i = 0; i < n; ++i) {
        const int t = pending[std::size_t(i)];
        cost[i] =
            ok_new[i] ? cost_of(S[t], &ev.p[std::size_t(6 * i)], &q_new[std::size_t(m * i)]) : kNan;
        if (!(cost[i] < A[t].cost)) continue;
        index[n_cheaper] = i, checks.owner[std::size_t(n_cheaper)] = t;
        std::copy_n(&ev.T[std::size_t(16 * i)], 16, &checks.T[std::size_t(16 * n_cheaper)]);
        std::copy_n(&q_new[std::size_t(m * i)], m, &checks.q[std::size_t(m * n_cheaper)]);
        ++n_cheaper;
      }
      if (n_cheaper) margins_of(S, checks, n_cheaper);
      for (int j = 0; j < n_cheaper; ++j) {
        const int t = checks.owner[std::size_t(j)];
        margin[index[j]] = checks.margin[std::size_t(j)];
        if (!(checks.margin[std::size_t(j)] >= S[t].in.margin)) continue;
        if (n_stable != j) {
          index[n_stable] = index[j], checks.owner[std::size_t(n_stable)] = t;
          std::copy_n(&checks.T[std::size_t(16 * j)], 16, &checks.T[std::size_t(16 * n_stable)]);
          std::copy_n(&checks.q[std::size_t(m * j)], m, &checks.q[std::size_t(m * n_stable)]);
        }
        ++n_stable;
      }
      if (n_stable) collisions_of(S, checks, n_stable);
      bool accept[kReachBlock] = {};
      for (int j = 0; j < n_stable; ++j) accept[index[j]] = checks.hits[std::size_t(j)] == 0;
      std::size_t kept = 0;
      for (int i = 0; i < n; ++i) {
        const int t = pending[std::size_t(i)];
        if (!accept[i]) {
          pending[kept++] = t;
          continue;
        }
        Answer& a = A[t];
        std::copy_n(&ev.p[std::size_t(6 * i)], 6, a.p);
        std::copy_n(&q_new[std::size_t(m * i)], m, a.q);
        std::copy_n(&ev.T[std::size_t(16 * i)], 16, a.T);
        std::copy_n(&ev.L[std::size_t(16 * i)], 16, a.L);
        branches_from(ev, i, a.branches, a.valid);
        a.slot = ev.arm_status[std::size_t(i)], a.cost = cost[i], a.margin = margin[i];
        taken.push_back(t);
      }
      pending.resize(kept);
    }
    std::sort(taken.begin(), taken.end());
    active.swap(taken);  // a target without a step stops
  }
}

// The hand's error e (6) from world <- body T_body and body <- hand T_arm: the target's
// position minus the hand's, and the rotation vector of R_target R_hand^T, times the scale.
template <typename Model>
void hand_error(const Search<Model>& s, const double* T_body, const double* T_arm, double* e) {
  const double* t = s.in.target;
  double T_hand[16], R[9];  // R_target R_hand^T
  mul4(T_body, T_arm, T_hand);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      R[3 * i + j] = t[4 * i] * T_hand[4 * j] + t[4 * i + 1] * T_hand[4 * j + 1] +
                     t[4 * i + 2] * T_hand[4 * j + 2];
  for (int i = 0; i < 3; ++i) e[i] = t[4 * i + 3] - T_hand[4 * i + 3];
  rotation_log(R, e + 3);
  for (int i = 3; i < 6; ++i) e[i] *= s.sh.scale;
}

// (F)'s hand error at z (12): e (6).
template <typename Model>
void hand_errors(const Search<Model>& s, const double* z, double* e) {
  double T_arm[16], T_body[16];
  kernels::chain_fk(*s.arm.chain, z + 6, T_arm, 1);
  body_T(s, z, T_body);
  hand_error(s, T_body, T_arm, e);
}

// The hand errors at z + FD_STEP along each of the 12 axes: es (12, 6). A body column moves the
// body only, an arm column the arm only: 7 body transforms and 7 arm poses.
template <typename Model>
void hand_error_columns(const Search<Model>& s, const double* z, double* es) {
  double arm_q[7 * 6], T_arm[7 * 16], T_body[7 * 16];
  for (int j = 0; j < 7; ++j) {
    double p[6];
    std::copy_n(z + 6, 6, arm_q + 6 * j), std::copy_n(z, 6, p);
    if (j > 0) arm_q[6 * j + j - 1] += kReachFdStep, p[j - 1] += kReachFdStep;
    body_T(s, p, T_body + 16 * j);
  }
  kernels::chain_fk(*s.arm.chain, arm_q, T_arm, 7);
  for (int j = 0; j < 6; ++j) {
    hand_error(s, T_body + 16 * (1 + j), T_arm, es + 6 * j);        // body axis j
    hand_error(s, T_body, T_arm + 16 * (1 + j), es + 6 * (6 + j));  // arm axis j
  }
}

template <typename Model>
bool legs_ok_at(const Search<Model>& s, const double* p) {
  double T[16], q[kReachMaxQ];
  std::int8_t status[Body::kMaxLegs];
  body_T(s, p, T);
  kernels::body_ik(s.robot.body, T, BodyPoseFormat::Matrix, xyz_sequence(), s.in.feet, true,
                   static_cast<const double*>(nullptr), q, status, 1, false);
  for (int l = 0; l < s.legs; ++l)
    if (status[l] != 0) return false;
  return true;
}

// (E) at the body pose z[0..6] into `end` (n = 1, the legs' nearest fallback as the reference's);
// whether an option there is feasible.
template <typename Model>
bool answers_at(const Search<Model>& s, const double* z, int order, Evaluation& end) {
  end.resize(1, s.legs);
  std::copy_n(z, 6, end.p.data());
  run(&s, end, nullptr, true);
  std::vector<Option> options;
  options_of(s, end, 0, 1, order, options, nullptr);
  std::int8_t status;
  choose(s, options, status);
  return status == kReachOk;
}

// (F)'s damped least squares from z (12): z and e (6) in place.
template <typename Model>
void descend(const Search<Model>& s, double* z, double* e, int order, Evaluation& end) {
  const int n3 = 3 * s.legs;
  double lower[12], upper[12];
  for (int k = 0; k < 6; ++k) {
    lower[k] = s.sh.lower[k], upper[k] = s.sh.upper[k];
    lower[6 + k] = s.sh.q_lower[n3 + k] + kReachRepairInset,
              upper[6 + k] = s.sh.q_upper[n3 + k] - kReachRepairInset;
  }
  for (int k = 0; k < 12; ++k) z[k] = std::min(std::max(z[k], lower[k]), upper[k]);
  hand_errors(s, z, e);
  double lam = kReachRepairDamping;
  double es[12 * 6];
  const auto norm2 = [](const double* v) {
    double sum = 0.0;
    for (int k = 0; k < 6; ++k) sum += v[k] * v[k];
    return sum;
  };
  for (int it = 0; it < kReachRepairIterations; ++it) {
    if (norm2(e) < 1e-24 || lam > kReachRepairStall) break;
    hand_error_columns(s, z, es);
    double J[6][12];  // d hand / dz = -d e / dz, forward differences
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 6; ++i) J[i][j] = -(es[6 * j + i] - e[i]) / kReachFdStep;
    double toward[12] = {};
    for (int k = 0; k < 6; ++k) toward[k] = kReachNullGain * (s.sh.nominal[k] - z[k]);
    bool free_[12];
    std::fill(free_, free_ + 12, true);
    double delta[12] = {};
    for (int pass = 0; pass < kReachActiveSetPasses; ++pass) {
      double Jf[6][12];
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 12; ++j) Jf[i][j] = free_[j] ? J[i][j] : 0.0;
      double A[36], X[36];  // X = (Jf Jf^T + lam^2 I)^-1
      for (int i = 0; i < 6; ++i)
        for (int j = 0; j < 6; ++j) {
          double sum = 0.0;
          for (int k = 0; k < 12; ++k) sum += Jf[i][k] * Jf[j][k];
          A[6 * i + j] = sum + (i == j ? lam * lam : 0.0);
          X[6 * i + j] = i == j ? 1.0 : 0.0;
        }
      cholesky_solve<6, 6>(A, X);
      double P[12][6];  // pinv = Jf^T X
      for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 6; ++j) {
          double sum = 0.0;
          for (int k = 0; k < 6; ++k) sum += Jf[k][i] * X[6 * k + j];
          P[i][j] = sum;
        }
      double secondary[12];
      for (int k = 0; k < 12; ++k) secondary[k] = free_[k] ? toward[k] : 0.0;
      double Jy[6];  // Jf secondary
      for (int i = 0; i < 6; ++i) {
        Jy[i] = 0.0;
        for (int k = 0; k < 12; ++k) Jy[i] += Jf[i][k] * secondary[k];
      }
      bool held_any = false;
      bool held[12];
      for (int i = 0; i < 12; ++i) {
        double d = secondary[i];
        for (int k = 0; k < 6; ++k) d += P[i][k] * (e[k] - Jy[k]);
        delta[i] = d;
      }
      for (int i = 0; i < 12; ++i) {
        held[i] = free_[i] &&
                  ((z[i] <= lower[i] && delta[i] < 0.0) || (z[i] >= upper[i] && delta[i] > 0.0));
        held_any = held_any || held[i];
      }
      if (!held_any) break;
      for (int i = 0; i < 12; ++i) free_[i] = free_[i] && !held[i];
    }
    double z_new[12], e_new[6];
    for (int k = 0; k < 12; ++k) z_new[k] = std::min(std::max(z[k] + delta[k], lower[k]), upper[k]);
    hand_errors(s, z_new, e_new);
    if (norm2(e_new) < std::max(norm2(e), 1e-24) && legs_ok_at(s, z_new)) {  // cheap test first
      std::copy_n(z_new, 12, z), std::copy_n(e_new, 6, e);
      lam /= 3.0;
    } else {
      lam *= 3.0;
    }
    if ((it + 1) % kReachRepairCheck == 0 && answers_at(s, z, order, end)) return;
  }
  answers_at(s, z, order, end);
}

}  // namespace spotkin::motion::search
