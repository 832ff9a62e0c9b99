// Times spotkin's C++ batch kernels without Python, so that kernel cost and
// boundary cost (argument checks, array creation, the GIL) can be told apart.
// Build and run (not part of `pip install`):
//
//   cmake -S bench/cpp -B build/harness -DCMAKE_BUILD_TYPE=Release
//   cmake --build build/harness
//   build/harness/spotkin_harness            # or: spotkin_harness 1000000 15
//   build/harness/spotkin_harness --check    # self-checks only (or: --check 2000)
//
// The robot is the built-in Spot: its legs, hips and knee limits as the packaged
// URDF (python/spotkin/robots/spot_with_arm.urdf) gives them, and its arm.
// Every kernel runs on one thread over n samples (default 1e6; the arm and the
// 6-joint chain 1e5); the best of `repeats` runs is reported in ns per sample
// and in TSC cycles per sample (the TSC rate is measured against steady_clock),
// beside a floor: the kernel's elementary operations (atan2, sincos, sqrt,
// multiply-adds; counts in spotkin/diagnostics.hpp) times their measured
// vectorised cost on this CPU, in the kernel's dtype (the arm has no floor).
//
// --check [n] (default n = 2000) runs self-checks instead of timings and exits
// nonzero when one fails: the elementary loops against the C library, leg and
// body IK against FK, every arm solution against FK, the chain's batch FK
// against its scalar FK and its Jacobian against finite differences, and the
// chain dynamics (RNEA, ABA, CRBA, Coriolis) against each other, at two lane
// widths (the 8-lane float64 path transposes in registers) and over enough
// samples that CRBA takes the non-temporal store path. Small enough to run
// under an emulator (tools/check_arm64.sh runs it under qemu-aarch64).
//
// Timings and checks run at every instruction-set level the CPU has, lowest first
// (spotkin/isa.hpp: sse2, avx2, avx512), each with its own elementary costs and floors;
// SPOTKIN_ISA=avx2 runs one level. The report starts with the CPU's model.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include "spotkin/arm.hpp"
#include "spotkin/body.hpp"
#include "spotkin/chain.hpp"
#include "spotkin/kernels/chain.hpp"
#include "spotkin/diagnostics.hpp"
#include "spotkin/dynamics/batch.hpp"
#include "spotkin/dynamics/kernels.hpp"
#include "spotkin/leg.hpp"
#include "spotkin/scratch.hpp"


using namespace spotkin;

#if defined(__GNUC__) && !defined(__clang__)
// The kernels' packs are inlined: no vector crosses a call by value (the wide models'
// templates are instantiated at the end of this file, outside the headers' own pragmas).
#pragma GCC diagnostic ignored "-Wpsabi"
#endif

// The same run-time dispatch as the Python module's kernels (spotkin/isa.hpp): each
// kernel is compiled for every instruction-set level and runs the active one's clone.

