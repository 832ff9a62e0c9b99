// 7R chains with one joint held at a given value (redundancy resolution by a free joint,
// as for Franka-Panda- and Kinova-Gen3-like arms): E_k(v) moved through the later joints
// (fix_joint in poe.hpp) leaves a 6R chain with the same target pose, solved by its
// family (Arm6). The family is found on probe values of the free joint when the solver
// is built.
//   The first or the last joint held: E_1(v) or E_7(v) only moves the six's base or tool
// rigidly, so one 6R solver (built at v = 0) serves every value, on the target moved by
// (F1) or (F7) below, and every pose of a batch goes through its lane kernel together.
//   A middle joint held turns the later axes about its own: each value has its own 6R
// solver, built once and kept in a bounded cache across calls; the poses that share a
// value (a grid of values over many poses) go through its lane kernel together.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <list>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "spotkin/chain_ik/kernels.hpp"

namespace spotkin::chain_ik {

class FreeJoint7 {
 public:
  static constexpr int kSlots = Arm6::kSlots;

  static FreeJoint7 make(const Chain<double>& chain, int free_joint, FamilyTolerance tolerance) {
    if (chain.dof() != 7)
      throw std::invalid_argument("a free joint needs a 7-joint chain, got " + std::to_string(chain.dof()) +
                                  " joints");
    if (free_joint < 0 || free_joint >= 7)
      throw std::invalid_argument("free_joint must be in [0, 6], got " + std::to_string(free_joint));
    for (int j = 0; j < 7; ++j)
      if (chain.joints()[std::size_t(j)].type != JointType::Revolute)
        throw std::invalid_argument("joint " + std::to_string(j + 1) + " is prismatic; the 7R free-joint form needs "
                                    "revolute joints");
    FreeJoint7 out(chain, free_joint, tolerance);
    // the family of the remaining six on probe values (it may depend on the value when the free
    // joint lies between two axes of the family); every probe must have one
    std::string family;
    for (const double probe : {0.3, -1.1, 2.0}) {
      const Arm6 arm = out.arm_for(probe);  // throws, naming the checks, when none fits
      if (family.empty()) family = arm.kind();
      if (arm.kind() != family)
        throw std::invalid_argument("with joint " + std::to_string(free_joint + 1) +
                                    " held, the other six change family with its value (" + family + ", then " +
                                    arm.kind() + "): hold another joint, or use Chain.ik_differential");
    }
    out.kind_ = family;
    if (out.end_joint()) {
      out.reference_ = std::make_shared<const Arm6>(out.arm_for(0.0));
      // the free joint's axis: in the tool frame M^-1 for the last joint (F7), the base frame for the first
      const V3 h = out.poe_.h[free_joint], p = out.poe_.p[free_joint];
      const Rigid<double> M_inv = inverse_rigid(out.poe_.M);
      out.axis_h_ = free_joint == 0 ? h : V3(M_inv.R * h);
      out.axis_p_ = free_joint == 0 ? p : V3(M_inv.R * p + M_inv.p);
    }
    return out;
  }

  // The first or the last joint held: one 6R solver for every value (reference()).
  bool end_joint() const noexcept { return free_joint_ == 0 || free_joint_ == 6; }
  const Arm6& reference() const noexcept { return *reference_; }

  // The target of the reference solver (value 0) for target T and value v (end joints):
  //   (F7) last joint:  T M^-1 E_7(-v) M, as FK_6(q) E_7(v) M = T;
  //   (F1) first joint: E_1(-v) T,        as E_1(v) FK_6(q) = T (fix_joint turns the six by E_1(v)).
  // E(-v) M^-1 ... M is the rotation by -v about the axis in the tool frame (axis_h_, axis_p_).
  Rigid<double> reference_target(const Rigid<double>& T, double value) const noexcept {
    const double c = std::cos(value), s = -std::sin(value);
    Rigid<double> E;
    for (int col = 0; col < 3; ++col) E.R.col(col) = rotate(axis_h_, c, s, V3::Unit(col));
    E.p = axis_p_ - E.R * axis_p_;
    return free_joint_ == 0 ? E * T : T * E;
  }

