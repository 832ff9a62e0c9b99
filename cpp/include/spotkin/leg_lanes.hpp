// Leg kernels whose lanes hold different legs (body_batch::ik_pairs: a few poses of a body, each
// (pose, leg) pair in its own lane). Each lane runs the operations of the one-leg kernels of
// leg.hpp (leg_block_slot, solve_slots) with its own leg's constants, so that a pair's answer is
// the bits the batch gives it.
#pragma once

#include <cstddef>

#include "spotkin/leg.hpp"

namespace spotkin::leg_batch {

// The constants of up to N legs, one per lane (SoA).
template <std::ptrdiff_t N>
struct LegLanes {
  double a0[N], a2[N], h[N], h2[N], Bz[N], Bx[N], Cz[N], Cx[N];
  double phi[N], cos_phi[N], sin_phi[N], knee_sum_sq[N], inv_2BC[N];
  double sign1[N], sign2[N], sign3[N], lower[3][N], upper[3][N];
  bool may_turn = false;  // some lane's limits may turn an angle (JointLimits::may_turn)

  void set(std::ptrdiff_t i, const Leg& leg) noexcept {
    may_turn = may_turn || leg.limits().may_turn();
    const RppConstants& k = leg.constants();
    a0[i] = k.a0, a2[i] = k.a2, h[i] = k.h, h2[i] = k.h2, Bz[i] = k.Bz, Bx[i] = k.Bx, Cz[i] = k.Cz,
    Cx[i] = k.Cx;
    phi[i] = k.phi, cos_phi[i] = k.cos_phi, sin_phi[i] = k.sin_phi;
    knee_sum_sq[i] = k.knee_sum_sq, inv_2BC[i] = k.inv_2BC;
    sign1[i] = k.sign1, sign2[i] = k.sign2, sign3[i] = k.sign3;
    for (int j = 0; j < 3; ++j)
      lower[j][i] = leg.limits().lower[j], upper[j][i] = leg.limits().upper[j];
  }
  SPOTKIN_INLINE RppConstants at(std::ptrdiff_t i) const noexcept {
    RppConstants k;
    k.a0 = a0[i], k.a2 = a2[i], k.h = h[i], k.h2 = h2[i], k.Bz = Bz[i], k.Bx = Bx[i], k.Cz = Cz[i],
    k.Cx = Cx[i];
    k.phi = phi[i], k.cos_phi = cos_phi[i], k.sin_phi = sin_phi[i];
    k.knee_sum_sq = knee_sum_sq[i], k.inv_2BC = inv_2BC[i];
    k.sign1 = sign1[i], k.sign2 = sign2[i], k.sign3 = sign3[i];
    return k;
  }
};

// slot_pass with lane i solved for the leg L holds in lane i (m <= N), all in one slot: the same
// operations on each lane as leg_block_slot for that leg alone. ok[i] = 1 where the slot exists
// and fits the limits; exists[i] -1 for a non-finite target. Bound: also each lane's
// slot_separation (bound), as leg_block gives it. Turn: as leg_block_slot's (L.may_turn); the
// same code as that kernel's, so that the compiler fuses the same multiply-adds in both.
template <bool Bound, bool Turn, std::ptrdiff_t N, typename C>
SPOTKIN_INLINE void slot_pass_lanes(const LegLanes<N>& __restrict L, Leg::SlotSigns<C> signs,
                                    const C* __restrict x, const C* __restrict y,
                                    const C* __restrict z, std::ptrdiff_t m, C tol, C limit_tol,
                                    C (*__restrict q)[kBlock], C* __restrict exists,
                                    C* __restrict ok, C* __restrict bound = nullptr) noexcept {
  Leg::SlotStages<C, kBlock> st;
  for (std::ptrdiff_t i = 0; i < m; ++i) Leg::slot_hip_with(L.at(i), i, y[i], z[i], tol, signs, st);
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    const RppConstants k = L.at(i);
    Leg::slot_knee_with(k, i, x[i], tol, signs, st);
    C qi[3];
    const C finite = finite_mask(x[i], y[i], z[i]);
    const C e = finite * Leg::slot_angles_with(k, i, x[i], y[i], z[i], st, qi);
    const double lower[3] = {L.lower[0][i], L.lower[1][i], L.lower[2][i]};
    const double upper[3] = {L.upper[0][i], L.upper[1][i], L.upper[2][i]};
    ok[i] = e * JointLimits<3>::wrap_mask_within<Turn>(lower, upper, qi, limit_tol);
    exists[i] = finite == C(0) ? C(-1) : e;
    q[0][i] = qi[0], q[1][i] = qi[1], q[2][i] = qi[2];
    if constexpr (Bound) bound[i] = Leg::slot_separation_with(k, i, st);
  }
}

// slot_pass_lanes in the lanes' shared preferred slot (0 .. 3), with or without turns (L.may_turn).
template <bool Bound, std::ptrdiff_t N, typename C>
SPOTKIN_INLINE void preferred_pass_lanes(const LegLanes<N>& __restrict L, int slot,
                                         const C* __restrict x, const C* __restrict y,
                                         const C* __restrict z, std::ptrdiff_t m, C tol,
                                         C limit_tol, C (*__restrict q)[kBlock],
                                         C* __restrict exists, C* __restrict ok,
                                         C* __restrict bound) noexcept {
  const Leg::SlotSigns<C> signs = Leg::slot_signs<C>(slot);
  with_turn(L.may_turn, [&](auto turn) SPOTKIN_LAMBDA_INLINE {
    slot_pass_lanes<Bound, decltype(turn)::value>(L, signs, x, y, z, m, tol, limit_tol, q, exists,
                                                  ok, bound);
  });
}

// solve_slots with lane i solved for the leg L holds in lane i (m <= N): the same operations on
// each lane as solve_slots for that leg alone, so the same answers to the bit. SharedKnee: every
// lane's leg has a_z = 0.
template <bool SharedKnee, std::ptrdiff_t N, typename C>
SPOTKIN_INLINE void solve_slots_lanes(const LegLanes<N>& __restrict L, const C* __restrict x,
                                      const C* __restrict y, const C* __restrict z,
                                      std::ptrdiff_t m, C tol, C limit_tol,
                                      C (*__restrict q)[3][kBlock], C (*__restrict ok)[kBlock],
                                      C (*__restrict exists_hip)[kBlock]) noexcept {
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    C q_all[Leg::kSlots][3], e[2];
    Leg::solve_all_with<SharedKnee>(L.at(i), x[i], y[i], z[i], q_all, e, tol);
    exists_hip[0][i] = e[0], exists_hip[1][i] = e[1];
#pragma GCC unroll 4
    for (int s = 0; s < Leg::kSlots; ++s)
#pragma GCC unroll 3
      for (int j = 0; j < 3; ++j) q[s][j][i] = q_all[s][j];
  }
#pragma GCC unroll 4
  for (int s = 0; s < Leg::kSlots; ++s) {
    for (std::ptrdiff_t i = 0; i < m; ++i) {
      C qi[3] = {q[s][0][i], q[s][1][i], q[s][2][i]};
      const double lower[3] = {L.lower[0][i], L.lower[1][i], L.lower[2][i]};
      const double upper[3] = {L.upper[0][i], L.upper[1][i], L.upper[2][i]};
      ok[s][i] =
          exists_hip[s / 2][i] * JointLimits<3>::wrap_mask_within(lower, upper, qi, limit_tol);
      q[s][0][i] = qi[0], q[s][1][i] = qi[1], q[s][2][i] = qi[2];
    }
  }
}

}  // namespace spotkin::leg_batch
