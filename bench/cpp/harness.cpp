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
// multiply-adds; counts in the Work constants below) times their measured
// vectorised cost on this CPU (float64; the float32 kernels and the arm have
// no floor here).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "spotkin/arm.hpp"
#include "spotkin/body.hpp"
#include "spotkin/chain.hpp"
#include "spotkin/leg.hpp"

#if defined(__x86_64__)
#include <x86intrin.h>
#endif

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

// Elementary operations over arrays, vectorised as in the kernels: their
// measured cost per element is the unit of the floor estimate.
HARNESS_KERNEL void elementary_atan2(const double* y, const double* x, double* out, std::ptrdiff_t n) {
  for (std::ptrdiff_t i = 0; i < n; ++i) out[i] = vector_math::atan2(y[i], x[i]);
}
HARNESS_KERNEL void elementary_sincos(const double* x, double* s, double* c, std::ptrdiff_t n) {
  for (std::ptrdiff_t i = 0; i < n; ++i) vector_math::sincos_bounded(x[i], s[i], c[i]);
}
HARNESS_KERNEL void elementary_sqrt(const double* x, double* out, std::ptrdiff_t n) {
  for (std::ptrdiff_t i = 0; i < n; ++i) out[i] = std::sqrt(x[i]);
}
// 32 dependent multiply-adds per element, over independent elements (throughput)
HARNESS_KERNEL void elementary_fma32(const double* x, double* out, std::ptrdiff_t n) {
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    double v = x[i];
#pragma GCC unroll 32
    for (int k = 0; k < 32; ++k) v = v * 0.999 + 0.001;
    out[i] = v;
  }
}

double tsc_ghz() {
#if defined(__x86_64__)
  const auto t0 = std::chrono::steady_clock::now();
  const std::uint64_t c0 = __rdtsc();
  while (std::chrono::steady_clock::now() - t0 < std::chrono::milliseconds(200)) {
  }
  const std::uint64_t c1 = __rdtsc();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return double(c1 - c0) / seconds * 1e-9;
#else
  return 0.0;
#endif
}

template <class F>
double best_seconds(int repeats, F&& run) {
  double best = 1e30;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    run();
    best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return best;
}

// What a kernel must evaluate per sample, at least: the floor estimate is
// the sum of these counts times the measured cost of each operation (memory
// traffic, selects, branch and limit logic are left out, so the floor is low).
struct Work {
  double atan2 = 0, sincos = 0, sqrt = 0, fma = 0;
};

struct Costs {  // ns per element, measured
  double atan2 = 0, sincos = 0, sqrt = 0, fma = 0;
  double floor_ns(const Work& w) const { return w.atan2 * atan2 + w.sincos * sincos + w.sqrt * sqrt + w.fma * fma; }
};

struct Report {
  double ghz;
  Costs costs;
  void operator()(const char* name, std::ptrdiff_t n, double seconds, const Work& work = Work{}) const {
    const double ns = seconds / double(n) * 1e9, floor = costs.floor_ns(work);
    if (floor > 0.0)
      std::printf("%-28s %10td %10.2f %10.1f %10.1f %8.1fx\n", name, n, ns, ns * ghz, floor * ghz, ns / floor);
    else
      std::printf("%-28s %10td %10.2f %10.1f %10s %9s\n", name, n, ns, ns * ghz, "-", "-");
  }
};