  // The 6R solver for a middle joint held at value, null when the six have no closed form there;
  // from the cache when it holds value (most recently used kCacheSize values, shared by threads).
  std::shared_ptr<const Arm6> arm_cached(double value) const {
    std::uint64_t key;
    std::memcpy(&key, &value, sizeof key);
    {
      std::lock_guard<std::mutex> lock(cache_->mutex);
      const auto found = cache_->index.find(key);
      if (found != cache_->index.end()) {
        cache_->order.splice(cache_->order.begin(), cache_->order, found->second);
        return found->second->second;
      }
    }
    std::shared_ptr<const Arm6> arm;  // built outside the lock: the same value gives the same solver
    try {
      arm = std::make_shared<const Arm6>(arm_for(value));
    } catch (const std::invalid_argument&) {
    }
    std::lock_guard<std::mutex> lock(cache_->mutex);
    if (cache_->index.count(key)) return arm;  // another thread built it meanwhile
    cache_->order.emplace_front(key, arm);
    cache_->index.emplace(key, cache_->order.begin());
    if (cache_->order.size() > kCacheSize) {
      cache_->index.erase(cache_->order.back().first);
      cache_->order.pop_back();
    }
    return arm;
  }
  static constexpr std::size_t kCacheSize = 1024;  // 6R solvers kept at most
  std::size_t cached_values() const {
    std::lock_guard<std::mutex> lock(cache_->mutex);
    return cache_->order.size();
  }

  const std::string& kind() const noexcept { return kind_; }
  int free_joint() const noexcept { return free_joint_; }

  // The 6R solver with the free joint at value (Arm6::make's ValueError when no family fits).
  Arm6 arm_for(double value) const {
    const Poe fixed = fix_joint(poe_, free_joint_, value);
    const Chain<double> chain = chain_of(fixed);
    return Arm6::make(chain, scale_, tolerance_);
  }

 private:
  FreeJoint7(const Chain<double>& chain, int free_joint, FamilyTolerance tolerance)
      : poe_(poe_of(chain)), free_joint_(free_joint), scale_(chain.length_scale()), tolerance_(tolerance) {}

  struct Cache {
    std::mutex mutex;
    std::list<std::pair<std::uint64_t, std::shared_ptr<const Arm6>>> order;  // most recent first
    std::unordered_map<std::uint64_t, decltype(order)::iterator> index;
  };

