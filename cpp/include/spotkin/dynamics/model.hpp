// The dynamic model of a serial chain: spotkin::Chain's joints plus one rigid
// body per joint, and the per-block pieces every algorithm shares (poses from
// the chain's own per-joint transform code, broadcast model constants, I/O of
// row-major batches into lanes).
//
// Body j (0-based) is the link moved by joint j; its frame is frame j + 1 of
// Chain::frames (after joint j's pre . Motion . post). Inertial contract:
// mass[j], com[j] (3, in that frame) and inertia[j] (3x3 about the centre of
// mass, in that frame's axes). Joint 0's pose in the root frame includes the
// chain's base (a fixed base, or the mount on a floating body).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>

#include "spotkin/chain.hpp"
#include "spotkin/dynamics/pack.hpp"
#include "spotkin/dynamics/spatial.hpp"
#include "spotkin/stream.hpp"

namespace spotkin::dynamics {

// One link's inertial parameters, in double, about the link frame's origin.
struct LinkInertial {
  double mass = 0;
  Vec3<double> com = Vec3<double>::Zero();
  Mat3<double> inertia = Mat3<double>::Zero();  // about the centre of mass

  // Throws std::invalid_argument unless finite, mass >= 0, inertia symmetric
  // (to 1e-9 relative) and positive semidefinite (eigenvalues >= -1e-12 scale).
  void check(const std::string& what) const {
    if (!std::isfinite(mass) || !com.allFinite() || !inertia.allFinite())
      throw std::invalid_argument(what + ": mass, com and inertia must be finite");
    if (mass < 0) throw std::invalid_argument(what + ": mass must be >= 0");
    const double scale = std::max(1.0, inertia.cwiseAbs().maxCoeff());
    if ((inertia - inertia.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale)
      throw std::invalid_argument(what + ": inertia must be symmetric");
    Eigen::SelfAdjointEigenSolver<Mat3<double>> eig(0.5 * (inertia + inertia.transpose()), Eigen::EigenvaluesOnly);
    if (eig.eigenvalues().minCoeff() < -1e-12 * scale)
      throw std::invalid_argument(what + ": inertia must be positive semidefinite");
  }

  // m, h = m c, J = I_c + m (|c|^2 1 - c c^T) (parallel axes, RBDA eq. 2.63).
  void about_origin(double& m, double h[3], double J[3][3]) const {
    m = mass;
    const Mat3<double> Jo = 0.5 * (inertia + inertia.transpose()) +
                            mass * (com.squaredNorm() * Mat3<double>::Identity() - com * com.transpose());
    for (int r = 0; r < 3; ++r) {
      h[r] = mass * com[r];
      for (int c = 0; c < 3; ++c) J[r][c] = Jo(r, c);
    }
  }
};

// f(std::integral_constant<int, k>) for k = axis in {0, 1, 2}.
template <typename F>
SPOTKIN_INLINE decltype(auto) axis_switch(int axis, F&& f) {
  switch (axis) {
    case 0:
      return f(std::integral_constant<int, 0>{});
    case 1:
      return f(std::integral_constant<int, 1>{});
    default:
      return f(std::integral_constant<int, 2>{});
  }
}

template <typename M>
struct BodyConstants {
  bool revolute = true;
  bool no_shift = false;  // a revolute joint with no offset along its axis (r = 0)
  int axis = -1;  // S = (sign e_axis, 0) exactly (a URDF revolute joint about +-x, y or z): sparse products
  M sign = 1;
  M sw[3] = {0, 0, 0}, sv[3] = {0, 0, 0};  // motion subspace S (RBDA eq. 3.33) in the body frame
  M m = 0, h[3] = {0, 0, 0}, J[3][3] = {{0, 0, 0}, {0, 0, 0}, {0, 0, 0}};
};

// A chain's dynamic model computed L samples at a time in precision M.
template <typename M, int L>
class ChainModel {
 public:
  using P = Pack<M, L>;
  static constexpr int kLanes = L;