// Operation counts per sample, from the kernels' equations (leg.hpp (I1)-(I4)
// and (R1), body.hpp (B1)-(B2), chain.hpp): a leg IK slot is one sqrt for the
// hip, one sqrt + one atan2 for the knee's acos, one atan2 each for hip roll
// and hip pitch, and about 40 multiply-adds; every slot (ik_all) shares the hip
// sqrt and, for a_z = 0, the knee.
constexpr Work kLegFk{0, 3, 0, 20};
constexpr Work kLegIk{3, 0, 2, 40};
constexpr Work kLegIkAll{7, 0, 2, 110};
constexpr Work kBodyIk{12, 3, 8, 4 * 40 + 60};
constexpr Work kBodyFk{0, 15, 0, 4 * 20 + 60};
constexpr Work kChain6Fk{0, 6, 0, 6 * 27};
constexpr Work kChain6Jacobian{0, 6, 0, 6 * 27 + 6 * 15};

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
  Report report{tsc_ghz(), {}};
  {
    const std::ptrdiff_t m = 1 << 16;  // in cache
    std::vector<double> a(m), b(m), c(m), d(m);
    std::mt19937_64 gen(1);
    for (std::ptrdiff_t i = 0; i < m; ++i)
      a[i] = std::uniform_real_distribution<double>(-3, 3)(gen), b[i] = std::uniform_real_distribution<double>(-3, 3)(gen);
    const int r = 20 * repeats;
    report.costs.atan2 = best_seconds(r, [&] { elementary_atan2(a.data(), b.data(), c.data(), m); }) / m * 1e9;
    report.costs.sincos = best_seconds(r, [&] { elementary_sincos(a.data(), c.data(), d.data(), m); }) / m * 1e9;
    report.costs.sqrt = best_seconds(r, [&] { elementary_sqrt(b.data(), c.data(), m); }) / m * 1e9;  // NaN half: same cost
    report.costs.fma = best_seconds(r, [&] { elementary_fma32(a.data(), c.data(), m); }) / m * 1e9 / 32.0;
  }
  std::printf("spotkin C++ kernels, one thread, best of %d; TSC %.3f GHz\n", repeats, report.ghz);
  std::printf("elementary costs (vectorised, cycles/element): atan2 %.2f, sincos %.2f, sqrt %.2f, multiply-add %.3f\n",
              report.costs.atan2 * report.ghz, report.costs.sincos * report.ghz, report.costs.sqrt * report.ghz,
              report.costs.fma * report.ghz);
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

  report("leg.fk", n, best_seconds(repeats, [&] { leg_fk(leg, q.data(), p.data(), n); }), kLegFk);
  report("leg.ik", n,
         best_seconds(repeats, [&] {
           leg_ik(leg, p.data(), static_cast<const double*>(nullptr), q_out.data(), status.data(), n);
         }),
         kLegIk);
  report("leg.ik seeded", n,
         best_seconds(repeats, [&] { leg_ik(leg, p.data(), seed.data(), q_out.data(), status.data(), n); }),
         kLegIkAll);
  report("leg.ik_all", n, best_seconds(repeats, [&] {
           leg_ik_all(leg, p.data(), q_all.data(), valid.data(), exists.data(), status.data(), n);
         }),
         kLegIkAll);
  {
    const std::vector<float> pf = as<float>(p);
    std::vector<float> qf(3 * n);
    report("leg.ik float32", n,
           best_seconds(repeats, [&] {
             leg_ik(leg, pf.data(), static_cast<const float*>(nullptr), qf.data(), status.data(), n);
           }));
  }
  report("body_ik", n, best_seconds(repeats, [&] { body_ik(body, poses.data(), feet, q12.data(), status.data(), n); }),
         kBodyIk);
  {
    const std::vector<float> posesf = as<float>(poses);
    const std::vector<float> feetf(feet, feet + 12);
    std::vector<float> qf(12 * n);
    report("body_ik float32", n, best_seconds(repeats, [&] {
             body_ik(body, posesf.data(), feetf.data(), qf.data(), status.data(), n);
           }));
  }
  report("body_fk", n,
         best_seconds(repeats, [&] { body_fk(body, poses.data(), q12.data(), feet_out.data(), n); }), kBodyFk);

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
         kChain6Fk);
  report("chain6.jacobian", n_arm,
         best_seconds(repeats, [&] { chain_jacobian(chain, q6.data(), J.data(), n_arm); }), kChain6Jacobian);
  return 0;
}