  Poe poe_;
  int free_joint_ = 0;
  double scale_ = 1.0;
  FamilyTolerance tolerance_;
  std::string kind_;
  std::shared_ptr<const Arm6> reference_;                     // end joints
  V3 axis_h_ = V3::Zero(), axis_p_ = V3::Zero();              // end joints: (F1), (F7)
  std::shared_ptr<Cache> cache_ = std::make_shared<Cache>();  // middle joints
};

// Every solution for count poses (Format) with the free joint at values[i]: q (count, 8, 7),
// valid, exists, exact (count, 8), status (count). lower, upper: the 7 joints' limits. A value that is not
// finite gives INVALID_INPUT; a value for which the other six have no closed form (a family
// lost at that value) gives UNREACHABLE with NaN. valid also needs the value within its limits.
template <PoseFormat Format, typename T>
void ik_free_joint(const FreeJoint7& solver, const double* lower, const double* upper, const T* poses, const T* values, T* q,
                   std::uint8_t* valid, std::uint8_t* exists, std::uint8_t* exact, std::int8_t* status,
                   std::ptrdiff_t count) {
  constexpr int S = FreeJoint7::kSlots, width = Format == PoseFormat::Matrix ? 16 : 7;
  constexpr std::ptrdiff_t kBlock = 256;  // poses staged per kernel call
  const int k = solver.free_joint();
  Limits limits6;
  limits6.dof = 6;
  for (int j = 0, o = 0; j < 7; ++j) {
    if (j == k) continue;
    limits6.lower[o] = lower[j], limits6.upper[o] = upper[j], limits6.sigma[o] = 0;
    ++o;
  }
  const T nan = std::numeric_limits<T>::quiet_NaN();
  std::vector<double> staged(static_cast<std::size_t>(kBlock * 16)), q6(static_cast<std::size_t>(kBlock * S * 6));
  std::vector<std::uint8_t> valid6(static_cast<std::size_t>(kBlock * S)), exists6(valid6.size()), exact6(valid6.size());
  std::vector<std::int8_t> status6(static_cast<std::size_t>(kBlock));
  auto read = [&](std::ptrdiff_t i, Arm::Pose& pose) {
    double in[width];
    for (int e = 0; e < width; ++e) in[e] = double(poses[i * width + e]);
    return Arm::read_pose<Format>(in, pose) != 0.0;
  };
  auto fail = [&](std::ptrdiff_t i, Status st) {
    T* qi = q + i * S * 7;
    for (int e = 0; e < S * 7; ++e) qi[e] = nan;
    for (int s = 0; s < S; ++s) valid[i * S + s] = exists[i * S + s] = exact[i * S + s] = 0;
    status[i] = static_cast<std::int8_t>(st);
  };
  // sample at from the kernel's row r: the six's solutions with the value in column k
  auto emit = [&](std::ptrdiff_t at, std::ptrdiff_t r, double value) {
    const bool value_fits = lower[k] <= value && value <= upper[k];
    T* qi = q + at * S * 7;
    bool any_valid = false, any_exists = false;
    for (int s = 0; s < S; ++s) {
      const std::size_t slot = std::size_t(r * S + s);
      const bool here = exists6[slot] != 0;
      for (int j = 0, o = 0; j < 7; ++j)
        qi[s * 7 + j] = !here ? nan : j == k ? T(value) : T(q6[slot * 6 + std::size_t(o++)]);
      const bool ok = valid6[slot] != 0 && value_fits;
      valid[at * S + s] = ok, exists[at * S + s] = here, exact[at * S + s] = exact6[slot];
      any_valid |= ok, any_exists |= here;
    }
    status[at] = status6[std::size_t(r)] == static_cast<std::int8_t>(Status::InvalidInput)
                     ? status6[std::size_t(r)]
                     : static_cast<std::int8_t>(any_valid    ? Status::Ok
                                                : any_exists ? Status::JointLimit
                                                             : Status::Unreachable);
  };
  auto solve = [&](const Arm6& arm, PoseFormat format, std::ptrdiff_t m) {
    arm6_kernel<double>(arm, limits6, staged.data(), format, q6.data(), valid6.data(), exists6.data(), exact6.data(),
                        status6.data(), m);
  };

  if (solver.end_joint()) {  // every pose through the reference solver, on its target (F1) or (F7)
    for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
      const std::ptrdiff_t m = std::min(kBlock, count - b0);
      for (std::ptrdiff_t r = 0; r < m; ++r) {
        const double value = double(values[b0 + r]);
        double* out = staged.data() + 16 * r;
        Arm::Pose pose;
        if (read(b0 + r, pose) && std::isfinite(value))
          write_homogeneous(solver.reference_target(Arm6::rigid_of(pose), value), out);
        else
          std::fill(out, out + 16, std::numeric_limits<double>::quiet_NaN());  // INVALID_INPUT
      }
      solve(solver.reference(), PoseFormat::Matrix, m);
      for (std::ptrdiff_t r = 0; r < m; ++r) {
        const double value = double(values[b0 + r]);
        if (std::isfinite(value))
          emit(b0 + r, r, value);
        else
          fail(b0 + r, Status::InvalidInput);
      }
    }
    return;
  }

  // a middle joint: the samples grouped by value (+ 0.0: -0 is 0), each group by its cached solver
  std::vector<std::ptrdiff_t> order;
  order.reserve(std::size_t(count));
  for (std::ptrdiff_t i = 0; i < count; ++i) {
    if (std::isfinite(double(values[i])))
      order.push_back(i);
    else
      fail(i, Status::InvalidInput);
  }
  auto value_of = [&](std::ptrdiff_t i) { return double(values[i]) + 0.0; };
  std::stable_sort(order.begin(), order.end(),
                   [&](std::ptrdiff_t a, std::ptrdiff_t b) { return value_of(a) < value_of(b); });
  for (std::size_t g = 0; g < order.size();) {
    const double value = value_of(order[g]);
    std::size_t end = g + 1;
    while (end < order.size() && value_of(order[end]) == value) ++end;
    const std::shared_ptr<const Arm6> arm = solver.arm_cached(value);
    for (std::size_t b0 = g; b0 < end; b0 += std::size_t(kBlock)) {
      const std::ptrdiff_t m = std::ptrdiff_t(std::min(std::size_t(kBlock), end - b0));
      if (!arm) {
        for (std::ptrdiff_t r = 0; r < m; ++r) {
          Arm::Pose pose;
          const std::ptrdiff_t at = order[b0 + std::size_t(r)];
          fail(at, read(at, pose) ? Status::Unreachable : Status::InvalidInput);
        }
        continue;
      }
      for (std::ptrdiff_t r = 0; r < m; ++r)
        for (int e = 0; e < width; ++e)
          staged[std::size_t(r * width + e)] = double(poses[order[b0 + std::size_t(r)] * width + e]);
      solve(*arm, Format, m);
      for (std::ptrdiff_t r = 0; r < m; ++r) emit(order[b0 + std::size_t(r)], r, value);
    }
    g = end;
  }
}

}  // namespace spotkin::chain_ik
