// Closed-form position IK of a chain's first three joints (Pieper's quartic).
#pragma once

#include "spotkin/chain_ik/common.hpp"

namespace spotkin::chain_ik {

// Position IK of the point w (in the frame after joint 3's variable Z) for
// the first three joints of a chain: the plan is made once per chain.
class Position3 {
 public:
  static constexpr int kSlots = 4;
  static constexpr int kMaxCandidates = 8;

  // Throws std::invalid_argument when no closed form applies, saying why.
  Position3(const Split& split, const V3& w, double scale) : split_(split), w_(w), scale_(scale) {
    for (int j = 0; j < 3; ++j) sigma_[j] = split.sigma[j];
    check_rank();
    plan();
    M0_inv_ = detail::inverse(split.M0);
    M1_inv_ = detail::inverse(split.M1);
    M2_inv_ = detail::inverse(split.M2);
    revolute_ = sigma_[0] == 0 && sigma_[1] == 0 && sigma_[2] == 0;
    if (revolute_) {  // the constants of (L) for solve_block
      P1_ = backward_ ? M2_inv_ : split.M1;
      P2_ = backward_ ? M1_inv_ : split.M2;
      ra_ = P1_.R.transpose() * P1_.p;
      rb_ = P1_.R.row(2).transpose();
    }
  }

  Kind kind() const noexcept { return kind_; }
  std::string name() const {
    switch (kind_) {
      case Kind::Parallel3R: return "3R-parallel";
      case Kind::Intersecting3R: return "3R-intersecting";
      case Kind::GeneralQuartic3R: return "3R-general-quartic";
      default: {
        std::string s;
        for (int j = 0; j < 3; ++j) s += sigma_[j] == 0 ? 'R' : 'P';
        return s;
      }
    }
  }
  bool backward() const noexcept { return backward_; }
  bool reduced() const noexcept { return reduced_; }
  int sigma(int j) const noexcept { return sigma_[j]; }
  double scale() const noexcept { return scale_; }
  const Split& split() const noexcept { return split_; }

  // Tool point for joint values (cos/sin or value), in the base frame.
  V3 point(const JointValue q[3]) const noexcept {
    const Split& S = split_;
    V3 x = detail::z_apply(sigma_[2], q[2], w_);
    x = S.M2.R * x + S.M2.p;
    x = detail::z_apply(sigma_[1], q[1], x);
    x = S.M1.R * x + S.M1.p;
    x = detail::z_apply(sigma_[0], q[0], x);
    return S.M0.R * x + S.M0.p;
  }

  // Every solution of point(q) = p: returns their number n <= 4 and writes
  // q[k] for k < n, sorted by (q1, q2, q3) with revolute angles in [-pi, pi]
  // (compared through their cosines and sines). 0 for a non-finite or an
  // unreachable p.
  // solve, out of line: the one-target path of solve_block, compiled once rather
  // than inlined into every instruction-set clone of the block kernels (it is
  // scalar code, and it carries the Newton polish's SVD).
  SPOTKIN_SCALAR_PATH int solve_one(const V3& p, JointValue q[kSlots][3]) const noexcept { return solve(p, q); }

  SPOTKIN_INLINE int solve(const V3& p, JointValue q[kSlots][3]) const noexcept {
    if (!p.allFinite()) return 0;
    const V3 target = M0_inv_.R * p + M0_inv_.p;  // p' of (F')
    const double s = std::max(scale_, target.norm());
    Candidate cands[kMaxCandidates];
    int n;
    if (!backward_) {
      Problem pb{{sigma_[0], sigma_[1], sigma_[2]}, target, split_.M1, split_.M2, w_, reduced_, s};
      n = pb.candidates(cands);
    } else {  // (F') reversed: w = Z3(-q3) M2^-1 Z2(-q2) M1^-1 Z1(-q1) p'
      Problem pb{{sigma_[2], sigma_[1], sigma_[0]}, w_, M2_inv_, M1_inv_, target, reduced_, s};
      n = pb.candidates(cands);
      for (int k = 0; k < n; ++k) {
        std::swap(cands[k].q[0], cands[k].q[2]);
        for (auto& v : cands[k].q) v.s = -v.s, v.v = -v.v;
      }
    }
    return finish(target, s, cands, n, q);
  }


  static constexpr int kLanes = 16;

  // Solutions of a block of targets, across the lanes: solution k of target i
  // is (c, s, v)[k][j][i] for joint j, k < n[i].
  struct BlockSolutions {
    double c[kSlots][3][kLanes], s[kSlots][3][kLanes], v[kSlots][3][kLanes];
    int n[kLanes];
  };

  // The all-revolute kinds, which solve_block runs across the lanes of a full block.
  bool lane_form() const noexcept { return revolute_; }

