// 7R chains with one joint held at a given value (redundancy resolution by a free joint,
// as for Franka-Panda- and Kinova-Gen3-like arms): E_k(v) moved through the later joints
// (fix_joint in poe.hpp) leaves a 6R chain with the same target pose, solved by its
// family (Arm6). The family is found on probe values of the free joint when the solver
// is built; each sample's 6R solver is built for its own value (reused while consecutive
// samples share it, as when many poses are solved for one value).
#pragma once

#include <cmath>
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
    return out;
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

  Poe poe_;
  int free_joint_ = 0;
  double scale_ = 1.0;
  FamilyTolerance tolerance_;
  std::string kind_;
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
  const int k = solver.free_joint();
  Limits limits6;
  limits6.dof = 6;
  for (int j = 0, o = 0; j < 7; ++j) {
    if (j == k) continue;
    limits6.lower[o] = lower[j], limits6.upper[o] = upper[j], limits6.sigma[o] = 0;
    ++o;
  }
  const T nan = std::numeric_limits<T>::quiet_NaN();
  std::vector<double> pose_run, q6;
  std::vector<std::uint8_t> valid6, exists6, exact6;
  std::vector<std::int8_t> status6;
  auto fail = [&](std::ptrdiff_t i, Status st) {
    T* qi = q + i * S * 7;
    for (int e = 0; e < S * 7; ++e) qi[e] = nan;
    for (int s = 0; s < S; ++s) valid[i * S + s] = exists[i * S + s] = exact[i * S + s] = 0;
    status[i] = static_cast<std::int8_t>(st);
  };
  // runs of samples sharing one value share one 6R solver and go through its block kernel together
  for (std::ptrdiff_t i = 0; i < count;) {
    const double value = double(values[i]);
    if (!std::isfinite(value)) {
      fail(i++, Status::InvalidInput);
      continue;
    }
    std::ptrdiff_t end = i + 1;
    while (end < count && double(values[end]) == value) ++end;
    const std::ptrdiff_t n = end - i;
    std::optional<Arm6> arm;
    try {
      arm.emplace(solver.arm_for(value));
    } catch (const std::exception&) {
      for (std::ptrdiff_t r = i; r < end; ++r) {
        double pose[width];
        for (int e = 0; e < width; ++e) pose[e] = double(poses[r * width + e]);
        Arm::Pose read;
        fail(r, Arm::read_pose<Format>(pose, read) != 0.0 ? Status::Unreachable : Status::InvalidInput);
      }
      i = end;
      continue;
    }
    pose_run.resize(std::size_t(n * width));
    for (std::ptrdiff_t e = 0; e < n * width; ++e) pose_run[std::size_t(e)] = double(poses[i * width + e]);
    q6.resize(std::size_t(n * S * 6)), valid6.resize(std::size_t(n * S)), exists6.resize(std::size_t(n * S));
    exact6.resize(std::size_t(n * S)), status6.resize(std::size_t(n));
    arm6_kernel<double>(*arm, limits6, pose_run.data(), Format, q6.data(), valid6.data(), exists6.data(),
                        exact6.data(), status6.data(), n);
    const bool value_fits = lower[k] <= value && value <= upper[k];
    for (std::ptrdiff_t r = 0; r < n; ++r) {
      const std::ptrdiff_t at = i + r;
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
    }
    i = end;
  }
}

}  // namespace spotkin::chain_ik
