// Times spotkin's C++ batch kernels without Python, so that kernel cost and
// boundary cost (argument checks, array creation, the GIL) can be told apart.
// Build and run (not part of `pip install`):
//
//   cmake -S bench/cpp -B build/harness -DCMAKE_BUILD_TYPE=Release
//   cmake --build build/harness
//   build/harness/spotkin_harness            # or: spotkin_harness 1000000 15
//
// The robot is the built-in Spot: its legs, hips and knee limits as the packaged
// URDF (python/spotkin/robots/spot_with_arm.urdf) gives them, and its arm.
// Every kernel runs on one thread over n samples (default 1e6; the arm and the
// 6-joint chain 1e5); the best of `repeats` runs is reported in ns per sample
// and in TSC cycles per sample (the TSC rate is measured against steady_clock),
// beside a floor: the kernel's elementary operations (atan2, sincos, sqrt,
// multiply-adds; counts in spotkin/diagnostics.hpp) times their measured
// vectorised cost on this CPU, in the kernel's dtype (the arm has no floor).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "spotkin/arm.hpp"
#include "spotkin/body.hpp"
#include "spotkin/chain.hpp"
#include "spotkin/diagnostics.hpp"
#include "spotkin/leg.hpp"


using namespace spotkin;

// The same run-time CPU dispatch as the Python module's kernels.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define HARNESS_KERNEL __attribute__((noinline, target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define HARNESS_KERNEL __attribute__((noinline))
#endif

namespace {

template <typename T>
HARNESS_KERNEL void leg_ik(const Leg& leg, const T* p, const T* seed, T* q, std::int8_t* status, std::ptrdiff_t n) {
  leg_batch::ik(leg, p, seed, q, status, n);
}
template <typename T>
HARNESS_KERNEL void leg_ik_all(const Leg& leg, const T* p, T* q, std::uint8_t* valid, std::uint8_t* exists,
                               std::int8_t* status, std::ptrdiff_t n) {
  leg_batch::ik_all(leg, p, q, valid, exists, status, n);
}
template <typename T>
HARNESS_KERNEL void leg_fk(const Leg& leg, const T* q, T* p, std::ptrdiff_t n) {
  leg_batch::fk(leg, q, p, n);
}
template <typename T>
HARNESS_KERNEL void body_ik(const Body& body, const T* poses, const T* feet, T* q, std::int8_t* status,
                            std::ptrdiff_t n) {
  body_batch::ik(body, poses, BodyPoseFormat::Euler, EulerSequence{}, feet, true, static_cast<const T*>(nullptr), q,
                 status, n);
}
template <typename T>
HARNESS_KERNEL void body_fk(const Body& body, const T* poses, const T* q, T* feet, std::ptrdiff_t n) {
  body_batch::fk(body, poses, BodyPoseFormat::Euler, EulerSequence{}, q, feet, n);
}
HARNESS_KERNEL void arm_ik_all(const Arm& arm, const double* poses, double* q, std::uint8_t* valid,
                               std::uint8_t* exists, std::int8_t* status, std::ptrdiff_t n) {
  arm_batch::ik_all(arm, poses, PoseFormat::Matrix, static_cast<const double*>(nullptr), q, valid, exists, status, n);
}
HARNESS_KERNEL void arm_fk(const Arm& arm, const double* q, double* poses, std::ptrdiff_t n) {
  arm_batch::fk(arm, q, poses, n);
}
HARNESS_KERNEL void chain_fk(const Chain<double>& chain, const double* q, double* out, std::ptrdiff_t n) {
  chain.forward_batch(q, out, n);
}
HARNESS_KERNEL void chain_jacobian(const Chain<double>& chain, const double* q, double* out, std::ptrdiff_t n) {
  chain.jacobian_batch(q, out, n, 6, false);
}

namespace d = spotkin::diagnostics;

// The elementary operations (diagnostics.hpp), compiled as the kernels are.
struct Loops {
  template <typename T>
  static HARNESS_KERNEL void atan2(const T* y, const T* x, T* out, std::ptrdiff_t n) { d::atan2_loop(y, x, out, n); }
  template <typename T>
  static HARNESS_KERNEL void sincos(const T* x, T* s, T* c, std::ptrdiff_t n) { d::sincos_loop(x, s, c, n); }
  template <typename T>
  static HARNESS_KERNEL void sqrt(const T* x, T* out, std::ptrdiff_t n) { d::sqrt_loop(x, out, n); }
  template <typename T>
  static HARNESS_KERNEL void fma32(const T* x, T* out, std::ptrdiff_t n) { d::fma32_loop(x, out, n); }
};

using d::best_seconds;

struct Report {
  double ghz;
  d::Costs costs64, costs32;
  // the floor of `kernel` (diagnostics.hpp's counts) in the costs of its dtype; none for an unnamed one
  void operator()(const char* name, std::ptrdiff_t n, double seconds, const char* kernel = "",
                  bool single = false) const {
    const double ns = seconds / double(n) * 1e9;
    const double floor = (single ? costs32 : costs64).floor_ns(d::work_of(kernel));
    if (floor > 0.0)
      std::printf("%-28s %10td %10.2f %10.1f %10.1f %8.1fx\n", name, n, ns, ns * ghz, floor * ghz, ns / floor);
    else
      std::printf("%-28s %10td %10.2f %10.1f %10s %9s\n", name, n, ns, ns * ghz, "-", "-");
  }
};

JointLimits<3> leg_limits(double knee_upper) {
  JointLimits<3> limits;
  const double lower[3] = {-0.78539816339744827899, -0.89884456477707963539, -2.7929};
  const double upper[3] = {0.78539816339744827899, 2.2951079663725435509, knee_upper};
  for (int j = 0; j < 3; ++j) limits.lower[j] = lower[j], limits.upper[j] = upper[j];
  return limits;
}

template <typename T>
std::vector<T> as(const std::vector<double>& v) {
  return std::vector<T>(v.begin(), v.end());
}

}  // namespace

