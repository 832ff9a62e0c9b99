// Whole-body reach (spotkin/motion/reach.hpp): python/spotkin/reference/reach.py step for step, in
// double. A target's candidates go through the batched body and arm kernels in one call each; the
// options (cpp/src/reach_search.hpp), the Gauss-Newton refinement and the repair
// (cpp/src/reach_steps.cpp) are scalar code over them.
#include <algorithm>
#include <cmath>
#include <vector>

#include "reach_search.hpp"

namespace spotkin::motion {

using namespace search;  // NOLINT: the search's steps

template <typename Model>
void reach_target(const dynamics::RobotStaticsModel<Model>& robot, const ReachArm& arm,
                  const ReachCapsules& capsules, const ReachShared& shared, const ReachInput& in,
                  const ReachOutput& out) {
  const int legs = robot.body.n_legs(), m = shared.m, n3 = 3 * legs;
  const auto invalid = [&] {
    std::fill(out.body_pose, out.body_pose + 6, kNan), std::fill(out.q, out.q + m, kNan);
    *out.status = kReachInvalid, *out.margin = *out.distance = *out.angle = kNan;
    std::fill(out.branches, out.branches + 48, kNan),
        std::fill(out.valid, out.valid + 8, std::uint8_t(0));
    *out.slot = -1;
  };
  {  // a finite rigid target (ref.rigid), finite feet, margin and references
    const double* T = in.target;
    bool ok = std::isfinite(in.margin);
    for (int k = 0; k < 16; ++k) ok = ok && std::isfinite(T[k]);
    for (int k = 0; k < 3 * legs; ++k) ok = ok && std::isfinite(in.feet[k]);
    for (int k = 0; k < 6; ++k)
      ok = ok && std::isfinite(in.p_ref[k]) && (!in.seed_pose || std::isfinite(in.seed_pose[k]));
    for (int k = 0; k < m; ++k) ok = ok && std::isfinite(in.q_ref[k]);
    if (ok) {
      double last = 0.0, ortho = 0.0;
      for (int k = 0; k < 4; ++k) last = std::max(last, std::abs(T[12 + k] - (k == 3 ? 1.0 : 0.0)));
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
          const double d =
              T[i] * T[j] + T[4 + i] * T[4 + j] + T[8 + i] * T[8 + j] - (i == j ? 1.0 : 0.0);
          ortho = std::max(ortho, std::abs(d));
        }
      const double det = T[0] * (T[5] * T[10] - T[6] * T[9]) - T[1] * (T[4] * T[10] - T[6] * T[8]) +
                         T[2] * (T[4] * T[9] - T[5] * T[8]);
      ok = last <= 1e-6 && ortho <= 1e-6 && det > 0.0;
    }
    if (!ok) return invalid();
  }
  const Search<Model> s{robot, arm, capsules, shared, in, legs, m};
  // (C), (E), (A): stage by stage, until an option is feasible
  const int first = (in.seed_pose ? 1 : 0) + 1;
  const int sizes[3] = {first, kReachStageTwo, kReachCandidates - kReachStageTwo};
  Evaluation stages[3];
  std::vector<int> order(std::size_t(first + kReachCandidates));
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = int(k);
  std::vector<Option> options;
  options.reserve(
      std::size_t(8 * (first + kReachCandidates)));  // no reallocation: options point at stages
  std::vector<Miss> misses;
  std::int8_t status = kReachUnreachable;
  int chosen = -1, halton = 0, next_order = 0;
  for (int stage = 0; stage < 3; ++stage) {
    Evaluation& ev = stages[stage];
    ev.resize(sizes[stage], legs);
    for (int j = 0; j < sizes[stage]; ++j) {
      double* p = &ev.p[std::size_t(6 * j)];
      if (stage == 0 && in.seed_pose && j == 0) {
        for (int k = 0; k < 6; ++k)
          p[k] = std::min(std::max(in.seed_pose[k], shared.lower[k]), shared.upper[k]);
      } else if (stage == 0) {
        std::copy_n(shared.nominal, 6, p);
      } else {
        for (int k = 0; k < 6; ++k)
          p[k] = shared.lower[k] + shared.halton[halton][k] * (shared.upper[k] - shared.lower[k]);
        ++halton;
      }
    }
    run(s, ev);
    options_of(s, ev, order.data() + next_order, options, &misses);
    next_order += sizes[stage];
    chosen = choose(s, options, status);
    if (status == kReachOk) break;
  }
  Answer a{};
  a.slot = -1;
  std::vector<int> start_order(kReachRepairStarts);
  for (int k = 0; k < kReachRepairStarts; ++k) start_order[std::size_t(k)] = k;
  std::vector<Evaluation> ends;  // the repair's ends (the chosen option may point at one)
  std::vector<Option> repaired;
  const Option* picked = chosen >= 0 ? &options[std::size_t(chosen)] : nullptr;
  double nearest_e[6] = {};
  if (!picked && !in.repair) {
    std::fill(out.body_pose, out.body_pose + 6, kNan), std::fill(out.q, out.q + m, kNan);
    *out.status = kReachUnreachable, *out.margin = *out.distance = *out.angle = kNan;
    std::fill(out.branches, out.branches + 48, kNan),
        std::fill(out.valid, out.valid + 8, std::uint8_t(0));
    *out.slot = -1;
    return;
  }
  if (!picked) {  // (F)
    double lo[6], hi[6];
    for (int k = 0; k < 6; ++k) {
      lo[k] = std::isfinite(shared.q_lower[n3 + k]) ? shared.q_lower[n3 + k] : -kPi;
      hi[k] = std::isfinite(shared.q_upper[n3 + k]) ? shared.q_upper[n3 + k] : kPi;
    }
    std::stable_sort(misses.begin(), misses.end(), [](const Miss& x, const Miss& y) {
      if (x.violation != y.violation) return x.violation < y.violation;
      if (x.order != y.order) return x.order < y.order;
      return x.slot < y.slot;
    });
    double z[kReachRepairStarts][12], e[kReachRepairStarts][6];
    int count = 0;
    std::copy_n(shared.nominal, 6, z[count]);
    for (int k = 0; k < 6; ++k) z[count][6 + k] = std::min(std::max(0.0, lo[k]), hi[k]);
    ++count;
    for (std::size_t j = 0; j < misses.size() && count < kReachRepairStarts; ++j, ++count) {
      std::copy_n(misses[j].p, 6, z[count]);
      for (int k = 0; k < 6; ++k)
        z[count][6 + k] = std::min(std::max(misses[j].q_arm[k], lo[k]), hi[k]);
    }
    for (int u = 0; count < kReachRepairStarts; ++u, ++count) {
      std::copy_n(shared.nominal, 6, z[count]);
      for (int k = 0; k < 6; ++k) z[count][6 + k] = lo[k] + shared.halton[u][k] * (hi[k] - lo[k]);
    }
    ends.resize(kReachRepairStarts);  // sized once: the options point at them
    repaired.reserve(8 * kReachRepairStarts);
    int ran = 0;
    for (int j = 0; j < kReachRepairStarts; ++j) {  // start by start, until one ends feasible
      descend(s, z[j], e[j], j, ends[std::size_t(j)]);
      ++ran;
      options_of(s, ends[std::size_t(j)], start_order.data() + j, repaired, nullptr);
      chosen = choose(s, repaired, status);
      if (status == kReachOk) break;
    }
    picked = chosen >= 0 ? &repaired[std::size_t(chosen)] : nullptr;
    if (!picked) {  // the nearest the repair came (ties to the earlier start)
      int best = 0;
      double best_e = kInf;
      for (int j = 0; j < ran; ++j) {
        double sum = 0.0;
        for (int k = 0; k < 6; ++k) sum += e[j][k] * e[j][k];
        if (sum < best_e) best_e = sum, best = j;
      }
      const Evaluation& end = ends[std::size_t(best)];
      std::copy_n(z[best], 6, a.p);
      std::copy_n(end.legs.data(), n3, a.q);
      std::copy_n(z[best] + 6, 6, a.q + n3);
      std::copy_n(end.T.data(), 16, a.T);
      a.margin = margin_of(s, a.T, a.q);
      std::copy_n(e[best], 6, nearest_e);
      status = kReachUnreachable;
    }
  }
  if (picked) {
    const Evaluation& ev = *picked->ev;
    std::copy_n(&ev.p[std::size_t(6 * picked->pose)], 6, a.p);
    whole_q(s, ev, picked->pose, picked->slot, a.q);
    std::copy_n(&ev.T[std::size_t(16 * picked->pose)], 16, a.T);
    a.slot = picked->slot, a.cost = picked->cost, a.margin = picked->margin;
    if (status == kReachOk && in.refine) refine(s, a);
  }
  // the answer
  pose_of(a.T, out.body_pose);
  std::copy_n(a.q, m, out.q);
  *out.status = status, *out.margin = a.margin,
  *out.slot = status == kReachUnreachable ? -1 : a.slot;
  if (status == kReachUnreachable) {
    // hypot: a target far beyond reach (1e300 m) still gets a finite distance
    *out.distance = std::hypot(std::hypot(nearest_e[0], nearest_e[1]), nearest_e[2]);
    *out.angle = std::hypot(std::hypot(nearest_e[3], nearest_e[4]), nearest_e[5]) / shared.scale;
  } else {
    *out.distance = *out.angle = 0.0;
  }
  double target[16], exact[8];
  std::uint8_t exists[8], exact_flags[8];
  std::int8_t arm_status;
  (void)exact;
  arm_target(s, a.T, target);
  arm_ik_all(arm, target, out.branches, out.valid, exists, exact_flags, &arm_status, 1);
}