namespace {

SPOTKIN_CLONES((template <typename T> __attribute__((noinline))), void, leg_ik, (const Leg& leg, const T* p, const T* seed, T* q, std::int8_t* status, std::ptrdiff_t n), (leg, p, seed, q, status, n),
  leg_batch::ik(leg, p, seed, q, status, n);
)
SPOTKIN_CLONES((template <typename T> __attribute__((noinline))), void, leg_ik_all, (const Leg& leg, const T* p, T* q, std::uint8_t* valid, std::uint8_t* exists,
                               std::int8_t* status, std::ptrdiff_t n), (leg, p, q, valid, exists, status, n),
  leg_batch::ik_all(leg, p, q, valid, exists, status, n);
)
SPOTKIN_CLONES((template <typename T> __attribute__((noinline))), void, leg_fk, (const Leg& leg, const T* q, T* p, std::ptrdiff_t n), (leg, q, p, n),
  leg_batch::fk(leg, q, p, n);
)
SPOTKIN_CLONES((template <typename T> __attribute__((noinline))), void, body_ik, (const Body& body, const T* poses, const T* feet, T* q, std::int8_t* status,
                            std::ptrdiff_t n), (body, poses, feet, q, status, n),
  body_batch::ik(body, poses, BodyPoseFormat::Euler, EulerSequence{}, feet, true, static_cast<const T*>(nullptr), q,
                 status, n);
)
SPOTKIN_CLONES((template <typename T> __attribute__((noinline))), void, body_fk, (const Body& body, const T* poses, const T* q, T* feet, std::ptrdiff_t n), (body, poses, q, feet, n),
  body_batch::fk(body, poses, BodyPoseFormat::Euler, EulerSequence{}, q, feet, n);
)
SPOTKIN_CLONES((__attribute__((noinline))), void, arm_ik_all,
               (const Arm& arm, const double* poses, double* q, std::uint8_t* valid,
                std::uint8_t* exists, std::int8_t* status, std::ptrdiff_t n),
               (arm, poses, q, valid, exists, status, n),
               arm_batch::ik_all<register_bytes(kIsa)>(arm, poses, PoseFormat::Matrix,
                                                       static_cast<const double*>(nullptr), q,
                                                       valid, exists, status, n);)
SPOTKIN_CLONES((__attribute__((noinline))), void, arm_fk, (const Arm& arm, const double* q, double* poses, std::ptrdiff_t n), (arm, q, poses, n),
  arm_batch::fk(arm, q, poses, n);
)
// The chain's FK and Jacobian are the module's own kernels (cpp/src/chain_kernels.cpp, built
// into the harness with the module's -ffp-contract=off), dispatched at the active level.
void chain_fk(const Chain<double>& chain, const double* q, double* out, std::ptrdiff_t n) {
  kernels::chain_fk(chain, q, out, n);
}
void chain_jacobian(const Chain<double>& chain, const double* q, double* out, std::ptrdiff_t n) {
  kernels::chain_jacobian(chain, q, out, n, 6, false);
}

// The chain dynamics at the lane widths of the Python module (8 float64, 16
// float32 lanes: spotkin/dynamics/kernels.hpp) and at 2 float64 lanes (no in-register
// transpose), for the self-checks.
namespace dyn = spotkin::dynamics;
using dyn::NonDeduced;
// Whether a batch's output is large enough for streamed stores, as the module decides it.
template <typename M>
bool streamed(std::ptrdiff_t n, int width) {
  return std::size_t(n) * std::size_t(width) * sizeof(M) >= spotkin::kStreamBytes;
}  // deduced from the model alone (nullptr passes)
SPOTKIN_CLONES((template <typename M, int L> __attribute__((noinline))), void, rnea, (const dyn::ChainModel<M, L>& model, NonDeduced<dyn::Rows<M>> q,
                         const NonDeduced<dyn::Rows<M>>* qd, const NonDeduced<dyn::Rows<M>>* qdd,
                         NonDeduced<dyn::Rows<M>> g, M* out, std::ptrdiff_t n), (model, q, qd, qdd, g, out, n),
  dyn::rnea_batch(model, q, qd, qdd, g, out, 0, n, streamed<M>(n, model.dof()));
)
SPOTKIN_CLONES((template <typename M, int L> __attribute__((noinline))), void, crba, (const dyn::ChainModel<M, L>& model, NonDeduced<dyn::Rows<M>> q, M* out, std::ptrdiff_t n), (model, q, out, n),
  dyn::crba_batch(model, q, out, 0, n, streamed<M>(n, model.dof() * model.dof()));
)
SPOTKIN_CLONES((template <typename M, int L> __attribute__((noinline))), void, coriolis, (const dyn::ChainModel<M, L>& model, NonDeduced<dyn::Rows<M>> q,
                             NonDeduced<dyn::Rows<M>> qd, M* out, std::ptrdiff_t n), (model, q, qd, out, n),
  dyn::coriolis_batch(model, q, qd, out, 0, n, streamed<M>(n, model.dof() * model.dof()));
)
SPOTKIN_CLONES((template <typename M, int L> __attribute__((noinline))), void, aba, (const dyn::ChainModel<M, L>& model, NonDeduced<dyn::Rows<M>> q, NonDeduced<dyn::Rows<M>> qd,
                        NonDeduced<dyn::Rows<M>> tau, NonDeduced<dyn::Rows<M>> g, M* out, std::ptrdiff_t n), (model, q, qd, tau, g, out, n),
  dyn::aba_batch(model, q, qd, tau, g, out, 0, n, streamed<M>(n, model.dof()));
)

namespace d = spotkin::diagnostics;

// The elementary operations (diagnostics.hpp), compiled as the kernels are.
SPOTKIN_CLONES((template <typename T> __attribute__((noinline))), void, atan2_loop, (const T* y, const T* x, T* out, std::ptrdiff_t n), (y, x, out, n), d::atan2_loop(y, x, out, n); )
SPOTKIN_CLONES((template <typename T> __attribute__((noinline))), void, sincos_loop, (const T* x, T* s, T* c, std::ptrdiff_t n), (x, s, c, n), d::sincos_loop(x, s, c, n); )
SPOTKIN_CLONES((template <typename T> __attribute__((noinline))), void, sqrt_loop, (const T* x, T* out, std::ptrdiff_t n), (x, out, n), d::sqrt_loop(x, out, n); )
SPOTKIN_CLONES((template <typename T> __attribute__((noinline))), void, fma32_loop, (const T* x, T* out, std::ptrdiff_t n), (x, out, n), d::fma32_loop(x, out, n); )

struct Loops {
  template <typename T>
  static void atan2(const T* y, const T* x, T* out, std::ptrdiff_t n) { atan2_loop(y, x, out, n); }
  template <typename T>
  static void sincos(const T* x, T* s, T* c, std::ptrdiff_t n) { sincos_loop(x, s, c, n); }
  template <typename T>
  static void sqrt(const T* x, T* out, std::ptrdiff_t n) { sqrt_loop(x, out, n); }
  template <typename T>
  static void fma32(const T* x, T* out, std::ptrdiff_t n) { fma32_loop(x, out, n); }
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

// Spot: legs fl, fr, hl, hr (hip roll x, hip pitch y, knee y); per-leg knee limits.
Body spot_body() {
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
  return Body(legs, hips, columns);
}

// a 6-joint DHm chain (Spot's arm as a table)
Chain<double> spot_arm_chain() {
  const double rows[30] = {0, 0, 0, 0, 0,       0, 0, -kPi<double> / 2, 0, 0,      0, 0.3385, 0, 0, -kPi<double> / 2,
                           0, 0.075, -kPi<double> / 2, 0.4033, 0, 0, 0, kPi<double> / 2, 0, 0, 0, 0, -kPi<double> / 2, 0, 0};
  return Chain<double>::from_table(Convention::ModifiedDH, rows, 6, Rigid<double>{}, Rigid<double>{});
}

// --check: each check prints PASS or FAIL with its measure, and a closing
// "N passed, N failed" line.
struct Checks {
  int passed = 0, failed = 0;
  // passes when err <= tol (a NaN error fails)
  void error(const char* name, double err, double tol) {
    const bool ok = err <= tol;
    ++(ok ? passed : failed);
    std::printf("%s  %-46s max error %.3g (tolerance %.3g)\n", ok ? "PASS" : "FAIL", name, err, tol);
  }
  // passes when at least `needed` of `total` samples are good
  void count(const char* name, std::ptrdiff_t good, std::ptrdiff_t total, std::ptrdiff_t needed) {
    const bool ok = good >= needed && total > 0;
    ++(ok ? passed : failed);
    std::printf("%s  %-46s %td of %td (at least %td needed)\n", ok ? "PASS" : "FAIL", name, good, total, needed);
  }
};

// |a - b| on the circle
double angle_gap(double a, double b) { return std::fabs(wrap_angle(a - b)); }
// max |a - b|, NaN when either holds a NaN
double max_gap(const double* a, const double* b, std::ptrdiff_t n) {
  double e = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const double d = std::fabs(a[i] - b[i]);
    if (!(d <= e)) e = std::isnan(d) ? d : std::max(e, d);
    if (std::isnan(e)) return e;
  }
  return e;
}

template <typename T>
void check_elementary(Checks& check, std::mt19937_64& rng, const char* atan2_name, const char* sincos_name,
                      double tol) {
  const std::ptrdiff_t m = 4096;
  std::uniform_real_distribution<double> wide(-40.0, 40.0);
  std::vector<T> y(m), x(m), a(m), s(m), c(m);
  for (std::ptrdiff_t i = 0; i < m; ++i) y[i] = T(wide(rng)), x[i] = T(wide(rng));
  Loops::atan2(y.data(), x.data(), a.data(), m);
  Loops::sincos(y.data(), s.data(), c.data(), m);
  double ea = 0, es = 0;
  for (std::ptrdiff_t i = 0; i < m; ++i) {
    const double yd = double(y[i]), xd = double(x[i]);
    ea = std::max(ea, std::fabs(double(a[i]) - std::atan2(yd, xd)));
    es = std::max({es, std::fabs(double(s[i]) - std::sin(yd)), std::fabs(double(c[i]) - std::cos(yd))});
    if (std::isnan(double(a[i]))) ea = double(a[i]);
    if (std::isnan(double(s[i]) + double(c[i]))) es = double(s[i]) + double(c[i]);
  }
  check.error(atan2_name, ea, tol);
  check.error(sincos_name, es, tol);
}

// Six links of decreasing mass, centres of mass off every axis, full inertia tensors.
std::vector<dyn::LinkInertial> arm_inertials() {
  std::vector<dyn::LinkInertial> links(6);
  for (int j = 0; j < 6; ++j) {
    dyn::LinkInertial& l = links[static_cast<std::size_t>(j)];
    l.mass = 2.0 - 0.25 * j;
    l.com = Vec3<double>(0.05 + 0.01 * j, -0.02 + 0.005 * j, 0.03 - 0.01 * j);
    const double d = 0.02 - 0.002 * j, o = 0.002;
    l.inertia << d, o, -o, o, 1.3 * d, o / 2, -o, o / 2, 0.8 * d;
  }
  return links;
}

// RNEA, ABA, CRBA and the Coriolis matrix of the chain against one another for
// n samples, in M over L lanes. tau = RNEA(q, qd, qdd); ABA(q, qd, tau) = qdd;
// CRBA(q) qdd + RNEA(q, qd, 0) = tau; C(q, qd) qd + RNEA(q, 0, 0) = RNEA(q, qd, 0).
// Returns tau and CRBA's output, for comparisons between lane widths.
template <typename M, int L>
void check_dynamics(Checks& check, const char* label, const Chain<double>& chain, const std::vector<double>& q64,
                    const std::vector<double>& qd64, const std::vector<double>& qdd64, std::ptrdiff_t n, double tol,
                    std::vector<double>& tau_out, std::vector<double>& A_out) {
  const dyn::ChainModel<M, L> model(chain, arm_inertials());
  const int dof = model.dof();
  const std::vector<M> q(q64.begin(), q64.end()), qd(qd64.begin(), qd64.end()), qdd(qdd64.begin(), qdd64.end());
  const M gravity[3] = {M(0), M(0), M(-9.81)};
  const dyn::Rows<M> rq{q.data(), dof}, rqd{qd.data(), dof}, rqdd{qdd.data(), dof}, rg{gravity, 0};
  std::vector<M> tau(n * dof), h(n * dof), G(n * dof), back(n * dof), A(n * dof * dof), C(n * dof * dof);
  rnea(model, rq, &rqd, &rqdd, rg, tau.data(), n);
  rnea(model, rq, &rqd, nullptr, rg, h.data(), n);
  rnea(model, rq, nullptr, nullptr, rg, G.data(), n);
  const dyn::Rows<M> rtau{tau.data(), dof};
  aba(model, rq, rqd, rtau, rg, back.data(), n);
  crba(model, rq, A.data(), n);
  coriolis(model, rq, rqd, C.data(), n);
  double e_aba = 0, e_crba = 0, e_sym = 0, e_cor = 0;
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const M* Ai = A.data() + i * dof * dof;
    const M* Ci = C.data() + i * dof * dof;
    for (int r = 0; r < dof; ++r) {
      const std::ptrdiff_t k = i * dof + r;
      double Aqdd = 0, Cqd = 0;
      for (int c = 0; c < dof; ++c) {
        Aqdd += double(Ai[r * dof + c]) * double(qdd[i * dof + c]);
        Cqd += double(Ci[r * dof + c]) * double(qd[i * dof + c]);
        e_sym = std::max(e_sym, std::fabs(double(Ai[r * dof + c]) - double(Ai[c * dof + r])));
      }
      const double scale = std::max(1.0, std::fabs(double(tau[k])));
      e_aba = std::max(e_aba, std::fabs(double(back[k]) - double(qdd[k])) / std::max(1.0, std::fabs(double(qdd[k]))));
      e_crba = std::max(e_crba, std::fabs(Aqdd + double(h[k]) - double(tau[k])) / scale);
      e_cor = std::max(e_cor, std::fabs(Cqd + double(G[k]) - double(h[k])) / scale);
      if (std::isnan(double(back[k]) + double(tau[k]) + Aqdd + Cqd)) e_aba = e_crba = e_cor = std::nan("");
    }
  }
  std::string name = std::string(label);
  check.error((name + " ABA(RNEA(qdd)) = qdd").c_str(), e_aba, tol);
  check.error((name + " CRBA qdd + h = RNEA").c_str(), e_crba, tol);
  check.error((name + " CRBA symmetric").c_str(), e_sym, tol);
  check.error((name + " C qd + G = h").c_str(), e_cor, tol);
  tau_out.assign(tau.begin(), tau.end());
  A_out.assign(A.begin(), A.end());
}