  ChainModel() = default;
  ChainModel(const Chain<double>& chain, const std::vector<LinkInertial>& links) {
    const int n = chain.dof();
    if (static_cast<int>(links.size()) != n)
      throw std::invalid_argument("one inertial per joint: expected " + std::to_string(n) + ", got " +
                                  std::to_string(links.size()));
    for (int j = 0; j < n; ++j) {
      links[static_cast<std::size_t>(j)].check("link " + std::to_string(j));
      Joint<double> joint = chain.joints()[static_cast<std::size_t>(j)];
      if (j == 0) {  // the base folded into joint 0's placement: poses are in the root frame
        const Rigid<double> base = chain.base().template cast<double>();
        joint.pre = Placement<double>::rigid(base * joint.pre.matrix());
      }
      BodyConstants<M> b;
      b.revolute = joint.type == JointType::Revolute;
      b.no_shift = b.revolute && joint.r == 0.0;
      // The motion about (along) u at the origin of the frame after pre . Motion,
      // seen from the body frame after post = (Rp, pp): w = Rp^T u, v = Rp^T (u x pp)
      // (revolute); w = 0, v = Rp^T u (prismatic).
      const Rigid<double> post = joint.post.matrix();
      const Vec3<double> u = joint.axis.template cast<double>();
      const Vec3<double> w = b.revolute ? Vec3<double>(post.R.transpose() * u) : Vec3<double>::Zero();
      const Vec3<double> v = b.revolute ? Vec3<double>(post.R.transpose() * u.cross(post.p))
                                        : Vec3<double>(post.R.transpose() * u);
      double m, h[3], J[3][3];
      links[static_cast<std::size_t>(j)].about_origin(m, h, J);
      b.m = M(m);
      for (int r = 0; r < 3; ++r) {
        b.sw[r] = M(w[r]), b.sv[r] = M(v[r]), b.h[r] = M(h[r]);
        for (int c = 0; c < 3; ++c) b.J[r][c] = M(J[r][c]);
      }
      if (v.isZero(0.0))
        for (int k = 0; k < 3; ++k)
          if (std::fabs(w[k]) == 1.0 && w[(k + 1) % 3] == 0.0 && w[(k + 2) % 3] == 0.0) b.axis = k, b.sign = M(w[k]);
      bodies_.push_back(b);
      joints_.push_back(joint.template cast<M>().template cast<P>());
    }
  }

  int dof() const noexcept { return static_cast<int>(joints_.size()); }
  const BodyConstants<M>& body(int j) const noexcept { return bodies_[static_cast<std::size_t>(j)]; }
  // Bit j set when joint j is revolute (its q is an angle), for joints below 64.
  std::uint64_t angle_columns() const noexcept {
    std::uint64_t bits = 0;
    for (int j = 0; j < dof() && j < 64; ++j)
      if (body(j).revolute) bits |= std::uint64_t{1} << j;
    return bits;
  }

  SPOTKIN_INLINE Motion<P> subspace(int j) const noexcept {
    const BodyConstants<M>& b = body(j);
    return {broadcast<P>(b.sw), broadcast<P>(b.sv)};
  }
  // S qd for a scalar joint rate qd.
  SPOTKIN_INLINE Motion<P> subspace_times(int j, const P& x) const noexcept {
    const BodyConstants<M>& b = body(j);
    return {{{P(b.sw[0]) * x, P(b.sw[1]) * x, P(b.sw[2]) * x}}, {{P(b.sv[0]) * x, P(b.sv[1]) * x, P(b.sv[2]) * x}}};
  }
  // The sparse forms below index with compile-time axes (axis_switch): an index known
  // only at run time would keep the spatial vectors in memory instead of registers.

  // S^T f.
  SPOTKIN_INLINE P project(int j, const Force<P>& f) const noexcept {
    const BodyConstants<M>& b = body(j);
    if (b.axis < 0) return dot(subspace(j), f);
    return axis_switch(b.axis, [&](auto K) { return b.sign > 0 ? f.n[K] : -f.n[K]; });
  }
  // m += S x.
  SPOTKIN_INLINE void add_subspace(int j, const P& x, Motion<P>& m) const noexcept {
    const BodyConstants<M>& b = body(j);
    if (b.axis < 0) {
      const Motion<P> s = subspace_times(j, x);
      m.w += s.w, m.v += s.v;
      return;
    }
    axis_switch(b.axis, [&](auto K) { m.w[K] += b.sign > 0 ? x : -x; });
  }
  // m x (S x) (RBDA eq. 2.31); for an axis joint (w x e_k, v x e_k) sign x, a x e_k = a_k2 e_k1 - a_k1 e_k2.
  SPOTKIN_INLINE Motion<P> cross_subspace(int j, const Motion<P>& m, const P& x) const noexcept {
    const BodyConstants<M>& b = body(j);
    if (b.axis < 0) return crm(m, subspace_times(j, x));
    const P s = b.sign > 0 ? x : -x;
    return axis_switch(b.axis, [&](auto K) {
      constexpr int k = decltype(K)::value, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
      Motion<P> o;
      o.w[k] = P(M(0)), o.w[k1] = m.w[k2] * s, o.w[k2] = -(m.w[k1] * s);
      o.v[k] = P(M(0)), o.v[k1] = m.v[k2] * s, o.v[k2] = -(m.v[k1] * s);
      return o;
    });
  }
  // IA S for an articulated inertia: (A e_k, B^T e_k) sign for an axis joint.
  SPOTKIN_INLINE Force<P> inertia_subspace(int j, const Inertia6<P>& I) const noexcept {
    const BodyConstants<M>& b = body(j);
    if (b.axis < 0) return apply(I, subspace(j));
    Force<P> o = axis_switch(b.axis, [&](auto K) {
      constexpr int k = decltype(K)::value;
      Force<P> r;
      for (int i = 0; i < 3; ++i) r.n[i] = I.A(i, k), r.f[i] = I.B(k, i);
      return r;
    });
    if (b.sign < 0) o.n = scale(o.n, P(M(-1))), o.f = scale(o.f, P(M(-1)));
    return o;
  }

