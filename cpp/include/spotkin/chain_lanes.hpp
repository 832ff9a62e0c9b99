// Batched chain FK and geometric Jacobian across lanes: a block of samples side by side
// (structure of arrays), every joint's fixed placements and motion applied to the whole
// block at once, so that the loops over samples vectorise (4 doubles or 8 floats per AVX2
// register: float32 runs twice the samples per instruction). The equations are
// Chain::forward's and Chain::jacobian's (spotkin/chain.hpp):
//   T = base . prod_j (pre_j . Motion_j(q_j) . post_j) . tool,
//   J_j = [z_j x (p_tool - o_j); z_j] (revolute) or [z_j; 0] (prismatic),
// with the sines and cosines of the block computed first (vector_math::sincos, in the
// batch's precision). A short block is padded with its last sample, whose copies are not
// stored: a sample's result does not depend on its neighbours or on how a batch is split.
#pragma once

#include <algorithm>
#include <cstring>
#include <type_traits>
#include <vector>

#include "spotkin/chain.hpp"
#include "spotkin/dynamics/pack.hpp"

#ifndef SPOTKIN_CHAIN_LANES  // 16 measured best on AVX2 (8: 47 / 45 ns per 6-joint FK, 32: 40 / 26)
#define SPOTKIN_CHAIN_LANES 16
#endif

namespace spotkin::chain_lanes {

constexpr int kBlock = SPOTKIN_CHAIN_LANES;  // samples per block: a multiple of every register width
// A call with fewer samples runs Chain's per-sample code instead (a block costs as much as 16
// samples): a batch that small never spans threads (a thread's chunk is thousands of samples),
// so the choice depends on the whole batch only; the two may differ in the last bit.
constexpr std::ptrdiff_t kFewSamples = 8;

template <typename S>
struct LaneFrame {
  S R[3][3][kBlock];
  S p[3][kBlock];

  SPOTKIN_INLINE void set(const Rigid<S>& X) noexcept {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i < kBlock; ++i) R[r][c][i] = X.R(r, c);
      for (int i = 0; i < kBlock; ++i) p[r][i] = X.p[r];
    }
  }
};

// T <- T . P for every lane (Placement::apply, lane by lane).
template <typename S>
SPOTKIN_INLINE void apply(LaneFrame<S>& T, const Placement<S>& P) noexcept {
  switch (P.kind) {
    case PlacementKind::Identity:
      return;
    case PlacementKind::XScrew: {  // TransX(a) RotX(alpha)
      const S a = P.a, ca = P.cos_alpha, sa = P.sin_alpha;
      for (int r = 0; r < 3; ++r)
        for (int i = 0; i < kBlock; ++i) {
          T.p[r][i] += a * T.R[r][0][i];
          const S y = T.R[r][1][i], z = T.R[r][2][i];
          T.R[r][1][i] = ca * y + sa * z;
          T.R[r][2][i] = ca * z - sa * y;
        }
      return;
    }
    case PlacementKind::Translation: {
      const S x0 = P.X.p[0], x1 = P.X.p[1], x2 = P.X.p[2];
      for (int r = 0; r < 3; ++r)
        for (int i = 0; i < kBlock; ++i) T.p[r][i] += T.R[r][0][i] * x0 + T.R[r][1][i] * x1 + T.R[r][2][i] * x2;
      return;
    }
    case PlacementKind::General: {
      S X[3][3], x[3];
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) X[a][b] = P.X.R(a, b);
        x[a] = P.X.p[a];
      }
      for (int r = 0; r < 3; ++r)
        for (int i = 0; i < kBlock; ++i) {
          const S r0 = T.R[r][0][i], r1 = T.R[r][1][i], r2 = T.R[r][2][i];
          T.p[r][i] += r0 * x[0] + r1 * x[1] + r2 * x[2];
          for (int k = 0; k < 3; ++k) T.R[r][k][i] = r0 * X[0][k] + r1 * X[1][k] + r2 * X[2][k];
        }
      return;
    }
  }
}