// The kernels' per-thread scratch stack: nested arrays stay aligned, hold their values while
// later ones are taken (across chunks, the first of which is 64 KiB), and a released
// stack serves the same sizes again from the same memory.
void check_scratch(Checks& check) {
  using P = dynamics::Pack<double, 8>;
  std::ptrdiff_t bad = 0, total = 0;
  const void* first_address[2] = {nullptr, nullptr};
  for (int round = 0; round < 2; ++round) {
    ScratchArray<P> a(100, P(1.0));                 // 6.4 KB
    ScratchArray<double> b(20000);                   // 160 KB: a second chunk
    ScratchArray<P> c(3000, P(3.0));                // 192 KB: a third
    {
      ScratchArray<float> d(7, 4.0f);
      total += 7;
      for (float x : d) bad += x != 4.0f;
    }
    ScratchArray<P> e(5);  // value-initialised: zeros, where d was
    for (const P* arr : {a.data(), c.data(), e.data()}) bad += reinterpret_cast<std::uintptr_t>(arr) % alignof(P) != 0;
    for (std::size_t i = 0; i < a.size(); ++i) bad += a[i].v[7] != 1.0;
    for (std::size_t i = 0; i < b.size(); ++i) bad += b[i] != 0.0;
    for (std::size_t i = 0; i < c.size(); ++i) bad += c[i].v[0] != 3.0;
    for (std::size_t i = 0; i < e.size(); ++i) bad += e[i].v[3] != 0.0;
    total += 3 + a.size() + b.size() + c.size() + e.size();
    first_address[round] = c.data();
  }
  check.count("scratch stack: nested arrays aligned, kept", total - bad, total, total);
  check.count("scratch stack: reused after release", first_address[0] == first_address[1], 1, 1);
}