  SPOTKIN_INLINE RigidInertia<P> inertia(int j) const noexcept {
    const BodyConstants<M>& b = body(j);
    RigidInertia<P> I;
    I.m = P(b.m);
    for (int r = 0; r < 3; ++r) {
      I.h[r] = P(b.h[r]);
      for (int c = 0; c < 3; ++c) I.J(r, c) = P(b.J[r][c]);
    }
    return I;
  }

  // sin and cos of every joint's rotation angle (theta + q, theta for a prismatic joint), in one
  // vector_math pass over dof() L values. scratch: 3 dof() L values.
  SPOTKIN_INLINE void joint_trig(const P* q, M* scratch, P* s, P* c) const noexcept {
    const int n = dof();
    M *angles = scratch, *sines = scratch + n * L, *cosines = sines + n * L;
    for (int j = 0; j < n; ++j) {
      const Joint<P>& joint = joints_[static_cast<std::size_t>(j)];
      const P angle = body(j).revolute ? P(joint.theta + q[j]) : joint.theta;
      std::memcpy(angles + j * L, &angle.v, sizeof angle.v);
    }
    vector_math::sincos(angles, sines, cosines, std::ptrdiff_t(n) * L);
    for (int j = 0; j < n; ++j) {
      std::memcpy(&s[j].v, sines + j * L, sizeof s[j].v);
      std::memcpy(&c[j].v, cosines + j * L, sizeof c[j].v);
    }
  }
  // x <- X_j^T x for a SymInertia or a Force of body j, into body j-1's frame (the root frame for
  // j = 0), piece by piece through X_j = pre . Rot(axis, theta + q) Trans(axis, shift) . post, each
  // piece in its sparse form (spatial.hpp); s, c from joint_trig.
  template <typename Q>
  SPOTKIN_INLINE void to_parent(int j, const P& q, const P& s, const P& c, Q& x) const noexcept {
    const Joint<P>& joint = joints_[static_cast<std::size_t>(j)];
    placement_to_parent(joint.post, x);
    const BodyConstants<M>& b = body(j);
    if (joint.axis_kind == AxisKind::General) {  // Rodrigues: R = c 1 + s [u]x + (1 - c) u u^T
      const P u[3] = {joint.axis[0], joint.axis[1], joint.axis[2]}, one_c = P(M(1)) - c;
      M3<P> R;
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) R(r, k) = one_c * u[r] * u[k] + (r == k ? c : P(M(0)));
      R(0, 1) -= s * u[2], R(0, 2) += s * u[1], R(1, 0) += s * u[2];
      R(1, 2) -= s * u[0], R(2, 0) -= s * u[1], R(2, 1) += s * u[0];
      rotate(x, R);
      if (!b.no_shift) {
        const P shift = b.revolute ? joint.r : P(joint.r + q);
        const P p[3] = {shift * u[0], shift * u[1], shift * u[2]};
        translate(x, p);
      }
    } else {
      axis_switch(static_cast<int>(joint.axis_kind), [&](auto K) {
        rotate_about<decltype(K)::value>(x, c, joint.axis_sign * s);
        if (!b.no_shift) translate_along<decltype(K)::value>(x, joint.axis_sign * (b.revolute ? joint.r : P(joint.r + q)));
      });
    }
    placement_to_parent(joint.pre, x);
  }
  // I S for a SymInertia: (J e_k, e_k x h) sign for an axis joint.
  SPOTKIN_INLINE Force<P> inertia_subspace(int j, const SymInertia<P>& I) const noexcept {
    const BodyConstants<M>& b = body(j);
    if (b.axis < 0) return apply(I, subspace(j));
    Force<P> o = axis_switch(b.axis, [&](auto K) {
      constexpr int k = decltype(K)::value, k1 = (k + 1) % 3, k2 = (k + 2) % 3;
      Force<P> r;
      for (int i = 0; i < 3; ++i) r.n[i] = I.J[kSymIndex[i][k]];
      r.f[k] = P(M(0)), r.f[k1] = -I.h[k2], r.f[k2] = I.h[k1];
      return r;
    });
    if (b.sign < 0) o.n = scale(o.n, P(M(-1))), o.f = scale(o.f, P(M(-1)));
    return o;
  }