// Rotation about +-e_k (k the third axis after I, J, cyclic) by (c, sign s), then the shift
// along it: columns I and J mix (Joint::rotate_columns).
template <int I, int J, typename S>
SPOTKIN_INLINE void rotate_columns(LaneFrame<S>& T, const S* c, const S* s, const S* shift, S sign) noexcept {
  constexpr int K = 3 - I - J;
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < kBlock; ++i) {
      const S ci = T.R[r][I][i], cj = T.R[r][J][i], si = sign * s[i];
      T.R[r][I][i] = c[i] * ci + si * cj;
      T.R[r][J][i] = c[i] * cj - si * ci;
      T.p[r][i] += sign * shift[i] * T.R[r][K][i];
    }
}

// T <- T . Rot(axis, angle) . Trans(axis, shift) per lane (Joint::apply_motion).
template <typename S>
SPOTKIN_INLINE void apply_motion(LaneFrame<S>& T, const Joint<S>& joint, const S* c, const S* s,
                                 const S* shift) noexcept {
  switch (joint.axis_kind) {
    case AxisKind::X:
      return rotate_columns<1, 2>(T, c, s, shift, joint.axis_sign);
    case AxisKind::Y:
      return rotate_columns<2, 0>(T, c, s, shift, joint.axis_sign);
    case AxisKind::Z:
      return rotate_columns<0, 1>(T, c, s, shift, joint.axis_sign);
    case AxisKind::General: {
      // R Rot(u, angle) = c R + s R [u]x + (1 - c) (R u) u^T (Rodrigues)
      const S u0 = joint.axis[0], u1 = joint.axis[1], u2 = joint.axis[2];
      for (int r = 0; r < 3; ++r)
        for (int i = 0; i < kBlock; ++i) {
          const S c0 = T.R[r][0][i], c1 = T.R[r][1][i], c2 = T.R[r][2][i];
          const S w = c0 * u0 + c1 * u1 + c2 * u2, one_c = S(1) - c[i];
          T.R[r][0][i] = c[i] * c0 + s[i] * (u2 * c1 - u1 * c2) + one_c * u0 * w;
          T.R[r][1][i] = c[i] * c1 + s[i] * (u0 * c2 - u2 * c0) + one_c * u1 * w;
          T.R[r][2][i] = c[i] * c2 + s[i] * (u1 * c0 - u0 * c1) + one_c * u2 * w;
          T.p[r][i] += shift[i] * w;
        }
      return;
    }
  }
}

// The joint axis in the frame reached after pre, per lane (Joint::axis_in).
template <typename S>
SPOTKIN_INLINE void axis_in(const LaneFrame<S>& T, const Joint<S>& joint, S (*out)[kBlock]) noexcept {
  if (joint.axis_kind == AxisKind::General) {
    const S u0 = joint.axis[0], u1 = joint.axis[1], u2 = joint.axis[2];
    for (int r = 0; r < 3; ++r)
      for (int i = 0; i < kBlock; ++i) out[r][i] = T.R[r][0][i] * u0 + T.R[r][1][i] * u1 + T.R[r][2][i] * u2;
    return;
  }
  const int k = static_cast<int>(joint.axis_kind);
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < kBlock; ++i) out[r][i] = joint.axis_sign * T.R[r][k][i];
}