// remainder_two_pi against std::remainder, bit for bit: a dense sweep of (-5 pi, 5 pi), the
// neighbours of every multiple of pi there, and the special values; float64 and float32.
template <typename T>
void check_remainder(Checks& check, const char* name) {
  std::ptrdiff_t good = 0, total = 0;
  const auto same = [&](T a) {
    const T fast = remainder_two_pi(a), slow = std::remainder(a, T(2) * kPi<T>);
    good += std::memcmp(&fast, &slow, sizeof(T)) == 0 || (std::isnan(fast) && std::isnan(slow));
    ++total;
  };
  for (int i = -500000; i <= 500000; ++i) same(T(5e-5 * i) * kPi<T>);
  for (int k = -4; k <= 4; ++k) {
    T a = T(k) * kPi<T>;
    for (int step = 0; step < 16; ++step) a = std::nextafter(a, T(-100));
    for (int step = 0; step < 33; ++step, a = std::nextafter(a, T(100))) same(a), same(-a);
  }
  for (const T a : {T(0), -T(0), std::numeric_limits<T>::max(),
                    std::numeric_limits<T>::infinity(), -std::numeric_limits<T>::infinity(), quiet_nan<T>(),
                    std::numeric_limits<T>::denorm_min()})
    same(a);
  check.count(name, good, total, total);
}