  // X[j]: body j's pose in body j-1's frame (the root frame for j = 0), by the
  // chain's per-joint code: pre . Motion(axis, theta + q | r + q) . post.
  SPOTKIN_INLINE void poses(const P* q, Pose<P>* X) const noexcept {
    for (int j = 0; j < dof(); ++j) {
      const Joint<P>& joint = joints_[static_cast<std::size_t>(j)];
      const bool revolute = body(j).revolute;
      P s, c;
      sincos(revolute ? P(joint.theta + q[j]) : joint.theta, s, c);
      Rigid<P> T = joint.pre.X;
      joint.apply_motion(T, c, s, revolute ? joint.r : P(joint.r + q[j]));
      joint.post.apply(T);
      for (int r = 0; r < 3; ++r) {
        X[j].p[r] = T.p[r];
        for (int k = 0; k < 3; ++k) X[j].R(r, k) = T.R(r, k);
      }
    }
  }

 private:
  template <typename Q>
  static SPOTKIN_INLINE void placement_to_parent(const Placement<P>& pl, Q& x) noexcept {
    switch (pl.kind) {
      case PlacementKind::Identity:
        return;
      case PlacementKind::XScrew:  // TransX(a) RotX(alpha)
        rotate_about<0>(x, pl.cos_alpha, pl.sin_alpha);
        translate_along<0>(x, pl.a);
        return;
      case PlacementKind::Translation:
        translate(x, pl.X.p);
        return;
      case PlacementKind::General:
        rotate(x, pl.X.R);
        translate(x, pl.X.p);
        return;
    }
  }