int main(int argc, char** argv) {
  const std::ptrdiff_t n = argc > 1 ? std::atol(argv[1]) : 1000000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 15;
  const std::ptrdiff_t n_arm = std::max<std::ptrdiff_t>(1, n / 10);
  if (n <= 0 || repeats <= 0) {
    std::fprintf(stderr, "usage: spotkin_harness [samples > 0] [repeats > 0]\n");
    return 2;
  }
  Report report{d::tsc_ghz(), d::measure_costs<double, Loops>(20 * repeats),
                d::measure_costs<float, Loops>(20 * repeats)};
  std::printf("spotkin C++ kernels, one thread, best of %d; TSC %.3f GHz\n", repeats, report.ghz);
  for (const auto& [label, c] : {std::pair{"float64", report.costs64}, std::pair{"float32", report.costs32}})
    std::printf("elementary costs, %s (vectorised, cycles/element): atan2 %.2f, sincos %.2f, sqrt %.2f, "
                "multiply-add %.3f\n",
                label, c.atan2 * report.ghz, c.sincos * report.ghz, c.sqrt * report.ghz, c.fma * report.ghz);
  std::printf("%-28s %10s %10s %10s %10s %9s\n", "kernel", "samples", "ns/sample", "cycles", "floor cyc", "/floor");

  // Spot: legs fl, fr, hl, hr (hip roll x, hip pitch y, knee y); per-leg knee limits.
  const double knee_upper[4] = {-0.254801, -0.247563, -0.267153, -0.257725};
  const double side[4] = {1, -1, 1, -1}, front[4] = {1, 1, -1, -1};
  std::vector<Leg> legs;
  std::vector<std::array<double, 3>> hips;
  std::vector<std::array<int, 3>> columns;
  for (int l = 0; l < 4; ++l) {
    legs.emplace_back(spot_style_geometry(side[l] * 0.110945, 0.3205, 0.3365, 0.025), leg_limits(knee_upper[l]));
    hips.push_back({front[l] * 0.29785, side[l] * 0.055, 0.0});
    columns.push_back({3 * l, 3 * l + 1, 3 * l + 2});
  }
  const Body body(legs, hips, columns);
  const Leg& leg = body.legs[0];

  std::mt19937_64 rng(0);
  std::normal_distribution<double> normal(0.0, 1.0);
  // leg targets: FK of configurations drawn uniformly inside the limits
  std::vector<double> q(3 * n), p(3 * n), q_out(3 * n), q_all(12 * n);
  std::vector<std::int8_t> status(4 * n);
  std::vector<std::uint8_t> valid(8 * n_arm > 4 * n ? 8 * n_arm : 4 * n), exists(valid.size());
  for (std::ptrdiff_t i = 0; i < n; ++i)
    for (int j = 0; j < 3; ++j)
      q[3 * i + j] = std::uniform_real_distribution<double>(leg.limits().lower[j], leg.limits().upper[j])(rng);
  leg_fk(leg, q.data(), p.data(), n);
  std::vector<double> seed(q);
  for (double& v : seed) v += 0.05 * normal(rng);

  // body poses around a 0.5 m stance, feet shared
  const double feet[12] = {0.29785, 0.165945, 0, 0.29785, -0.165945, 0, -0.29785, 0.165945, 0, -0.29785, -0.165945, 0};
  const double spread[6] = {0.03, 0.03, 0.03, 0.06, 0.06, 0.06};
  std::vector<double> poses(6 * n), q12(12 * n), feet_out(12 * n);
  for (std::ptrdiff_t i = 0; i < n; ++i)
    for (int k = 0; k < 6; ++k) poses[6 * i + k] = (k == 2 ? 0.5 : 0.0) + spread[k] * normal(rng);
  body_ik(body, poses.data(), feet, q12.data(), status.data(), n);

  report("leg.fk", n, best_seconds(repeats, [&] { leg_fk(leg, q.data(), p.data(), n); }), "leg.fk");
  report("leg.ik", n,
         best_seconds(repeats, [&] {
           leg_ik(leg, p.data(), static_cast<const double*>(nullptr), q_out.data(), status.data(), n);
         }),
         "leg.ik");
  report("leg.ik seeded", n,
         best_seconds(repeats, [&] { leg_ik(leg, p.data(), seed.data(), q_out.data(), status.data(), n); }),
         "leg.ik_all");
  report("leg.ik_all", n, best_seconds(repeats, [&] {
           leg_ik_all(leg, p.data(), q_all.data(), valid.data(), exists.data(), status.data(), n);
         }),
         "leg.ik_all");
  {
    const std::vector<float> pf = as<float>(p);
    std::vector<float> qf(3 * n);
    report("leg.ik float32", n,
           best_seconds(repeats, [&] {
             leg_ik(leg, pf.data(), static_cast<const float*>(nullptr), qf.data(), status.data(), n);
           }),
           "leg.ik", true);
  }
  report("body_ik", n, best_seconds(repeats, [&] { body_ik(body, poses.data(), feet, q12.data(), status.data(), n); }),
         "body_ik");
  {
    const std::vector<float> posesf = as<float>(poses);
    const std::vector<float> feetf(feet, feet + 12);
    std::vector<float> qf(12 * n);
    report("body_ik float32", n, best_seconds(repeats, [&] {
             body_ik(body, posesf.data(), feetf.data(), qf.data(), status.data(), n);
           }),
           "body_ik", true);
  }
  {  // one pose per call, as a control loop calls it (the block is padded to whole vectors)
    const std::ptrdiff_t calls = std::max<std::ptrdiff_t>(1, n / 10);
    report("body_ik one pose per call", calls, best_seconds(repeats, [&] {
             for (std::ptrdiff_t i = 0; i < calls; ++i)
               body_ik(body, poses.data() + 6 * (i & 1023), feet, q12.data(), status.data(), 1);
           }));
  }
  report("body_fk", n,
         best_seconds(repeats, [&] { body_fk(body, poses.data(), q12.data(), feet_out.data(), n); }), "body_fk");

  // Spot's arm (its default geometry; no limits), targets from FK
  const Arm arm;
  std::vector<double> q6(6 * n_arm), T(16 * n_arm), q_arm(48 * n_arm), out16(16 * n_arm), J(36 * n_arm);
  for (double& v : q6) v = std::uniform_real_distribution<double>(-2.5, 2.5)(rng);
  arm_fk(arm, q6.data(), T.data(), n_arm);
  report("arm.ik_all", n_arm, best_seconds(repeats, [&] {
           arm_ik_all(arm, T.data(), q_arm.data(), valid.data(), exists.data(), status.data(), n_arm);
         }));
  // a 6-joint DHm chain (Spot's arm as a table)
  const double rows[30] = {0, 0, 0, 0, 0,       0, 0, -kPi<double> / 2, 0, 0,      0, 0.3385, 0, 0, -kPi<double> / 2,
                           0, 0.075, -kPi<double> / 2, 0.4033, 0, 0, 0, kPi<double> / 2, 0, 0, 0, 0, -kPi<double> / 2, 0, 0};
  const Chain<double> chain = Chain<double>::from_table(Convention::ModifiedDH, rows, 6, Rigid<double>{}, Rigid<double>{});
  report("chain6.fk", n_arm, best_seconds(repeats, [&] { chain_fk(chain, q6.data(), out16.data(), n_arm); }),
         "chain6.fk");
  report("chain6.jacobian", n_arm,
         best_seconds(repeats, [&] { chain_jacobian(chain, q6.data(), J.data(), n_arm); }), "chain6.jacobian");
  return 0;
}