template <typename Model>
void reach_constraints(const dynamics::RobotStaticsModel<Model>& robot, const ReachArm& arm,
                       const ReachCapsules& capsules, const ReachShared& shared,
                       const double* T_body, const double* q, const double* feet, double* margin,
                       bool* hits) {
  const double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  const double zeros[kReachMaxQ] = {};
  const ReachInput in{identity, feet, identity, zeros, zeros, nullptr, 0.0};
  const Search<Model> s{robot, arm, capsules, shared, in, robot.body.n_legs(), shared.m};
  *margin = margin_of(s, T_body, q);
  *hits = collides(s, q, T_body);
}

#define SPOTKIN_INSTANTIATE(L)                                                                 \
  template void reach_target<dynamics::FloatingModel<double, L>>(                              \
      const dynamics::RobotStaticsModel<dynamics::FloatingModel<double, L>>&, const ReachArm&, \
      const ReachCapsules&, const ReachShared&, const ReachInput&, const ReachOutput&);        \
  template void reach_constraints<dynamics::FloatingModel<double, L>>(                         \
      const dynamics::RobotStaticsModel<dynamics::FloatingModel<double, L>>&, const ReachArm&, \
      const ReachCapsules&, const ReachShared&, const double*, const double*, const double*,   \
      double*, bool*);
SPOTKIN_INSTANTIATE(dynamics::kLanes64)
SPOTKIN_INSTANTIATE(dynamics::kMidLanes64)
SPOTKIN_INSTANTIATE(dynamics::kSmallLanes64)
#undef SPOTKIN_INSTANTIATE

}  // namespace spotkin::motion