// out[i * width + e] = soa[e][i] for the block's m samples. float: groups of 8 columns of 8
// lanes transposed in registers (dynamics::transpose_lanes, one AVX2 register each), then
// stored whole, the columns left over one by one; scalar moves were a third of the float
// kernel. double: element by element (its 4 x 4 transposes measured slower: 35 -> 47 ns per
// 6-joint FK on AVX2).
template <typename S>
SPOTKIN_INLINE void store_rows(const S (*soa)[kBlock], int width, std::ptrdiff_t m, S* out) noexcept {
  constexpr int L = 8;
  static_assert(kBlock % L == 0, "a block is whole registers");
  using V = typename dynamics::Pack<float, L>::Vector;
  int e0 = 0;
  if constexpr (std::is_same_v<S, float>)
    for (; e0 + L <= width; e0 += L)
    for (int i0 = 0; i0 < kBlock && i0 < m; i0 += L) {
      V r[L];
      for (int k = 0; k < L; ++k) std::memcpy(&r[k], &soa[e0 + k][i0], sizeof(V));
      dynamics::transpose_lanes<S, L>(r);
      for (int i = 0; i < L && i0 + i < m; ++i) std::memcpy(out + (i0 + i) * width + e0, &r[i], sizeof(V));
    }
  for (std::ptrdiff_t i = 0; i < m; ++i)
    for (int e = e0; e < width; ++e) out[i * width + e] = soa[e][i];
}

// The block's joint values by joint (padded with the last sample), their sines and cosines,
// and the shifts along the axes (r, plus q for a prismatic joint).
template <typename S>
struct LaneJoints {
  std::vector<S> c, s, shift;  // [n][kBlock]
  explicit LaneJoints(int n) : c(std::size_t(n) * kBlock), s(c.size()), shift(c.size()) {}

  SPOTKIN_INLINE void load(const Chain<S>& chain, const S* q, std::ptrdiff_t m) noexcept {
    const int n = chain.dof();
    S angle[kBlock];
    for (int j = 0; j < n; ++j) {
      const Joint<S>& joint = chain.joints()[std::size_t(j)];
      const bool revolute = joint.type == JointType::Revolute;
      S* sh = shift.data() + std::size_t(j) * kBlock;
      for (int i = 0; i < kBlock; ++i) {
        const S qi = q[std::min<std::ptrdiff_t>(i, m - 1) * n + j];
        angle[i] = revolute ? joint.theta + qi : joint.theta;
        sh[i] = revolute ? joint.r : joint.r + qi;
      }
      vector_math::sincos(angle, s.data() + std::size_t(j) * kBlock, c.data() + std::size_t(j) * kBlock, kBlock);
    }
  }
};

// T of the block, tool included, and, when axes is given, every joint's axis and origin
// ([3 n][kBlock] each) on the way. Each step is one pass over the block's lanes.
template <typename S>
SPOTKIN_INLINE void walk(const Chain<S>& chain, const Placement<S>& tool, const LaneJoints<S>& lanes,
                         LaneFrame<S>& T, S (*axes)[kBlock], S (*origins)[kBlock]) noexcept {
  T.set(chain.base());
  const int n = chain.dof();
  for (int j = 0; j < n; ++j) {
    const Joint<S>& joint = chain.joints()[std::size_t(j)];
    apply(T, joint.pre);
    if (axes) {
      axis_in(T, joint, axes + 3 * j);
      for (int r = 0; r < 3; ++r) std::memcpy(origins[3 * j + r], T.p[r], sizeof T.p[r]);
    }
    const std::size_t o = std::size_t(j) * kBlock;
    apply_motion(T, joint, lanes.c.data() + o, lanes.s.data() + o, lanes.shift.data() + o);
    apply(T, joint.post);
  }
  apply(T, tool);
}