  // solve() for m <= kLanes targets at once (coordinates in lanes, kLanes entries each), into out (same solutions, same
  // order). The all-revolute kinds run each step across the targets (lanes),
  // so that it vectorises; the roots of the quartic, the rare Newton steps and
  // the rare merges stay per target. Same equations and tolerances as solve().
  SPOTKIN_INLINE void solve_block(const double* px, const double* py, const double* pz, int m,
                                  BlockSolutions& out) const noexcept {
    auto store = [&](int i, const JointValue (*q)[3], int n) {
      out.n[i] = n;
      for (int k = 0; k < kSlots; ++k)
        for (int j = 0; j < 3; ++j) {
          const JointValue v = k < n ? q[k][j] : joint_zero();
          out.c[k][j][i] = v.c, out.s[k][j][i] = v.s, out.v[k][j][i] = v.v;
        }
    };
    if (!revolute_ || m < kLanes) {  // one by one (a short block costs no more than its targets)
      for (int i = 0; i < m; ++i) {
        JointValue q[kSlots][3];
        store(i, q, solve_one(V3(px[i], py[i], pz[i]), q));
      }
      return;
    }
    constexpr int L = kLanes, C = kSlots;  // C candidates: 4 roots q3 (Q), or 2 q3 x 2 q2 (Q')
    // target p' of (F'), the problem's target and point (PT, PW): (p', w) or (w, p') reversed
    double tx[L], ty[L], tz[L], sc[L], PTx[L], PTy[L], PTz[L], PWx[L], PWy[L], PWz[L];
    const M3& R0 = M0_inv_.R;
    const V3 t0 = M0_inv_.p;
    for (int i = 0; i < L; ++i) {
      tx[i] = R0(0, 0) * px[i] + R0(0, 1) * py[i] + R0(0, 2) * pz[i] + t0[0];
      ty[i] = R0(1, 0) * px[i] + R0(1, 1) * py[i] + R0(1, 2) * pz[i] + t0[1];
      tz[i] = R0(2, 0) * px[i] + R0(2, 1) * py[i] + R0(2, 2) * pz[i] + t0[2];
      sc[i] = std::max(scale_, std::sqrt(tx[i] * tx[i] + ty[i] * ty[i] + tz[i] * tz[i]));
      PTx[i] = backward_ ? w_[0] : tx[i], PTy[i] = backward_ ? w_[1] : ty[i], PTz[i] = backward_ ? w_[2] : tz[i];
      PWx[i] = backward_ ? tx[i] : w_[0], PWy[i] = backward_ ? ty[i] : w_[1], PWz[i] = backward_ ? tz[i] : w_[2];
    }
    const M3& R1 = P1_.R;
    const M3& R2 = P2_.R;
    const V3 t1 = P1_.p, t2 = P2_.p;
    const double a00 = ra_[0], a01 = ra_[1], a10 = rb_[0], a11 = rb_[1], ra2 = ra_[2], rb2 = rb_[2];
    const double det = a00 * a11 - a01 * a10, t1_2 = t1.squaredNorm();
    // (B') uses the row of Rr of largest norm; (Q') its left null vector
    const bool first_row = a00 * a00 + a01 * a01 >= a10 * a10 + a11 * a11;
    const Eigen::Vector2d null = Problem::null_row(a00, a01, a10, a11);
    // g = R2 Z3(q3) PW + t2 and d = kappa(g) - (ra2, rb2) g_z of (L)
    auto gd = [&](int i, double c3, double s3, double* g, double* d) SPOTKIN_INLINE_LAMBDA {
      const double hx = c3 * PWx[i] - s3 * PWy[i], hy = s3 * PWx[i] + c3 * PWy[i], hz = PWz[i];
      for (int r = 0; r < 3; ++r) g[r] = R2(r, 0) * hx + R2(r, 1) * hy + R2(r, 2) * hz + t2[r];
      const double pt2 = PTx[i] * PTx[i] + PTy[i] * PTy[i] + PTz[i] * PTz[i];
      d[0] = 0.5 * (pt2 - (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) - t1_2) - ra2 * g[2];
      d[1] = PTz[i] - t1[2] - rb2 * g[2];
    };
    // roots q3 (per target)
    double c3[C][L], s3[C][L];
    double roots3[L];  // their number (a double: one element width in the lane loops, so that they vectorise)
    if (reduced_) {
      double vals[3][L];
      for (int k = 0; k < 3; ++k)
        for (int i = 0; i < L; ++i) {
          double g[3], d[2];
          gd(i, kCos3[k], kSin3[k], g, d);
          vals[k][i] = null[0] * d[0] + null[1] * d[1];
        }
      for (int i = 0; i < L; ++i)
        roots3[i] = trig_roots3(vals[0][i], vals[1][i], vals[2][i], c3[0][i], s3[0][i], c3[1][i], s3[1][i]);
    } else {
      double vals[5][L];
      for (int k = 0; k < 5; ++k)
        for (int i = 0; i < L; ++i) {
          double g[3], d[2];
          gd(i, kCos5[k], kSin5[k], g, d);
          const double x = a11 * d[0] - a01 * d[1], y = -a10 * d[0] + a00 * d[1];
          vals[k][i] = x * x + y * y - det * det * (g[0] * g[0] + g[1] * g[1]);
        }
      for (int i = 0; i < m; ++i) {
        const double v[5] = {vals[0][i], vals[1][i], vals[2][i], vals[3][i], vals[4][i]};
        JointValue r[4];
        const int count = trig_roots5(v, r);
        roots3[i] = count;
        for (int k = 0; k < 4; ++k) c3[k][i] = k < count ? r[k].c : 1.0, s3[k][i] = k < count ? r[k].s : 0.0;
      }
    }
    double roots_found[L];
    for (int i = 0; i < L; ++i) roots_found[i] = i < m ? roots3[i] : 0.0;
    // candidates: q2 by (B) or (B'), q1 by (I), and the residual |point - PT|
    double q1c[C][L], q1s[C][L], q2c[C][L], q2s[C][L], q3c[C][L], q3s[C][L], res2[C][L];  // res2: squared residual
    double ok[C][L];  // 1 or 0
    // For candidate k of target i: q2 by (B) or (B'), q1 by (I), the residual
    // |point - PT|, and whether it exists. Reduced is a compile-time copy of
    // reduced_ (no branch in the lane loop, so that it vectorises).
    auto candidates = [&](auto reduced_tag) SPOTKIN_INLINE_LAMBDA {
      constexpr bool Reduced = decltype(reduced_tag)::value;
      for (int k = 0; k < C; ++k) {
        const int root = Reduced ? k / 2 : k;
        const double sign = k % 2 == 0 ? 1.0 : -1.0;
        double c3_row[L], s3_row[L];
        std::copy(c3[root], c3[root] + L, c3_row);
        std::copy(s3[root], s3[root] + L, s3_row);
        for (int i = 0; i < L; ++i) {
          const double c = c3_row[i], s = s3_row[i];
          double g[3], d[2], cq2, sq2, exists;
          gd(i, c, s, g, d);
          if constexpr (!Reduced) {  // (B): e^{i q2} = (adj(Rr) d / det) / (g_x + i g_y)
            const JointValue v = detail::angle_difference_lane((a11 * d[0] - a01 * d[1]) / det,
                                                               (-a10 * d[0] + a00 * d[1]) / det, g[0], g[1]);
            cq2 = v.c, sq2 = v.s;
            exists = root < roots_found[i] ? 1.0 : 0.0;
          } else {  // (B'): a cos q2 + b sin q2 = d_i, branch k % 2
            const double r0 = first_row ? a00 : a10, r1 = first_row ? a01 : a11;
            const double a = r0 * g[0] + r1 * g[1], b = r1 * g[0] - r0 * g[1], rhs = first_row ? d[0] : d[1];
            exists = (root < roots_found[i] ? 1.0 : 0.0) * detail::cos_sin_root(a, b, rhs, sign, cq2, sq2);
          }
          // f = R1 Z2(q2) g + t1; (I) q1 = angle(PT_xy) - angle(f_xy)
          const double mx = cq2 * g[0] - sq2 * g[1], my = sq2 * g[0] + cq2 * g[1], mz = g[2];
          double f[3];
          for (int r = 0; r < 3; ++r) f[r] = R1(r, 0) * mx + R1(r, 1) * my + R1(r, 2) * mz + t1[r];
          const JointValue v1 = detail::angle_difference_lane(PTx[i], PTy[i], f[0], f[1]);
          const double ex = v1.c * f[0] - v1.s * f[1] - PTx[i], ey = v1.s * f[0] + v1.c * f[1] - PTy[i],
                       ez = f[2] - PTz[i];
          q1c[k][i] = v1.c, q1s[k][i] = v1.s, q2c[k][i] = cq2, q2s[k][i] = sq2, q3c[k][i] = c, q3s[k][i] = s;
          res2[k][i] = ex * ex + ey * ey + ez * ez;
          ok[k][i] = exists;
        }
      }
    };
    if (reduced_)
      candidates(std::true_type{});
    else
      candidates(std::false_type{});
    // Newton steps where a residual is above 1e-13 s (rare), in the problem's frame
    for (int k = 0; k < C; ++k)
      for (int i = 0; i < m; ++i) {
        if (!(ok[k][i] != 0.0 && res2[k][i] > 1e-26 * sc[i] * sc[i])) continue;
        const Problem pb{{0, 0, 0}, V3(PTx[i], PTy[i], PTz[i]), P1_, P2_, V3(PWx[i], PWy[i], PWz[i]), reduced_, sc[i]};
        Candidate cand{{JointValue{q1c[k][i], q1s[k][i], 0.0}, JointValue{q2c[k][i], q2s[k][i], 0.0},
                        JointValue{q3c[k][i], q3s[k][i], 0.0}},
                       std::sqrt(res2[k][i])};
        pb.polish(cand);
        q1c[k][i] = cand.q[0].c, q1s[k][i] = cand.q[0].s, q2c[k][i] = cand.q[1].c, q2s[k][i] = cand.q[1].s;
        q3c[k][i] = cand.q[2].c, q3s[k][i] = cand.q[2].s, res2[k][i] = cand.residual * cand.residual;
      }
    // the chain's joints: (q3, q2, q1) with negated angles when the problem is reversed
    double joint_c[C][3][L], joint_s[C][3][L];
    const double sign = backward_ ? -1.0 : 1.0;
    for (int k = 0; k < C; ++k)
      for (int i = 0; i < L; ++i) {
        joint_c[k][0][i] = backward_ ? q3c[k][i] : q1c[k][i], joint_s[k][0][i] = sign * (backward_ ? q3s[k][i] : q1s[k][i]);
        joint_c[k][1][i] = q2c[k][i], joint_s[k][1][i] = sign * q2s[k][i];
        joint_c[k][2][i] = backward_ ? q1c[k][i] : q3c[k][i], joint_s[k][2][i] = sign * (backward_ ? q1s[k][i] : q3s[k][i]);
      }
    // finish() across the lanes where no two accepted candidates are within
    // Tolerance::merge (nothing to merge): accepted candidates sorted by their
    // (q1, q2, q3) pseudo-angles by a sorting network. Lanes with a pair to
    // merge go through finish() itself.
    const double merge2 = Tolerance::merge * Tolerance::merge;
    double accepted[C][L], key[C][3][L], merge_lane[L];
    for (int i = 0; i < L; ++i) {
      const bool finite = std::isfinite(px[i]) && std::isfinite(py[i]) && std::isfinite(pz[i]);
      for (int k = 0; k < C; ++k) {
        const bool acc = finite && ok[k][i] != 0.0 && res2[k][i] <= Tolerance::residual * Tolerance::residual * sc[i] * sc[i];
        accepted[k][i] = acc ? 1.0 : 0.0;
      }
      double near = 0.0;
      for (int a = 0; a < C; ++a)
        for (int b = a + 1; b < C; ++b) {
          double worst = 0.0;
          for (int j = 0; j < 3; ++j) {
            const double dc = joint_c[a][j][i] - joint_c[b][j][i], ds = joint_s[a][j][i] - joint_s[b][j][i];
            worst = std::max(worst, dc * dc + ds * ds);
          }
          near = std::max(near, accepted[a][i] * accepted[b][i] * (worst <= merge2 ? 1.0 : 0.0));
        }
      merge_lane[i] = near;
    }
    for (int k = 0; k < C; ++k)  // a loop of its own, so that it vectorises
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < L; ++i)
          key[k][j][i] = accepted[k][i] != 0.0 ? detail::angle_key(joint_c[k][j][i], joint_s[k][j][i])
                                               : std::numeric_limits<double>::infinity();
    // the network moves keys and values together (selects, no gathers); the
    // unsorted values stay in joint_c, joint_s for the lanes that merge
    double sorted_c[C][3][L], sorted_s[C][3][L];
    std::copy(&joint_c[0][0][0], &joint_c[0][0][0] + C * 3 * L, &sorted_c[0][0][0]);
    std::copy(&joint_s[0][0][0], &joint_s[0][0][0] + C * 3 * L, &sorted_s[0][0][0]);
    detail::sort4([&](int x, int y) SPOTKIN_INLINE_LAMBDA {
      for (int i = 0; i < L; ++i) {
        const bool swap = detail::order_less(key[y][0][i], key[y][1][i], key[y][2][i], key[x][0][i],
                                             key[x][1][i], key[x][2][i]);
        for (int j = 0; j < 3; ++j) {
          const double kx = key[x][j][i], ky = key[y][j][i], cx = sorted_c[x][j][i], cy = sorted_c[y][j][i];
          const double sx = sorted_s[x][j][i], sy = sorted_s[y][j][i];
          key[x][j][i] = swap ? ky : kx, key[y][j][i] = swap ? kx : ky;
          sorted_c[x][j][i] = swap ? cy : cx, sorted_c[y][j][i] = swap ? cx : cy;
          sorted_s[x][j][i] = swap ? sy : sx, sorted_s[y][j][i] = swap ? sx : sy;
        }
      }
    });
    for (int k = 0; k < C; ++k)
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < L; ++i) out.c[k][j][i] = sorted_c[k][j][i], out.s[k][j][i] = sorted_s[k][j][i], out.v[k][j][i] = 0.0;
    for (int i = 0; i < m; ++i) {
      if (merge_lane[i] == 0.0) {
        out.n[i] = static_cast<int>(accepted[0][i] + accepted[1][i] + accepted[2][i] + accepted[3][i]);
        continue;
      }
      Candidate cands[C];
      for (int k = 0; k < C; ++k) {
        for (int j = 0; j < 3; ++j) cands[k].q[j] = JointValue{joint_c[k][j][i], joint_s[k][j][i], 0.0};
        cands[k].residual = ok[k][i] != 0.0 ? std::sqrt(res2[k][i]) : std::numeric_limits<double>::quiet_NaN();
      }
      JointValue q[kSlots][3];
      store(i, q, finish(V3(tx[i], ty[i], tz[i]), sc[i], cands, C, q));
    }
  }
 private:
  struct Candidate {
    JointValue q[3];
    double residual;
  };

  // Sample angles 2 pi k / 3 and 2 pi k / 5 for P's coefficients.
  static constexpr double kCos3[3] = {1.0, -0.5, -0.5}, kSin3[3] = {0.0, 0.8660254037844386, -0.8660254037844386};
  static constexpr double kCos5[5] = {1.0, 0.30901699437494745, -0.8090169943749473, -0.8090169943749476,
                                      0.30901699437494723};
  static constexpr double kSin5[5] = {0.0, 0.9510565162951535, 0.5877852522924732, -0.587785252292473,
                                      -0.9510565162951536};

  // Real roots q3 of (Q'), of degree 1 in (cos q3, sin q3), from its samples
  // at 2 pi k / 3: P = a0 + a1 cos + b1 sin exactly. Branch-free: writes both
  // candidate roots and returns how many exist (0, 1 or 2; one, q3 = 0, when
  // P is constant: q3 free or no solution, and the residual test decides).
  static SPOTKIN_INLINE double trig_roots3(double v0, double v1, double v2, double& c0, double& s0, double& c1,
                                           double& s1) noexcept {
    const double a0 = (v0 + v1 + v2) / 3.0;
    const double a1 = (2.0 / 3.0) * (v0 * kCos3[0] + v1 * kCos3[1] + v2 * kCos3[2]);
    const double b1 = (2.0 / 3.0) * (v1 * kSin3[1] + v2 * kSin3[2]);
    const double m1 = 0.5 * std::sqrt(a1 * a1 + b1 * b1), top = std::max(std::fabs(a0), m1);
    const bool varying = m1 > Tolerance::trim * top;
    const double found = detail::cos_sin_root(a1, b1, -a0, 1.0, c0, s0);
    detail::cos_sin_root(a1, b1, -a0, -1.0, c1, s1);
    c0 = varying ? c0 : 1.0, s0 = varying ? s0 : 0.0;
    return !(top == top) ? 0.0 : !varying ? 1.0 : 2.0 * found;
  }

  static SPOTKIN_INLINE int trig_roots3(const double vals[3], JointValue out[2]) noexcept {
    out[0].v = out[1].v = 0.0;
    return static_cast<int>(trig_roots3(vals[0], vals[1], vals[2], out[0].c, out[0].s, out[1].c, out[1].s));
  }

  // Real roots q3 of (Q) from its samples at 2 pi k / 5; the DFT gives
  // P = a0 + a1 cos + b1 sin + a2 cos 2q + b2 sin 2q exactly.
  static SPOTKIN_INLINE int trig_roots5(const double vals[5], JointValue out[4]) noexcept {
    double a0 = 0, a1 = 0, b1 = 0, a2 = 0, b2 = 0;
    for (int k = 0; k < 5; ++k) {
      const int k2 = (2 * k) % 5;
      a0 += vals[k];
      a1 += vals[k] * kCos5[k], b1 += vals[k] * kSin5[k];
      a2 += vals[k] * kCos5[k2], b2 += vals[k] * kSin5[k2];
    }
    a0 /= 5.0, a1 *= 0.4, b1 *= 0.4, a2 *= 0.4, b2 *= 0.4;
    // |c_m| of the complex form, m = 0, 1, 2
    const double m1 = 0.5 * std::sqrt(a1 * a1 + b1 * b1), m2 = 0.5 * std::sqrt(a2 * a2 + b2 * b2);
    const double top = std::max({std::fabs(a0), m1, m2});
    if (!(top == top)) return 0;
    if (m2 > Tolerance::trim * top) {
      // phi = theta_k* - pi, k* the sample of largest |P|: the quartic in
      // t = tan(theta / 2), q3 = phi + theta, has leading coefficient P(theta_k*).
      int kmax = 0;
      for (int k = 1; k < 5; ++k)
        if (std::fabs(vals[k]) > std::fabs(vals[kmax])) kmax = k;
      const double cp = -kCos5[kmax], sp = -kSin5[kmax];
      const double c2p = cp * cp - sp * sp, s2p = 2.0 * cp * sp;
      const double A1 = a1 * cp + b1 * sp, B1 = b1 * cp - a1 * sp;
      const double A2 = a2 * c2p + b2 * s2p, B2 = b2 * c2p - a2 * s2p;
      // (1 + t^2)^2 P(phi + theta), cos = (1 - t^2) / (1 + t^2), sin = 2 t / (1 + t^2)
      const double coef[5] = {a0 + A1 + A2, 2.0 * B1 + 4.0 * B2, 2.0 * a0 - 6.0 * A2, 2.0 * B1 - 4.0 * B2,
                              a0 - A1 + A2};
      detail::Complex z[4];
      detail::quartic_roots(coef, z);
      int n = 0;
      for (const auto& t : z) {
        const double re = t.real(), im = t.imag();
        // ||e^{i theta}| - 1| ~ 2 |Im t| / (1 + |t|^2)
        if (!(2.0 * std::fabs(im) <= Tolerance::root * (1.0 + re * re))) continue;
        const double d = 1.0 + re * re, ct = (1.0 - re * re) / d, st = 2.0 * re / d;
        out[n++] = JointValue{cp * ct - sp * st, sp * ct + cp * st, 0.0};
      }
      return n;
    }
    if (m1 > Tolerance::trim * top) return detail::cos_sin_roots(a1, b1, -a0, out);
    out[0] = joint_zero();  // P constant: q3 free or no solution; the residual test decides
    return 1;
  }

  // The forward problem target = Z1(q1) M1 Z2(q2) M2 Z3(q3) w of (F').
  struct Problem {
    int sig[3];
    V3 target;
    Rigid<double> M1, M2;
    V3 w;
    bool reduced;
    double s;

    // g(q3) = R2 Z3(q3) w + t2
    SPOTKIN_INLINE V3 g_of(const JointValue& q3) const noexcept { return M2.R * detail::z_apply(sig[2], q3, w) + M2.p; }

    // q2 revolute, eq. (L): rows r_a, r_b and kappa(g).
    SPOTKIN_INLINE void rows(V3& ra, V3& rb) const noexcept {
      if (sig[0] == 0) {
        ra = M1.R.transpose() * M1.p;      // u
        rb = M1.R.row(2).transpose();      // v = R1^T e3
      } else {
        ra = M1.R.row(0).transpose();
        rb = M1.R.row(1).transpose();
      }
    }
    SPOTKIN_INLINE Eigen::Vector2d kappa(const V3& g) const noexcept {
      if (sig[0] == 0)
        return {(target.squaredNorm() - g.squaredNorm() - M1.p.squaredNorm()) / 2.0, target[2] - M1.p[2]};
      return {target[0] - M1.p[0], target[1] - M1.p[1]};
    }

    // P(q3) of (Q), (Q') or the prismatic variants, and the back substitution.
    SPOTKIN_INLINE double P(const JointValue& q3, const V3& ra, const V3& rb) const noexcept {
      const V3 g = g_of(q3);
      if (sig[1] == 0) {
        const Eigen::Vector2d d = kappa(g) - Eigen::Vector2d(ra[2], rb[2]) * g[2];
        const double a00 = ra[0], a01 = ra[1], a10 = rb[0], a11 = rb[1];
        if (!reduced) {  // (Q) |adj(Rr) d|^2 - det(Rr)^2 (g_x^2 + g_y^2)
          const double det = a00 * a11 - a01 * a10;
          const double x = a11 * d[0] - a01 * d[1], y = -a10 * d[0] + a00 * d[1];
          return x * x + y * y - det * det * (g[0] * g[0] + g[1] * g[1]);
        }
        const Eigen::Vector2d n = null_row(a00, a01, a10, a11);  // (Q') n . d
        return n.dot(d);
      }
      const V3 u = M1.R.transpose() * M1.p, v = M1.R.row(2).transpose();
      if (sig[0] == 0) {
        if (!reduced) {  // RP: q2 from (I2), then (I1)
          const double q2 = (target[2] - M1.p[2] - v.dot(g)) / v[2];
          return (g + V3(0, 0, q2) + u).squaredNorm() - target.squaredNorm();
        }
        return v.dot(g) + M1.p[2] - target[2];
      }
      const V3 e = M1.R.col(2), k = M1.R * g + M1.p - target;  // PP
      return e[0] * k[1] - e[1] * k[0];
    }

    // A row of adj(Rr) of largest norm: the left null vector when det Rr = 0.
    static SPOTKIN_INLINE Eigen::Vector2d null_row(double a00, double a01, double a10, double a11) noexcept {
      const Eigen::Vector2d n0(a11, -a01), n1(-a10, a00);
      return n0.squaredNorm() >= n1.squaredNorm() ? n0 : n1;
    }

    // q2 values for a root q3 (eqs. (B), (B') and the prismatic forms).
    SPOTKIN_INLINE int back(const JointValue& q3, const V3& ra, const V3& rb, JointValue out[2]) const noexcept {
      const V3 g = g_of(q3);
      if (sig[1] == 0) {
        const Eigen::Vector2d d = kappa(g) - Eigen::Vector2d(ra[2], rb[2]) * g[2];
        const double a00 = ra[0], a01 = ra[1], a10 = rb[0], a11 = rb[1];
        if (!reduced) {  // (B): y = adj(Rr) d / det, e^{i q2} = y / (g_x + i g_y)
          const double det = a00 * a11 - a01 * a10;
          const double y0 = (a11 * d[0] - a01 * d[1]) / det, y1 = (-a10 * d[0] + a00 * d[1]) / det;
          out[0] = detail::angle_difference(y0, y1, g[0], g[1]);
          return 1;
        }
        // (B'): a cos q2 + b sin q2 = d_i on the row i of Rr of largest norm
        const bool first = a00 * a00 + a01 * a01 >= a10 * a10 + a11 * a11;
        const double r0 = first ? a00 : a10, r1 = first ? a01 : a11;
        const double a = r0 * g[0] + r1 * g[1], b = r1 * g[0] - r0 * g[1];
        return detail::cos_sin_roots(a, b, first ? d[0] : d[1], out);
      }
      const V3 u = M1.R.transpose() * M1.p, v = M1.R.row(2).transpose();
      if (sig[0] == 0) {
        if (!reduced) {
          out[0] = JointValue{1.0, 0.0, (target[2] - M1.p[2] - v.dot(g)) / v[2]};
          return 1;
        }
        // q2^2 + 2 (g_z + u_z) q2 + |g + u|^2 - |p'|^2 = 0
        const double b = g[2] + u[2], c = (g + u).squaredNorm() - target.squaredNorm();
        const double disc = b * b - c;
        if (disc < -Tolerance::ratio * s * s) return 0;
        const double root = std::sqrt(std::max(disc, 0.0));
        out[0] = JointValue{1.0, 0.0, -b + root};
        out[1] = JointValue{1.0, 0.0, -b - root};
        return 2;
      }
      const V3 e = M1.R.col(2), k = M1.R * g + M1.p - target;  // PP
      out[0] = JointValue{1.0, 0.0, -(e[0] * k[0] + e[1] * k[1]) / (e[0] * e[0] + e[1] * e[1])};
      return 1;
    }

    // Real roots q3 of P: a trigonometric polynomial of degree <= 2 (revolute
    // q3) or a polynomial of degree <= 4 (prismatic), recovered from 5 samples.
    SPOTKIN_INLINE int roots(const V3& ra, const V3& rb, JointValue out[4]) const noexcept {
      if (sig[2] == 0 && reduced) {
        double vals[3];
        for (int k = 0; k < 3; ++k) vals[k] = P(JointValue{kCos3[k], kSin3[k], 0.0}, ra, rb);
        return trig_roots3(vals, out);
      }
      if (sig[2] == 0) {
        double vals[5];
        for (int k = 0; k < 5; ++k) vals[k] = P(JointValue{kCos5[k], kSin5[k], 0.0}, ra, rb);
        return trig_roots5(vals, out);
      }
      // Prismatic q3 = s x: samples at the Chebyshev extrema x_k = cos(pi k / 4).
      static const Eigen::Matrix<double, 5, 5> inverse_vandermonde = [] {
        Eigen::Matrix<double, 5, 5> V;
        for (int k = 0; k < 5; ++k) {
          const double x = std::cos(kPi<double> * k / 4.0);
          for (int j = 0; j < 5; ++j) V(k, j) = std::pow(x, j);
        }
        return dense::inverse5(V);
      }();
      Eigen::Matrix<double, 5, 1> vals;
      for (int k = 0; k < 5; ++k) vals[k] = P(JointValue{1, 0, s * std::cos(kPi<double> * k / 4.0)}, ra, rb);
      const Eigen::Matrix<double, 5, 1> c = inverse_vandermonde * vals;
      const double top = c.cwiseAbs().maxCoeff();
      if (!(top == top)) return 0;
      int deg = 4;
      while (deg > 0 && std::fabs(c[deg]) <= Tolerance::trim * top) --deg;
      if (deg == 0) {
        out[0] = joint_zero();
        return 1;
      }
      detail::Complex z[4];
      const int m = detail::polynomial_roots(c.data(), deg, z);
      int n = 0;
      for (int k = 0; k < m; ++k)
        if (std::fabs(z[k].imag()) <= Tolerance::root * std::max(1.0, std::sqrt(std::norm(z[k]))))
          out[n++] = JointValue{1, 0, s * z[k].real()};
      return n;
    }

    // Tool point and its 3x3 Jacobian in the problem's frame.
    SPOTKIN_INLINE V3 point(const JointValue q[3], M3* J) const noexcept {
      const V3 h = detail::z_apply(sig[2], q[2], w);
      const V3 g = M2.R * h + M2.p;
      const V3 m = detail::z_apply(sig[1], q[1], g);
      const V3 f = M1.R * m + M1.p;
      const V3 p = detail::z_apply(sig[0], q[0], f);
      if (J) {
        J->col(0) = detail::z_tangent(sig[0], p);
        J->col(1) = detail::z_rotate(sig[0], q[0], M1.R * detail::z_tangent(sig[1], m));
        J->col(2) = detail::z_rotate(sig[0], q[0], M1.R * detail::z_rotate(sig[1], q[1], M2.R * detail::z_tangent(sig[2], h)));
      }
      return p;
    }

    // Candidates, each polished by Gauss-Newton on the position equations.
    SPOTKIN_INLINE int candidates(Candidate out[kMaxCandidates]) const noexcept {
      V3 ra = V3::Zero(), rb = V3::Zero();
      if (sig[1] == 0) rows(ra, rb);
      JointValue q3s[4];
      const int n3 = roots(ra, rb, q3s);
      int n = 0;
      for (int i = 0; i < n3; ++i) {
        JointValue q2s[2];
        const int n2 = back(q3s[i], ra, rb, q2s);
        const V3 g = g_of(q3s[i]);
        for (int j = 0; j < n2; ++j) {
          Candidate& c = out[n++];
          c.q[2] = q3s[i];
          c.q[1] = q2s[j];
          const V3 f = M1.R * detail::z_apply(sig[1], q2s[j], g) + M1.p;
          if (sig[0] == 0) {  // (I) q1 = angle(p'_xy) - angle(f_xy)
            c.q[0] = detail::angle_difference(target[0], target[1], f[0], f[1]);
          } else {
            c.q[0] = JointValue{1.0, 0.0, target[2] - f[2]};
          }
          polish(c);
        }
      }
      return n;
    }

    SPOTKIN_INLINE void polish(Candidate& c) const noexcept {
      // Steps stop once |fk(q) - p| <= 1e-13 s (4 orders below Tolerance::residual,
      // 3 below the 1e-10 accuracy promised; a closed-form root usually starts there).
      const double done = 1e-13 * s;
      V3 r = point(c.q, nullptr) - target;
      double res = r.norm();
      M3 J;
      if (res > done) point(c.q, &J);
      for (int step = 0; step < Tolerance::newton_steps && res > done; ++step) {
        // Gauss-Newton step J delta = -r (least squares when J is singular)
        V3 delta;
        const M3 adj = (M3() << J.col(1).cross(J.col(2)).transpose(), J.col(2).cross(J.col(0)).transpose(),
                        J.col(0).cross(J.col(1)).transpose())
                           .finished();
        const double det = J.col(0).dot(J.col(1).cross(J.col(2)));
        const double norms = J.col(0).norm() * J.col(1).norm() * J.col(2).norm();
        if (std::fabs(det) > 1e-8 * norms) {
          delta = -(adj * r) / det;
        } else {
          delta = -dense::svd_solve3(J, r);
        }
        Candidate next = c;
        for (int j = 0; j < 3; ++j) advance(sig[j], delta[j], next.q[j]);
        M3 J_next;
        const V3 r_next = point(next.q, &J_next) - target;
        const double res_next = r_next.norm();
        if (!(res_next < res)) break;
        c = next, r = r_next, res = res_next, J = J_next;
      }
      c.residual = res;
    }

    static SPOTKIN_INLINE void advance(int sigma, double delta, JointValue& q) noexcept {
      if (sigma == 1) {
        q.v += delta;
        return;
      }
      double sd, cd;
      if (std::fabs(delta) < 0.05) {  // Taylor to the 9th order: exact to 1e-16 here
        const double d2 = delta * delta;
        sd = delta * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0 * (1.0 - d2 / 72.0))));
        cd = 1.0 - d2 / 2.0 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0)));
      } else {
        sd = std::sin(delta), cd = std::cos(delta);
      }
      const double c = q.c * cd - q.s * sd, s = q.s * cd + q.c * sd;
      const double norm = std::sqrt(c * c + s * s);
      q.c = c / norm, q.s = s / norm;
    }
  };

  // Residual test, merging of near-equal solutions, angles, sorting.
  SPOTKIN_INLINE int finish(const V3& target, double s, Candidate* cands, int n, JointValue q[kSlots][3]) const noexcept {
    const double merge2 = Tolerance::merge * Tolerance::merge, length2 = s * s;
    // joint distance within Tolerance::merge: chord (revolute) or |dv| / s (prismatic)
    auto close = [&](const Candidate& a, const Candidate& b) SPOTKIN_INLINE_LAMBDA {
      for (int j = 0; j < 3; ++j) {
        const double dc = a.q[j].c - b.q[j].c, ds = a.q[j].s - b.q[j].s, dv = a.q[j].v - b.q[j].v;
        if (sigma_[j] == 0 ? dc * dc + ds * ds > merge2 : dv * dv > merge2 * length2) return false;
      }
      return true;
    };
    // accepted candidates, best residual first: a branch-free sorting network
    // for up to 4 (the residuals are random), else an insertion sort (at most 8)
    int order[kMaxCandidates], m = 0;
    if (n <= 4) {
      double key[4];
      for (int k = 0; k < 4; ++k) {
        const bool accepted = k < n && cands[k].residual <= Tolerance::residual * s;
        key[k] = accepted ? cands[k].residual : std::numeric_limits<double>::infinity();
        order[k] = k;
        m += accepted;
      }
      detail::sort4([&](int x, int y) SPOTKIN_INLINE_LAMBDA {
        const bool swap = key[order[y]] < key[order[x]];
        const int ox = order[x], oy = order[y];
        order[x] = swap ? oy : ox, order[y] = swap ? ox : oy;
      });
    } else {
      for (int k = 0; k < n; ++k) {
        if (!(cands[k].residual <= Tolerance::residual * s)) continue;
        int at = m++;
        for (; at > 0 && cands[order[at - 1]].residual > cands[k].residual; --at) order[at] = order[at - 1];
        order[at] = k;
      }
    }
    // merge solutions within Tolerance::merge into their mean (kept if it is a solution)
    const Candidate* groups[kMaxCandidates];
    Candidate means[kMaxCandidates];
    int count_groups = 0;
    bool used[kMaxCandidates] = {};
    for (int a = 0; a < m; ++a) {
      if (used[a]) continue;
      const Candidate& lead = cands[order[a]];
      Candidate& mean = means[count_groups];
      int count = 1;
      for (int b = a + 1; b < m; ++b) {
        const Candidate& other = cands[order[b]];
        if (used[b] || !close(lead, other)) continue;
        used[b] = true;
        if (count++ == 1) mean = lead;
        for (int j = 0; j < 3; ++j) mean.q[j].c += other.q[j].c, mean.q[j].s += other.q[j].s, mean.q[j].v += other.q[j].v;
      }
      const Candidate* kept = &lead;
      if (count > 1) {
        for (int j = 0; j < 3; ++j) {
          detail::unit(mean.q[j].c, mean.q[j].s, mean.q[j].c, mean.q[j].s);
          mean.q[j].v /= count;
        }
        const Problem forward{{sigma_[0], sigma_[1], sigma_[2]}, target, split_.M1, split_.M2, w_, reduced_, s};
        mean.residual = (forward.point(mean.q, nullptr) - target).norm();
        if (mean.residual <= Tolerance::residual * s) kept = &mean;
      }
      groups[count_groups++] = kept;
    }
    // the kSlots best residuals (groups keep the residual order; more than 4 never seen)
    count_groups = std::min(count_groups, kSlots);
    // (q1, q2, q3) order (detail::order_less, on detail::angle_key or v / s).
    // Branch-free (the signs and the order are random): keys, then a sorting
    // network over kSlots = 4 entries, missing ones keyed +inf.
    static_assert(kSlots == 4, "the sorting network below is for 4 slots");
    if (count_groups == 0) return 0;
    double keys[kSlots][3];
    int rank[kSlots] = {0, 1, 2, 3};
    for (int k = 0; k < kSlots; ++k)
      for (int j = 0; j < 3; ++j) {
        const JointValue& v = groups[std::min(k, count_groups - 1)]->q[j];
        const double key = sigma_[j] == 1 ? v.v / s : detail::angle_key(v.c, v.s);
        keys[k][j] = k < count_groups ? key : std::numeric_limits<double>::infinity();
      }
    detail::sort4([&](int x, int y) SPOTKIN_INLINE_LAMBDA {
      const double* a = keys[rank[x]];
      const double* b = keys[rank[y]];
      const bool swap = detail::order_less(b[0], b[1], b[2], a[0], a[1], a[2]);
      const int rx = rank[x], ry = rank[y];
      rank[x] = swap ? ry : rx, rank[y] = swap ? rx : ry;
    });
    for (int k = 0; k < count_groups; ++k)
      for (int j = 0; j < 3; ++j) q[k][j] = groups[rank[k]]->q[j];
    return count_groups;
  }

  // ValueError unless the position Jacobian has rank 3 somewhere (3 probes).
  void check_rank() const {
    static constexpr double probes[3][3] = {{0.7, -1.9, 2.4}, {-2.2, 0.5, -0.8}, {1.3, 2.9, -2.6}};
    double best = 0.0;
    for (const auto& probe : probes) {
      JointValue q[3];
      for (int j = 0; j < 3; ++j) q[j] = sigma_[j] == 0 ? JointValue{std::cos(probe[j]), std::sin(probe[j]), 0.0}
                                                        : JointValue{1, 0, probe[j] * scale_};
      const Problem pb{{sigma_[0], sigma_[1], sigma_[2]}, V3::Zero(), split_.M1, split_.M2, w_, false, scale_};
      M3 J;
      pb.point(q, &J);
      for (int j = 0; j < 3; ++j)
        if (sigma_[j] == 0) J.col(j) /= scale_;  // revolute columns carry a length
      best = std::max(best, dense::singular_values3(J)[2]);
    }
    if (!(best > Tolerance::rank))
      throw std::invalid_argument(
          "no closed form: the tool point of this " + pattern() +
          " chain cannot be placed in 3D (position Jacobian of rank < 3 at every probe configuration: "
          "e.g. a planar chain, coincident or concurrent axes, or the tool point on the last axis)");
  }

  std::string pattern() const {
    std::string s;
    for (int j = 0; j < 3; ++j) s += sigma_[j] == 0 ? 'R' : 'P';
    return s;
  }

  enum class Relation { Coincident, Parallel, Intersecting, Skew };

  // Axis z of the current frame vs axis z of frame M.
  Relation relation(const Rigid<double>& M) const noexcept {
    const V3 t = M.p, z = M.R.col(2);
    const V3 cross(-z[1], z[0], 0.0);  // e3 x z
    const double sin = cross.norm();
    if (sin <= Tolerance::angle)
      return std::hypot(t[0], t[1]) <= Tolerance::length * scale_ ? Relation::Coincident : Relation::Parallel;
    return std::fabs(t.dot(cross)) / sin <= Tolerance::length * scale_ ? Relation::Intersecting : Relation::Skew;
  }

  // Whether the pair (joint a, next joint b) gives the reduced equation (Q').
  bool reduces(int sa, int sb, const Rigid<double>& M) const noexcept {
    if (sa == 1 && sb == 1) return true;                           // PP: degree <= 2
    if (sa != sb) return std::fabs(M.R(2, 2)) <= Tolerance::angle;  // PR / RP: perpendicular axes
    const Relation r = relation(M);
    return r == Relation::Parallel || r == Relation::Intersecting;
  }

  void plan() {
    const Rigid<double> M2_inv = detail::inverse(split_.M2);
    if (sigma_[0] == 0 && sigma_[1] == 0 && sigma_[2] == 0) {
      const Relation r12 = relation(split_.M1), r23 = relation(split_.M2);
      if (r23 == Relation::Parallel) {
        kind_ = Kind::Parallel3R, backward_ = true, reduced_ = true;
      } else if (r12 == Relation::Parallel) {
        kind_ = Kind::Parallel3R, backward_ = false, reduced_ = true;
      } else if (r12 == Relation::Intersecting) {
        kind_ = Kind::Intersecting3R, backward_ = false, reduced_ = true;
      } else if (r23 == Relation::Intersecting) {
        kind_ = Kind::Intersecting3R, backward_ = true, reduced_ = true;
      } else {
        kind_ = Kind::GeneralQuartic3R, backward_ = false, reduced_ = false;
      }
      return;
    }
    kind_ = Kind::Prismatic;
    if (reduces(sigma_[0], sigma_[1], split_.M1)) {
      backward_ = false, reduced_ = true;
    } else if (reduces(sigma_[2], sigma_[1], M2_inv)) {
      backward_ = true, reduced_ = true;
    } else {
      backward_ = false, reduced_ = false;
    }
  }

  Split split_;
  V3 w_;
  double scale_;
  int sigma_[3];
  Kind kind_ = Kind::GeneralQuartic3R;
  bool backward_ = false, reduced_ = false;
  Rigid<double> M0_inv_, M1_inv_, M2_inv_;
  bool revolute_ = false;
  Rigid<double> P1_, P2_;  // M1 and M2 of the problem solved (reversed when backward_)
  V3 ra_ = V3::Zero(), rb_ = V3::Zero();
};


}  // namespace spotkin::chain_ik