int self_check(std::ptrdiff_t n) {
  Checks check;
  std::mt19937_64 rng(1);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::printf("spotkin C++ kernels, self-checks on %td samples (%s)\n", n,
#if defined(__aarch64__)
              "aarch64"
#elif defined(__x86_64__)
              "x86_64"
#else
              "other target"
#endif
  );

  check_scratch(check);
  check_remainder<double>(check, "remainder_two_pi = std::remainder, float64");
  check_remainder<float>(check, "remainder_two_pi = std::remainder, float32");
  check_elementary<double>(check, rng, "atan2 float64 vs libm", "sincos float64 vs libm", 1e-15);
  check_elementary<float>(check, rng, "atan2 float32 vs libm", "sincos float32 vs libm", 1e-6);

  // Leg: targets from FK of configurations inside the limits.
  const Body body = spot_body();
  const Leg& leg = body.legs[0];
  std::vector<double> q(3 * n), p(3 * n), q_out(3 * n), p_out(3 * n), q_all(12 * n);
  std::vector<std::int8_t> status(4 * n);
  std::vector<std::uint8_t> valid(8 * n), exists(8 * n);
  for (std::ptrdiff_t i = 0; i < n; ++i)
    for (int j = 0; j < 3; ++j)
      q[3 * i + j] = std::uniform_real_distribution<double>(leg.limits().lower[j], leg.limits().upper[j])(rng);
  leg_fk(leg, q.data(), p.data(), n);
  {
    leg_ik(leg, p.data(), static_cast<const double*>(nullptr), q_out.data(), status.data(), n);
    check.count("leg.ik status OK (reachable targets)",
                std::count(status.begin(), status.begin() + n, std::int8_t(Status::Ok)), n, n);
    leg_fk(leg, q_out.data(), p_out.data(), n);
    check.error("leg.ik: FK(IK(p)) = p [m]", max_gap(p_out.data(), p.data(), 3 * n), 1e-9);
    leg_ik(leg, p.data(), q.data(), q_out.data(), status.data(), n);
    double e = 0;
    for (std::ptrdiff_t k = 0; k < 3 * n; ++k) e = std::max(e, angle_gap(q_out[k], q[k]));
    if (std::isnan(max_gap(q_out.data(), q.data(), 3 * n))) e = std::nan("");
    check.error("leg.ik seeded by q: IK(FK(q)) = q [rad]", e, 1e-6);
  }
  {
    leg_ik_all(leg, p.data(), q_all.data(), valid.data(), exists.data(), status.data(), n);
    std::vector<double> slot(3 * n), slot_p(3 * n);
    double e_fk = 0;
    std::ptrdiff_t found = 0;
    std::vector<double> best(n, 1e30);
    for (int s = 0; s < Leg::kSlots; ++s) {
      for (std::ptrdiff_t i = 0; i < n; ++i)
        for (int j = 0; j < 3; ++j) slot[3 * i + j] = valid[4 * i + s] ? q_all[12 * i + 3 * s + j] : q[3 * i + j];
      leg_fk(leg, slot.data(), slot_p.data(), n);
      e_fk = std::max(e_fk, max_gap(slot_p.data(), p.data(), 3 * n));
      for (std::ptrdiff_t i = 0; i < n; ++i)
        if (valid[4 * i + s]) {
          double g = 0;
          for (int j = 0; j < 3; ++j) g = std::max(g, angle_gap(slot[3 * i + j], q[3 * i + j]));
          best[i] = std::min(best[i], g);
        }
    }
    for (std::ptrdiff_t i = 0; i < n; ++i) found += best[i] <= 1e-6;
    check.error("leg.ik_all: every valid slot FK = p [m]", e_fk, 1e-9);
    check.count("leg.ik_all: q among the valid slots", found, n, n);
  }
  {
    const std::vector<float> pf = as<float>(p);
    std::vector<float> qf(3 * n);
    leg_ik(leg, pf.data(), static_cast<const float*>(nullptr), qf.data(), status.data(), n);
    const std::vector<double> qd(qf.begin(), qf.end());
    leg_fk(leg, qd.data(), p_out.data(), n);
    std::ptrdiff_t ok = 0;
    double e = 0;
    for (std::ptrdiff_t i = 0; i < n; ++i)
      if (status[i] == std::int8_t(Status::Ok)) {
        ++ok;
        e = std::max(e, max_gap(p_out.data() + 3 * i, p.data() + 3 * i, 3));
      }
    check.count("leg.ik float32 status OK", ok, n, n - n / 100);
    check.error("leg.ik float32: FK(IK(p)) = p [m]", e, 1e-5);
  }

  // Body: poses around a 0.5 m stance, feet shared; IK then FK gives the feet back.
  {
    const double feet[12] = {0.29785, 0.165945, 0, 0.29785, -0.165945, 0, -0.29785, 0.165945, 0, -0.29785, -0.165945, 0};
    const double spread[6] = {0.03, 0.03, 0.03, 0.06, 0.06, 0.06};
    std::vector<double> poses(6 * n), q12(12 * n), feet_out(12 * n);
    for (std::ptrdiff_t i = 0; i < n; ++i)
      for (int k = 0; k < 6; ++k) poses[6 * i + k] = (k == 2 ? 0.5 : 0.0) + spread[k] * normal(rng);
    body_ik(body, poses.data(), feet, q12.data(), status.data(), n);
    body_fk(body, poses.data(), q12.data(), feet_out.data(), n);
    std::ptrdiff_t ok = 0;
    double e = 0;
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      if (std::count(status.begin() + 4 * i, status.begin() + 4 * i + 4, std::int8_t(Status::Ok)) != 4) continue;
      ++ok;
      e = std::max(e, max_gap(feet_out.data() + 12 * i, feet, 12));
    }
    check.count("body_ik: every leg OK", ok, n, n - n / 10);
    check.error("body_ik: FK(IK(feet)) = feet [m]", e, 1e-9);
    // One to four poses per call go through the pair lanes (body_batch::ik_pairs): their rows are
    // the batch's, bit for bit (a NaN pose included).
    poses[6 * 11 + 4] = std::numeric_limits<double>::quiet_NaN();  // in the third call
    body_ik(body, poses.data(), feet, q12.data(), status.data(), n);
    std::ptrdiff_t same = 0, calls = 0;
    std::vector<double> q_few(12 * 4);
    std::vector<std::int8_t> status_few(4 * 4);
    for (std::ptrdiff_t i = 0; i + 4 <= n && calls < 400; i += 5, ++calls) {
      const std::ptrdiff_t count = 1 + calls % 4;
      body_ik(body, poses.data() + 6 * i, feet, q_few.data(), status_few.data(), count);
      same += std::memcmp(q_few.data(), q12.data() + 12 * i,
                          sizeof(double) * std::size_t(12 * count)) == 0 &&
              std::memcmp(status_few.data(), status.data() + 4 * i, std::size_t(4 * count)) == 0;
    }
    check.count("body_ik, 1-4 poses a call = the batch's rows (bits)", same, calls, calls);
  }

  // Arm: every solution of FK(q) reproduces the pose, and q is among them.
  {
    const Arm arm;
    std::vector<double> q6(6 * n), T(16 * n), q_arm(48 * n), slot(6 * n), T_out(16 * n);
    for (double& v : q6) v = std::uniform_real_distribution<double>(-2.5, 2.5)(rng);
    arm_fk(arm, q6.data(), T.data(), n);
    arm_ik_all(arm, T.data(), q_arm.data(), valid.data(), exists.data(), status.data(), n);
    check.count("arm.ik_all status OK", std::count(status.begin(), status.begin() + n, std::int8_t(Status::Ok)), n,
                n);
    double e_fk = 0;
    std::vector<double> best(n, 1e30);
    for (int s = 0; s < 8; ++s) {
      for (std::ptrdiff_t i = 0; i < n; ++i)
        for (int j = 0; j < 6; ++j) slot[6 * i + j] = valid[8 * i + s] ? q_arm[48 * i + 6 * s + j] : q6[6 * i + j];
      arm_fk(arm, slot.data(), T_out.data(), n);
      e_fk = std::max(e_fk, max_gap(T_out.data(), T.data(), 16 * n));
      for (std::ptrdiff_t i = 0; i < n; ++i)
        if (valid[8 * i + s]) {
          double g = 0;
          for (int j = 0; j < 6; ++j) g = std::max(g, angle_gap(slot[6 * i + j], q6[6 * i + j]));
          best[i] = std::min(best[i], g);
        }
    }
    std::ptrdiff_t found = 0;
    for (std::ptrdiff_t i = 0; i < n; ++i) found += best[i] <= 1e-6;
    check.error("arm.ik_all: every valid slot FK = pose", e_fk, 1e-9);
    check.count("arm.ik_all: q among the valid slots", found, n, n);
  }

  // Chain: batch FK against the scalar FK (libm's sin and cos), the Jacobian
  // against central differences of the scalar FK.
  const Chain<double> chain = spot_arm_chain();
  std::vector<double> q6(6 * n), out16(16 * n), J(36 * n);
  for (double& v : q6) v = std::uniform_real_distribution<double>(-2.5, 2.5)(rng);
  {
    chain_fk(chain, q6.data(), out16.data(), n);
    double e = 0;
    for (std::ptrdiff_t i = 0; i < n; ++i) {
      const Rigid<double> T = chain.forward(q6.data() + 6 * i);
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) e = std::max(e, std::fabs(out16[16 * i + 4 * r + c] - T.R(r, c)));
        e = std::max(e, std::fabs(out16[16 * i + 4 * r + 3] - T.p[r]));
      }
      if (std::isnan(out16[16 * i])) e = std::nan("");
    }
    check.error("chain6.fk: batch = scalar", e, 1e-12);
  }
  {
    chain_jacobian(chain, q6.data(), J.data(), n);
    const double step = 1e-6;
    double e = 0;
    for (std::ptrdiff_t i = 0; i < n; ++i)
      for (int j = 0; j < 6; ++j) {
        double qp[6], qm[6];
        std::copy(q6.data() + 6 * i, q6.data() + 6 * i + 6, qp);
        std::copy(qp, qp + 6, qm);
        qp[j] += step, qm[j] -= step;
        const Rigid<double> Tp = chain.forward(qp), Tm = chain.forward(qm), T = chain.forward(q6.data() + 6 * i);
        const Vec3<double> v = (Tp.p - Tm.p) / (2 * step);
        const Mat3<double> W = (Tp.R - Tm.R) / (2 * step) * T.R.transpose();  // [w]x
        const Vec3<double> w(W(2, 1), W(0, 2), W(1, 0));
        for (int r = 0; r < 3; ++r) {
          e = std::max(e, std::fabs(J[36 * i + 6 * r + j] - v[r]));
          e = std::max(e, std::fabs(J[36 * i + 6 * (r + 3) + j] - w[r]));
        }
        if (std::isnan(J[36 * i + j])) e = std::nan("");
      }
    check.error("chain6.jacobian vs central differences", e, 1e-7);
  }

  // Dynamics: enough samples that CRBA's output (36 float64 per sample) takes
  // the non-temporal store path (stream.hpp kStreamBytes).
  {
    const std::ptrdiff_t nd = std::max<std::ptrdiff_t>(n, std::ptrdiff_t(spotkin::kStreamBytes / (36 * sizeof(double))) + 64);
    std::vector<double> qd(6 * nd), qv(6 * nd), qdd(6 * nd);
    for (std::ptrdiff_t k = 0; k < 6 * nd; ++k)
      qd[k] = std::uniform_real_distribution<double>(-3.0, 3.0)(rng), qv[k] = normal(rng), qdd[k] = normal(rng);
    std::vector<double> tau8, A8, tau2, A2, tau32, A32;
    check_dynamics<double, 8>(check, "dynamics f64 x8:", chain, qd, qv, qdd, nd, 1e-9, tau8, A8);
    check_dynamics<double, 2>(check, "dynamics f64 x2:", chain, qd, qv, qdd, nd, 1e-9, tau2, A2);
    check.error("dynamics f64: 8 lanes = 2 lanes (RNEA)", max_gap(tau8.data(), tau2.data(), 6 * nd), 1e-9);
    check.error("dynamics f64: 8 lanes = 2 lanes (CRBA)", max_gap(A8.data(), A2.data(), 36 * nd), 1e-9);
    check_dynamics<float, 16>(check, "dynamics f32 x16:", chain, qd, qv, qdd, nd, 2e-3, tau32, A32);
    double e = 0;
    for (std::ptrdiff_t k = 0; k < 6 * nd; ++k) e = std::max(e, std::fabs(tau32[k] - tau8[k]) / std::max(1.0, std::fabs(tau8[k])));
    if (std::isnan(max_gap(tau32.data(), tau8.data(), 6 * nd))) e = std::nan("");
    check.error("dynamics f32 = f64 (RNEA, relative)", e, 1e-4);
  }

  std::printf("harness self-check: %d passed, %d failed\n", check.passed, check.failed);
  return check.failed == 0 ? 0 : 1;
}

}  // namespace