// Base -> tool transforms of count samples (q row-major count x n) as 4 x 4 matrices.
template <typename S>
SPOTKIN_INLINE void forward_batch(const Chain<S>& chain, const S* q, S* out, std::ptrdiff_t count) {
  if (count < kFewSamples) return chain.forward_batch(q, out, count);
  const int n = chain.dof();
  const Placement<S> tool = Placement<S>::rigid(chain.tool().template cast<double>());
  LaneJoints<S> lanes(n);
  LaneFrame<S> T;
  alignas(64) S rows[16][kBlock];
  for (int e = 12; e < 16; ++e)
    for (int i = 0; i < kBlock; ++i) rows[e][i] = e == 15 ? S(1) : S(0);
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min<std::ptrdiff_t>(kBlock, count - b0);
    lanes.load(chain, q + b0 * n, m);
    walk<S>(chain, tool, lanes, T, nullptr, nullptr);
    if constexpr (std::is_same_v<S, float>) {  // 16 columns of lanes, transposed in registers
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) std::memcpy(rows[4 * r + c], T.R[r][c], sizeof rows[0]);
        std::memcpy(rows[4 * r + 3], T.p[r], sizeof rows[0]);
      }
      store_rows<S>(rows, 16, m, out + 16 * b0);
    } else {
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        S* o = out + 16 * (b0 + i);
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) o[4 * r + c] = T.R[r][c][i];
          o[4 * r + 3] = T.p[r][i];
        }
        o[12] = o[13] = o[14] = S(0);
        o[15] = S(1);
      }
    }
  }
}

// rows x n geometric Jacobians (rows 6, or 3 for the linear block) of count samples; in the
// tool frame, both blocks rotated by R_tool^T.
template <typename S>
SPOTKIN_INLINE void jacobian_batch(const Chain<S>& chain, const S* q, S* out, std::ptrdiff_t count, int rows,
                                   bool in_tool_frame) {
  if (count < kFewSamples) return chain.jacobian_batch(q, out, count, rows, in_tool_frame);
  const int n = chain.dof();
  const Placement<S> tool = Placement<S>::rigid(chain.tool().template cast<double>());
  LaneJoints<S> lanes(n);
  LaneFrame<S> T;
  std::vector<S> axis_store(std::size_t(3 * n) * kBlock), origin_store(axis_store.size());
  auto* axes = reinterpret_cast<S(*)[kBlock]>(axis_store.data());
  auto* origins = reinterpret_cast<S(*)[kBlock]>(origin_store.data());
  const std::ptrdiff_t width = std::ptrdiff_t(rows) * n;
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += kBlock) {
    const std::ptrdiff_t m = std::min<std::ptrdiff_t>(kBlock, count - b0);
    lanes.load(chain, q + b0 * n, m);
    walk<S>(chain, tool, lanes, T, axes, origins);
    for (int j = 0; j < n; ++j) {
      const bool revolute = chain.joints()[std::size_t(j)].type == JointType::Revolute;
      const S(*z)[kBlock] = axes + 3 * j;
      const S(*o)[kBlock] = origins + 3 * j;
      S v[3][kBlock], w[3][kBlock];
      for (int i = 0; i < kBlock; ++i) {
        const S d0 = T.p[0][i] - o[0][i], d1 = T.p[1][i] - o[1][i], d2 = T.p[2][i] - o[2][i];
        v[0][i] = revolute ? z[1][i] * d2 - z[2][i] * d1 : z[0][i];
        v[1][i] = revolute ? z[2][i] * d0 - z[0][i] * d2 : z[1][i];
        v[2][i] = revolute ? z[0][i] * d1 - z[1][i] * d0 : z[2][i];
        for (int r = 0; r < 3; ++r) w[r][i] = revolute ? z[r][i] : S(0);
      }
      if (in_tool_frame)
        for (auto* x : {v, w})
          for (int i = 0; i < kBlock; ++i) {
            const S x0 = x[0][i], x1 = x[1][i], x2 = x[2][i];
            for (int c = 0; c < 3; ++c) x[c][i] = T.R[0][c][i] * x0 + T.R[1][c][i] * x1 + T.R[2][c][i] * x2;
          }
      for (std::ptrdiff_t i = 0; i < m; ++i) {
        S* J = out + width * (b0 + i);
        for (int r = 0; r < 3; ++r) J[r * n + j] = v[r][i];
        if (rows == 6)
          for (int r = 0; r < 3; ++r) J[(r + 3) * n + j] = w[r][i];
      }
    }
  }
}

}  // namespace spotkin::chain_lanes