  std::vector<Joint<P>> joints_;
  std::vector<BodyConstants<M>> bodies_;
};

// A batch input: sample i's row starts at data + i * stride (stride 0: one row for every sample).
template <typename M>
struct Rows {
  const M* data;
  std::ptrdiff_t stride;
};

// Loads `width` columns of samples b0 .. b0 + m - 1 into lanes (a short block
// repeats its last sample); clears ok[i] for a lane holding a NaN or an Inf.
// float32, a whole block of contiguous rows at least L / 2 wide: by groups of L
// columns, each row's L values loaded as one vector and the L x L group transposed
// in registers; a row whose group would read past the block's last value is filled
// value by value. (Element by element, the loads were a fifth of the float32 arm's
// RNEA: 65 -> 60 ns per sample on AVX2; float64 measured slower this way, 106 -> 113
// ns, and so did a 3-joint leg in float32.) At AVX-512 (16 float lanes), rows of L / 4
// to L / 2 values go by two halves of 8 samples (below).
template <typename M, int L>
SPOTKIN_INLINE void load(const Rows<M>& in, std::ptrdiff_t b0, int m, int width, Pack<M, L>* out,
                         bool* ok) noexcept {
  if constexpr (std::is_same_v<M, float> && L >= 4 && L <= 16) {
    if (m == L && in.stride == width && 2 * width >= L) {
      using V = typename Pack<M, L>::Vector;
      using Mask = decltype(V{} != V{});
      const M* block = in.data + b0 * width;
      Mask bad{};
      for (int j0 = 0; j0 < width; j0 += L) {
        const int w = std::min(L, width - j0);
        V r[L];
        for (int i = 0; i < L; ++i) {
          const M* at = block + i * width + j0;
          if (i * width + j0 + L <= L * width) {
            std::memcpy(&r[i], at, sizeof(V));
          } else {
            r[i] = V{};
            for (int k = 0; k < w; ++k) r[i][k] = at[k];
          }
        }
        transpose_lanes<M, L>(r);
        for (int k = 0; k < w; ++k) {
          out[j0 + k].v = r[k];
          bad |= (r[k] - r[k]) != V{};  // NaN for NaN and Inf
        }
      }
      for (int i = 0; i < L; ++i) ok[i] = ok[i] && bad[i] == 0;
      return;
    }
    if constexpr (L == 16) {  // AVX-512: rows of 4 to 7 (the arm's 6 in 16 lanes), two halves of
      // 8 samples, each 8 x 8 transposed, then joined in registers (arm RNEA 25.5 -> 19.8 ns; joined
      // through memory instead, two 32-byte stores read back as one 64-byte load, it was slower
      // than value by value: 27 -> 30 ns)
      constexpr int H = L / 2;
      if (m == L && in.stride == width && 2 * width >= H && width < H) {
        using V = typename Pack<M, L>::Vector;
        using HV = typename Pack<M, H>::Vector;
        using Mask = decltype(V{} != V{});
        const M* block = in.data + b0 * width;
        HV lo[H], hi[H];
        for (int i = 0; i < H; ++i) {
          std::memcpy(&lo[i], block + i * width, sizeof(HV));
          if ((H + i) * width + H <= L * width) {
            std::memcpy(&hi[i], block + (H + i) * width, sizeof(HV));
          } else {
            hi[i] = HV{};
            for (int k = 0; k < width; ++k) hi[i][k] = block[(H + i) * width + k];
          }
        }
        transpose_lanes<M, H>(lo);
        transpose_lanes<M, H>(hi);
        Mask bad{};
        for (int k = 0; k < width; ++k) {
          const V v = __builtin_shufflevector(lo[k], hi[k], 0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
          out[k].v = v;
          bad |= (v - v) != V{};  // NaN for NaN and Inf
        }
        for (int i = 0; i < L; ++i) ok[i] = ok[i] && bad[i] == 0;
        return;
      }
    }
  }
  for (int i = 0; i < L; ++i) {
    const M* row = in.data + (b0 + std::min(i, m - 1)) * in.stride;
    bool finite = true;
    for (int j = 0; j < width; ++j) {
      out[j].v[i] = row[j];
      finite &= std::isfinite(row[j]);
    }
    ok[i] = ok[i] && finite;
  }
}

// The layout of a symmetric n x n output (the mass matrix): Full, row-major n x n; Lower, the
// same with the strict upper triangle zero (LAPACK's lower storage); Packed, the lower triangle
// row by row, n (n + 1) / 2 values: A_ij (j <= i) at i (i + 1) / 2 + j.
enum class SymmetricLayout : int { Full = 0, Lower = 1, Packed = 2 };

constexpr int symmetric_width(int n, SymmetricLayout layout) noexcept {
  return layout == SymmetricLayout::Packed ? n * (n + 1) / 2 : n * n;
}

// Writes A_ij = A_ji (j <= i) of a symmetric n x n block of lanes into a packed lane buffer
// (A_ij at i (i + 1) / 2 + j), and one zero entry after it: every layout is then a gather from
// it (symmetric_gather, store's index), so that the kernel is compiled once for the three
// layouts (compiled per layout, it cost the two dynamics units 40 s of compiler time). The
// entries never written (the blocks between a floating body's chains) are zeroed once by clear().
template <typename P>
struct SymmetricWriter {
  P* out;
  int n;
  static constexpr int size(int n) noexcept { return n * (n + 1) / 2 + 1; }  // the buffer, with its zero
  SPOTKIN_INLINE void clear() const noexcept {
    for (int k = 0; k < size(n); ++k) out[k] = P(typename LanesOf<P>::Scalar(0));
  }
  SPOTKIN_INLINE void operator()(int i, int j, const P& x) const noexcept { out[i * (i + 1) / 2 + j] = x; }
};

// index[i n + j]: the entry of SymmetricWriter's buffer that a row in layout holds at i n + j:
// A_ij, or its mirror A_ji above the diagonal, for Full; A_ij on and below the diagonal and the
// zero entry above it for Lower. Null for Packed, whose rows are the buffer's own order.
inline const int* symmetric_gather(int n, SymmetricLayout layout, int* index) noexcept {
  if (layout == SymmetricLayout::Packed) return nullptr;
  const int zero = n * (n + 1) / 2;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      index[i * n + j] = j <= i ? i * (i + 1) / 2 + j : layout == SymmetricLayout::Full ? j * (j + 1) / 2 + i : zero;
  return index;
}

// store() of rows narrower than H (H <= L lanes, L / H groups of samples): see store().
template <typename M, int L, int H, bool Gather>
SPOTKIN_INLINE void store_narrow(const Pack<M, L>* in, int width, std::ptrdiff_t b0, int m, const bool* ok, M* out,
                                 const int* index) noexcept {
  using HV = typename Pack<M, H>::Vector;
  for (int g = 0; g * H < m; ++g) {
    HV r[H];
    for (int k = 0; k < H; ++k) {
      if (k < width)
        std::memcpy(&r[k], reinterpret_cast<const char*>(&in[Gather ? index[k] : k].v) + g * sizeof(HV), sizeof(HV));
      else
        r[k] = HV{};
    }
    transpose_lanes<M, H>(r);
    const int end = std::min(m, (g + 1) * H);
    for (int i = g * H; i < end; ++i) {
      M* row = out + (b0 + i) * width;
      if (!ok[i]) {
        for (int j = 0; j < width; ++j) row[j] = quiet_nan<M>();
      } else if (i + 1 < m) {
        std::memcpy(row, &r[i - g * H], sizeof(HV));
      } else {
        for (int j = 0; j < width; ++j) row[j] = r[i - g * H][j];
      }
    }
  }
}

// Stores `width` lanes-values (in[index[k]] for value k with Gather) of samples b0 .. b0 + m - 1, row-major; a lane
// whose inputs were not all finite gets NaN in its whole row. Groups of L
// columns of L lanes are transposed in registers; with `stream`, rows go
// through a small buffer and out with non-temporal stores (stream_fence after).
template <typename M, int L, bool Gather = false>
SPOTKIN_INLINE void store(const Pack<M, L>* in, int width, std::ptrdiff_t b0, int m, const bool* ok, M* out,
                          bool stream = false, const int* index = nullptr) noexcept {
  if (stream) {  // the block's rows are contiguous in out: assemble them, then stream them out
    thread_local std::vector<M> rows;
    const std::size_t count = std::size_t(m) * std::size_t(width);
    if (rows.size() < count) rows.resize(count);
    store<M, L, Gather>(in, width, 0, m, ok, rows.data(), false, index);
    stream_copy<M, L>(rows.data(), out + b0 * width, count);
    return;
  }
  if constexpr (L >= 8 && L <= 16) {
    // Rows narrower than the lanes (the arm's 6 torques in 8 or 16 lanes): groups of H samples
    // (H = L, or L / 2 for rows of at most L / 2), each column's H lanes transposed in
    // registers with zero columns past the row, then stored H wide. A row's store runs into
    // the next row's first values, which that row's own store then rewrites: the last row of
    // the block is stored value by value. (Float32 arm RNEA at AVX-512, value by value before:
    // 26.5 -> 25.0 ns.)
    if (width < L && 2 * width > L / 2) {
      if (2 * width <= L)
        return store_narrow<M, L, L / 2, Gather>(in, width, b0, m, ok, out, index);
      return store_narrow<M, L, L, Gather>(in, width, b0, m, ok, out, index);
    }
  }
  int j0 = 0;
  if constexpr (L >= 2 && L <= 16) {  // groups of L columns: transposed in registers
    for (; j0 + L <= width; j0 += L) {
      typename Pack<M, L>::Vector r[L];
      for (int k = 0; k < L; ++k) r[k] = in[Gather ? index[j0 + k] : j0 + k].v;
      transpose_lanes<M, L>(r);
      for (int i = 0; i < m; ++i)
        if (ok[i]) std::memcpy(out + (b0 + i) * width + j0, &r[i], sizeof r[i]);
    }
  }
  for (int i = 0; i < m; ++i) {
    M* row = out + (b0 + i) * width;
    if (!ok[i]) {
      for (int j = 0; j < width; ++j) row[j] = quiet_nan<M>();
      continue;
    }
    for (int j = j0; j < width; ++j) row[j] = in[Gather ? index[j] : j].v[i];
  }
}

// store() of a SymmetricWriter buffer in its layout: gathered through index, or in the buffer's
// own order (Packed, index null) without an indirection.
template <typename M, int L>
SPOTKIN_INLINE void store_symmetric(const Pack<M, L>* in, int width, std::ptrdiff_t b0, int m, const bool* ok, M* out,
                                    bool stream, const int* index) noexcept {
  if (index)
    store<M, L, true>(in, width, b0, m, ok, out, stream, index);
  else
    store(in, width, b0, m, ok, out, stream);
}

}  // namespace spotkin::dynamics