// The CPU's model name (Linux), for the report.
std::string cpu_model() {
  std::FILE* info = std::fopen("/proc/cpuinfo", "r");
  std::string model = "unknown";
  if (info == nullptr) return model;
  char line[512];
  while (std::fgets(line, sizeof line, info) != nullptr) {
    const std::string text(line);
    if (text.rfind("model name", 0) == 0 && text.find(':') != std::string::npos) {
      model = text.substr(text.find(':') + 2);
      if (!model.empty() && model.back() == '\n') model.pop_back();
      break;
    }
  }
  std::fclose(info);
  return model;
}

// Runs `run` at the level SPOTKIN_ISA names, or else at every level the CPU has, lowest
// first (isa.hpp); nonzero if any run was.
template <typename F>
int for_each_level(F&& run) {
  Isa only;
  try {
    only = isa_from_environment();
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }
  const char* forced = std::getenv("SPOTKIN_ISA");
  const bool all = forced == nullptr || *forced == '\0';
  int status = 0;
  for (int level = 0; level <= static_cast<int>(best_isa()); ++level) {
    if (!all && level != static_cast<int>(only)) continue;
    set_isa(static_cast<Isa>(level));
    std::printf("== instruction-set level %s (best on this CPU: %s)\n", isa_name(active_isa()), isa_name(best_isa()));
    std::fflush(stdout);
    status |= run();
  }
  return status;
}

