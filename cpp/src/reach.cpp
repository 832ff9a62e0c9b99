// Whole-body reach (spotkin/motion/reach.hpp): python/spotkin/reference/reach.py step for step, in
// double. The targets of a block go through each step together: a stage's candidates of every
// target still searching, and a Gauss-Newton step's line search of every target, in one call of
// the batched body and arm kernels each; the options (cpp/src/reach_search.hpp), the refinement's
// normal equations and the repair (cpp/src/reach_steps.cpp) are scalar code, target by target.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "reach_search.hpp"
#include "reach_steps.hpp"
#include "spotkin/isa.hpp"

namespace spotkin::motion {

using namespace search;  // NOLINT: the search's steps

// The candidates' points of the box: p = lower + u (upper - lower) for (C)'s unit point u.
void candidate_pose(const ReachShared& shared, int k, double* p) {
  for (int i = 0; i < 6; ++i)
    p[i] = shared.lower[i] + shared.halton[k][i] * (shared.upper[i] - shared.lower[i]);
}

void prepare_shared(ReachShared& shared) {
  body_batch::pose_transform(shared.nominal, BodyPoseFormat::Euler, xyz_sequence(),
                             shared.local[0]);
  for (int k = 0; k < kReachCandidates; ++k) {
    double p[6];
    candidate_pose(shared, k, p);
    body_batch::pose_transform(p, BodyPoseFormat::Euler, xyz_sequence(), shared.local[1 + k]);
  }
}

namespace {

// ref.rigid: a finite rigid target, and finite feet, margin and references.
bool valid_input(const ReachInput& in, int legs, int m) {
  const double* T = in.target;
  bool ok = std::isfinite(in.margin);
  for (int k = 0; k < 16; ++k) ok = ok && std::isfinite(T[k]);
  for (int k = 0; k < 3 * legs; ++k) ok = ok && std::isfinite(in.feet[k]);
  for (int k = 0; k < 6; ++k)
    ok = ok && std::isfinite(in.p_ref[k]) && (!in.seed_pose || std::isfinite(in.seed_pose[k]));
  for (int k = 0; k < m; ++k) ok = ok && std::isfinite(in.q_ref[k]);
  if (!ok) return false;
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
  return last <= 1e-6 && ortho <= 1e-6 && det > 0.0;
}

// NaN answers with a status (INVALID_INPUT, or UNREACHABLE without the repair).
void no_answer(const ReachOutput& out, int m, std::int8_t status) {
  std::fill(out.body_pose, out.body_pose + 6, kNan), std::fill(out.q, out.q + m, kNan);
  *out.status = status, *out.margin = *out.distance = *out.angle = kNan;
  std::fill(out.branches, out.branches + 48, kNan),
      std::fill(out.valid, out.valid + 8, std::uint8_t(0));
  *out.slot = -1;
}

// A target's search in its block.
struct Target {
  bool searching = false, answered = false;  // in (C) .. (A); has an answer to write
  std::vector<Option> options;               // point at the block's stage evaluations
  std::vector<Miss> misses;
  std::int8_t status = kReachUnreachable;
  int chosen = -1, next_order = 0, begin = 0, size = 0;
  std::vector<Evaluation> ends;  // the repair's ends (the chosen option may point at one)
  std::vector<Option> repaired;
  double nearest_e[6] = {};
  void reset() {  // a new target (the vectors keep their memory)
    searching = answered = false, status = kReachUnreachable;
    chosen = -1, next_order = begin = size = 0;
    options.clear(), misses.clear(), ends.clear(), repaired.clear();
    std::fill(nearest_e, nearest_e + 6, 0.0);
  }
};

// A thread's memory for its blocks, kept from block to block.
struct BlockScratch {
  Target targets[kReachBlock];
  Evaluation stages[3];
  Checks checks;
};

// (F) for a target no candidate reaches: the repaired answer, or the nearest the repair came.
template <typename Model>
void repair(const Search<Model>& s, Target& t, Answer& a) {
  const ReachShared& shared = s.sh;
  const int n3 = 3 * s.legs;
  double lo[6], hi[6];
  for (int k = 0; k < 6; ++k) {
    lo[k] = std::isfinite(shared.q_lower[n3 + k]) ? shared.q_lower[n3 + k] : -kPi;
    hi[k] = std::isfinite(shared.q_upper[n3 + k]) ? shared.q_upper[n3 + k] : kPi;
  }
  std::vector<Miss>& misses = t.misses;
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
  t.ends.resize(kReachRepairStarts);  // sized once: the options point at them
  t.repaired.reserve(8 * kReachRepairStarts);
  int ran = 0;
  for (int j = 0; j < kReachRepairStarts; ++j) {  // start by start, until one ends feasible
    descend(s, z[j], e[j], j, t.ends[std::size_t(j)]);
    ++ran;
    options_of(s, t.ends[std::size_t(j)], 0, 1, j, t.repaired, nullptr);
    t.chosen = choose(s, t.repaired, t.status);
    if (t.status == kReachOk) break;
  }
  if (t.chosen >= 0) return;
  int best = 0;  // the nearest the repair came (ties to the earlier start)
  double best_e = kInf;
  for (int j = 0; j < ran; ++j) {
    double sum = 0.0;
    for (int k = 0; k < 6; ++k) sum += e[j][k] * e[j][k];
    if (sum < best_e) best_e = sum, best = j;
  }
  const Evaluation& end = t.ends[std::size_t(best)];
  std::copy_n(z[best], 6, a.p);
  std::copy_n(end.legs.data(), n3, a.q);
  std::copy_n(z[best] + 6, 6, a.q + n3);
  std::copy_n(end.T.data(), 16, a.T), std::copy_n(end.L.data(), 16, a.L);
  branches_from(end, 0, a.branches, a.valid);
  a.slot = -1;
  a.margin = margin_of(s, a.T, a.q);
  std::copy_n(e[best], 6, t.nearest_e);
  t.status = kReachUnreachable;
}

}  // namespace

template <typename Model>
inline void search_block(const dynamics::RobotStaticsModel<Model>& robot, const ReachArm& arm,
                         const ReachCapsules& capsules, const ReachShared& shared,
                         const ReachInput* in, const ReachOutput* out, int count) {
  const int legs = robot.body.n_legs(), m = shared.m;
  std::vector<Search<Model>> S;
  S.reserve(std::size_t(count));
  static thread_local BlockScratch scratch;
  Target* targets = scratch.targets;
  Evaluation* stages = scratch.stages;
  Checks& checks = scratch.checks;
  Answer answers[kReachBlock] = {};
  for (int t = 0; t < count; ++t) {
    S.push_back({robot, arm, capsules, shared, in[t], legs, m});
    // the stance and feet of the target before (the common case: every target's), or its own
    const int before = t > 0 ? S[std::size_t(t - 1)].same_feet : -1;
    const bool same =  // bit for bit
        before >= 0 &&
        std::memcmp(in[t].feet, in[before].feet, sizeof(double) * std::size_t(3 * legs)) == 0 &&
        std::memcmp(in[t].stance, in[before].stance, sizeof(double) * 16) == 0;
    S[std::size_t(t)].same_feet = same ? before : t;
    targets[t].reset();
    if (!valid_input(in[t], legs, m)) {
      no_answer(out[t], m, kReachInvalid);
      continue;
    }
    targets[t].searching = true;
  }
  // (C), (E), (A): stage by stage, until an option is feasible; a stage's candidates of every
  // target still searching in one evaluation
  for (int stage = 0, halton = 0; stage < 3; ++stage) {
    Evaluation& ev = stages[stage];
    int total = 0;
    for (int t = 0; t < count; ++t) {
      Target& tg = targets[t];
      if (!tg.searching) continue;
      const int first = (in[t].seed_pose ? 1 : 0) + 1;
      tg.begin = total;
      tg.size = stage == 0   ? first
                : stage == 1 ? kReachStageTwo
                             : kReachCandidates - kReachStageTwo;
      total += tg.size;
    }
    if (total == 0) break;
    ev.resize(total, legs);
    for (int t = 0; t < count; ++t) {
      const Target& tg = targets[t];
      if (!tg.searching) continue;
      for (int j = 0; j < tg.size; ++j) {
        const int k = tg.begin + j;
        double* p = &ev.p[std::size_t(6 * k)];
        ev.owner[std::size_t(k)] = t;
        if (stage == 0 && in[t].seed_pose && j == 0) {
          for (int i = 0; i < 6; ++i)
            p[i] = std::min(std::max(in[t].seed_pose[i], shared.lower[i]), shared.upper[i]);
        } else if (stage == 0) {
          std::copy_n(shared.nominal, 6, p);
          ev.local[std::size_t(k)] = shared.local[0];
        } else {
          candidate_pose(shared, halton + j, p);
          ev.local[std::size_t(k)] = shared.local[1 + halton + j];
        }
      }
    }
    if (stage > 0) halton += stage == 1 ? kReachStageTwo : kReachCandidates - kReachStageTwo;
    run(S.data(), ev);
    Option* first[kReachBlock];
    int owner[kReachBlock], n_first = 0;
    for (int t = 0; t < count; ++t) {
      Target& tg = targets[t];
      if (!tg.searching) continue;
      options_of(S[std::size_t(t)], ev, tg.begin, tg.begin + tg.size, tg.next_order, tg.options,
                 &tg.misses);
      tg.next_order += tg.size;
      if (Option* o = first_unchecked(tg.options)) first[n_first] = o, owner[n_first++] = t;
    }
    check_all(S.data(), first, owner, n_first, checks);  // the options choose() checks first
    for (int t = 0; t < count; ++t) {
      Target& tg = targets[t];
      if (!tg.searching) continue;
      tg.chosen = choose(S[std::size_t(t)], tg.options, tg.status);
      if (tg.status == kReachOk) tg.searching = false;
    }
  }
  // the chosen options, or (F) where none reaches; then (R) on every feasible answer at once
  int refining[kReachBlock], n_refining = 0;
  for (int t = 0; t < count; ++t) {
    Target& tg = targets[t];
    if (!tg.searching && tg.status != kReachOk) continue;  // INVALID_INPUT
    tg.searching = false;
    const Search<Model>& s = S[std::size_t(t)];
    Answer& a = answers[t];
    a.slot = -1;
    const Option* picked = tg.chosen >= 0 ? &tg.options[std::size_t(tg.chosen)] : nullptr;
    if (!picked && !in[t].repair) {
      no_answer(out[t], m, kReachUnreachable);
      continue;
    }
    if (!picked) {
      repair(s, tg, a);
      picked = tg.chosen >= 0 ? &tg.repaired[std::size_t(tg.chosen)] : nullptr;
    }
    tg.answered = true;
    if (!picked) continue;  // UNREACHABLE: the nearest the repair came, in a
    const Evaluation& ev = *picked->ev;
    std::copy_n(&ev.p[std::size_t(6 * picked->pose)], 6, a.p);
    whole_q(s, ev, picked->pose, picked->slot, a.q);
    std::copy_n(&ev.T[std::size_t(16 * picked->pose)], 16, a.T);
    std::copy_n(&ev.L[std::size_t(16 * picked->pose)], 16, a.L);
    branches_from(ev, picked->pose, a.branches, a.valid);
    a.slot = picked->slot, a.cost = picked->cost, a.margin = picked->margin;
    if (tg.status == kReachOk && in[t].refine) refining[n_refining++] = t;
  }
  if (n_refining) refine(S.data(), answers, refining, n_refining);
  // the answers, with the arm's branches at each answer's body pose (from its evaluation)
  for (int t = 0; t < count; ++t) {
    const Target& tg = targets[t];
    if (!tg.answered) continue;
    const Answer& a = answers[t];
    const ReachOutput& o = out[t];
    pose_of(a.T, o.body_pose);
    std::copy_n(a.q, m, o.q);
    *o.status = tg.status, *o.margin = a.margin;
    *o.slot = tg.status == kReachUnreachable ? -1 : a.slot;
    if (tg.status == kReachUnreachable) {
      // hypot: a target far beyond reach (1e300 m) still gets a finite distance
      const double* e = tg.nearest_e;
      *o.distance = std::hypot(std::hypot(e[0], e[1]), e[2]);
      *o.angle = std::hypot(std::hypot(e[3], e[4]), e[5]) / shared.scale;
    } else {
      *o.distance = *o.angle = 0.0;
    }
    std::copy_n(a.branches, 48, o.branches), std::copy_n(a.valid, 8, o.valid);
  }
}

// The entry points, one per model. The vector model's (every CPU with AVX2) has the search
// inlined whole (flatten) and compiled for AVX2 with FMA where the build makes clones (the
// search's scalar code is a tenth faster so). The baseline model's (CPUs without AVX2) is compiled
// as any function: flattened too, this unit took 73 s of compiler CPU, the longest of the build
// (GCC's register liveness and CSE passes grow faster than the function), for no measured gain
// (SPOTKIN_ISA=sse2, batched Spot reach: 10.9 us per target flattened, 10.2 us not).
#if SPOTKIN_HAS_ISA_CLONES
#define SPOTKIN_REACH_VECTOR_TARGET \
  __attribute__((target("avx2,fma,bmi,bmi2,lzcnt,popcnt,f16c,movbe"), flatten))
#else
#define SPOTKIN_REACH_VECTOR_TARGET __attribute__((flatten))
#endif

SPOTKIN_REACH_VECTOR_TARGET void reach_block(
    const dynamics::RobotStaticsModel<ReachVectorModel>& robot, const ReachArm& arm,
    const ReachCapsules& capsules, const ReachShared& shared, const ReachInput* in,
    const ReachOutput* out, int count) {
  search_block(robot, arm, capsules, shared, in, out, count);
}

void reach_block(const dynamics::RobotStaticsModel<ReachBaselineModel>& robot, const ReachArm& arm,
                 const ReachCapsules& capsules, const ReachShared& shared, const ReachInput* in,
                 const ReachOutput* out, int count) {
  search_block(robot, arm, capsules, shared, in, out, count);
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

template void reach_constraints<ReachVectorModel>(
    const dynamics::RobotStaticsModel<ReachVectorModel>&, const ReachArm&, const ReachCapsules&,
    const ReachShared&, const double*, const double*, const double*, double*, bool*);
template void reach_constraints<ReachBaselineModel>(
    const dynamics::RobotStaticsModel<ReachBaselineModel>&, const ReachArm&, const ReachCapsules&,
    const ReachShared&, const double*, const double*, const double*, double*, bool*);

}  // namespace spotkin::motion