int timings(std::ptrdiff_t n, int repeats, std::ptrdiff_t n_arm);

int main(int argc, char** argv) {
  if (argc > 1 && std::strcmp(argv[1], "--check") == 0) {
    const std::ptrdiff_t n = argc > 2 ? std::atol(argv[2]) : 2000;
    if (n <= 0 || argc > 3) {
      std::fprintf(stderr, "usage: spotkin_harness --check [samples > 0]\n");
      return 2;
    }
    return for_each_level([&] { return self_check(n); });
  }
  const std::ptrdiff_t n = argc > 1 ? std::atol(argv[1]) : 1000000;
  const int repeats = argc > 2 ? std::atoi(argv[2]) : 15;
  const std::ptrdiff_t n_arm = std::max<std::ptrdiff_t>(1, n / 10);
  if (n <= 0 || repeats <= 0) {
    std::fprintf(stderr, "usage: spotkin_harness [samples > 0] [repeats > 0]  |  spotkin_harness --check [samples > 0]\n");
    return 2;
  }
  std::printf("CPU: %s\n", cpu_model().c_str());
  return for_each_level([&] { return timings(n, repeats, n_arm); });
}

int timings(std::ptrdiff_t n, int repeats, std::ptrdiff_t n_arm) {
  Report report{d::tsc_ghz(), d::measure_costs<double, Loops>(20 * repeats),
                d::measure_costs<float, Loops>(20 * repeats)};
  std::printf("spotkin C++ kernels, one thread, best of %d; TSC %.3f GHz\n", repeats, report.ghz);
  for (const auto& [label, c] : {std::pair{"float64", report.costs64}, std::pair{"float32", report.costs32}})
    std::printf("elementary costs, %s (vectorised, cycles/element): atan2 %.2f, sincos %.2f, sqrt %.2f, "
                "multiply-add %.3f\n",
                label, c.atan2 * report.ghz, c.sincos * report.ghz, c.sqrt * report.ghz, c.fma * report.ghz);
  std::printf("%-28s %10s %10s %10s %10s %9s\n", "kernel", "samples", "ns/sample", "cycles", "floor cyc", "/floor");

  const Body body = spot_body();
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
  const Chain<double> chain = spot_arm_chain();
  report("chain6.fk", n_arm, best_seconds(repeats, [&] { chain_fk(chain, q6.data(), out16.data(), n_arm); }),
         "chain6.fk");
  report("chain6.jacobian", n_arm,
         best_seconds(repeats, [&] { chain_jacobian(chain, q6.data(), J.data(), n_arm); }), "chain6.jacobian");
  return 0;
}
