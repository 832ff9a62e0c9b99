// Batched chain FK and geometric Jacobian across lanes: a block of samples side by side
// (structure of arrays), every joint's fixed placements and motion applied to the whole
// block at once, so that the loops over samples vectorise (4 doubles or 8 floats per AVX2
// register: float32 runs twice the samples per instruction). The equations are
// Chain::forward's and Chain::jacobian's (spotkin/chain.hpp):
//   T = base . prod_j (pre_j . Motion_j(q_j) . post_j) . tool,
//   J_j = [z_j x (p_tool - o_j); z_j] (revolute) or [z_j; 0] (prismatic),
// with the sines and cosines of the block computed first (vector_math::sincos, in the
// batch's precision). A short block is padded with its last sample, whose copies are not
// stored: a sample's result does not depend on its neighbours, on how a batch is split or on
// the size of the call (without fused multiply-adds, the same equations give the same bits in
// blocks of 16 and of 4 lanes).
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
constexpr int kSmallBlock = 4;               // calls of fewer than kBlock samples

template <typename S, int B>
struct LaneFrame {
  S R[3][3][B];
  S p[3][B];

  SPOTKIN_INLINE void set(const Rigid<S>& X) noexcept {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c)
        for (int i = 0; i < B; ++i) R[r][c][i] = X.R(r, c);
      for (int i = 0; i < B; ++i) p[r][i] = X.p[r];
    }
  }
};

// T <- T . P for every lane (Placement::apply, lane by lane).
template <typename S, int B>
SPOTKIN_INLINE void apply(LaneFrame<S, B>& T, const Placement<S>& P) noexcept {
  switch (P.kind) {
    case PlacementKind::Identity:
      return;
    case PlacementKind::XScrew: {  // TransX(a) RotX(alpha)
      const S a = P.a, ca = P.cos_alpha, sa = P.sin_alpha;
      for (int r = 0; r < 3; ++r)
        for (int i = 0; i < B; ++i) {
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
        for (int i = 0; i < B; ++i) T.p[r][i] += T.R[r][0][i] * x0 + T.R[r][1][i] * x1 + T.R[r][2][i] * x2;
      return;
    }
    case PlacementKind::General: {
      S X[3][3], x[3];
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b < 3; ++b) X[a][b] = P.X.R(a, b);
        x[a] = P.X.p[a];
      }
      for (int r = 0; r < 3; ++r)
        for (int i = 0; i < B; ++i) {
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
template <int I, int J, typename S, int B>
SPOTKIN_INLINE void rotate_columns(LaneFrame<S, B>& T, const S* c, const S* s, const S* shift, S sign) noexcept {
  constexpr int K = 3 - I - J;
  for (int r = 0; r < 3; ++r)
    for (int i = 0; i < B; ++i) {
      const S ci = T.R[r][I][i], cj = T.R[r][J][i], si = sign * s[i];
      T.R[r][I][i] = c[i] * ci + si * cj;
      T.R[r][J][i] = c[i] * cj - si * ci;
      T.p[r][i] += sign * shift[i] * T.R[r][K][i];
    }
}

// T <- T . Rot(axis, angle) . Trans(axis, shift) per lane (Joint::apply_motion).
template <typename S, int B>
SPOTKIN_INLINE void apply_motion(LaneFrame<S, B>& T, const Joint<S>& joint, const S* c, const S* s,
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
        for (int i = 0; i < B; ++i) {
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
template <typename S, int B>
SPOTKIN_INLINE void axis_in(const LaneFrame<S, B>& T, const Joint<S>& joint, S (*out)[B]) noexcept {
  if (joint.axis_kind == AxisKind::General) {
    const S u0 = joint.axis[0], u1 = joint.axis[1], u2 = joint.axis[2];
    for (int r = 0; r < 3; ++r)
      for (int i = 0; i < B; ++i) out[r][i] = T.R[r][0][i] * u0 + T.R[r][1][i] * u1 + T.R[r][2][i] * u2;
    return;
  }
  // The sign in a local, and each row formed in a local then copied: a store through `out` may
  // alias the joint and the frame, so GCC reloaded the sign at every lane and left the loop scalar
  // (perf: a fifth of the float Jacobian at AVX-512).
  const int k = static_cast<int>(joint.axis_kind);
  const S sign = joint.axis_sign;
  for (int r = 0; r < 3; ++r) {
    S row[B];
    for (int i = 0; i < B; ++i) row[i] = sign * T.R[r][k][i];
    std::memcpy(out[r], row, sizeof row);
  }
}

// out[i * width + e] = soa[e][i] for the block's m samples. float: groups of 8 columns of 8
// lanes transposed in registers (dynamics::transpose_lanes, one AVX2 register each), then
// stored whole, the columns left over one by one (scalar moves were a third of the float FK's
// samples; the time gained was small, 22 -> 21 ns). double: the same with 8 x 8 doubles where
// Wide (the AVX-512 clones, one register each); element by element otherwise (staging the
// rows for 4 x 4 transposes measured slower, 35 -> 47 ns per 6-joint FK on AVX2).
template <typename S, int B, bool Wide = false>
SPOTKIN_INLINE void store_rows(const S (*soa)[B], int width, std::ptrdiff_t m, S* out) noexcept {
  constexpr int L = 8;
  using V = typename dynamics::Pack<S, L>::Vector;
  int e0 = 0;
  if constexpr ((std::is_same_v<S, float> || Wide) && B % L == 0)
    for (; e0 + L <= width; e0 += L)
    for (int i0 = 0; i0 < B && i0 < m; i0 += L) {
      V r[L];
      for (int k = 0; k < L; ++k) std::memcpy(&r[k], &soa[e0 + k][i0], sizeof(V));
      dynamics::transpose_lanes<S, L>(r);
      for (int i = 0; i < L && i0 + i < m; ++i) std::memcpy(out + (i0 + i) * width + e0, &r[i], sizeof(V));
    }
  for (std::ptrdiff_t i = 0; i < m; ++i)
    for (int e = e0; e < width; ++e) out[i * width + e] = soa[e][i];
}

// A thread's scratch buffer of at least count values (slot: two buffers used at once), kept
// between calls: a single sample from a control loop allocates nothing.
template <typename S, int Slot>
S* scratch(std::size_t count) {
  thread_local std::vector<S> buffer;
  if (buffer.size() < count) buffer.resize(count);
  return buffer.data();
}

// The block's joint values by joint (padded with the last sample), their sines and cosines,
// and the shifts along the axes (r, plus q for a prismatic joint). load<true> (the Jacobian's
// small blocks: a control loop's call) writes every joint's angles first and takes their sines
// and cosines in one pass over [n][B]: joint by joint, each vector load of a joint's B angles just
// after their scalar stores missed store-to-load forwarding (perf: the single-sample Jacobian's
// hottest instruction). Everything else keeps the joint-by-joint pass: FK's and the frames' full
// blocks measured 5-6 % slower with the other pass compiled beside them. The angles stay in a
// local array (in the thread's scratch, which the compiler cannot tell from q, the full blocks
// were 4-9 % slower). Element by element both ways: the same bits.
template <typename S, int B>
struct LaneJoints {
  static constexpr int kOnePassJoints = 32;  // the small blocks' one pass, up to this many joints
  S *c, *s, *shift;                          // [n][B] each, in the thread's scratch
  explicit LaneJoints(int n) {
    S* at = scratch<S, 0>(3 * std::size_t(n) * B);
    c = at, s = at + std::size_t(n) * B, shift = at + 2 * std::size_t(n) * B;
  }

  template <bool OnePass = false>
  SPOTKIN_INLINE void load(const Chain<S>& chain, const S* q, std::ptrdiff_t m) noexcept {
    const int n = chain.dof();
    if constexpr (OnePass) {
      if (n <= kOnePassJoints) {
        S angle[kOnePassJoints * B];
        for (int j = 0; j < n; ++j) {
          const Joint<S>& joint = chain.joints()[std::size_t(j)];
          const bool revolute = joint.type == JointType::Revolute;
          S* sh = shift + std::size_t(j) * B;
          S* a = angle + std::size_t(j) * B;
          for (int i = 0; i < B; ++i) {
            const S qi = q[std::min<std::ptrdiff_t>(i, m - 1) * n + j];
            a[i] = revolute ? joint.theta + qi : joint.theta;
            sh[i] = revolute ? joint.r : joint.r + qi;
          }
        }
        vector_math::sincos(angle, s, c, std::ptrdiff_t(n) * B);
        return;
      }
    }
    S angle[B];
    for (int j = 0; j < n; ++j) {
      const Joint<S>& joint = chain.joints()[std::size_t(j)];
      const bool revolute = joint.type == JointType::Revolute;
      S* sh = shift + std::size_t(j) * B;
      for (int i = 0; i < B; ++i) {
        const S qi = q[std::min<std::ptrdiff_t>(i, m - 1) * n + j];
        angle[i] = revolute ? joint.theta + qi : joint.theta;
        sh[i] = revolute ? joint.r : joint.r + qi;
      }
      vector_math::sincos(angle, s + std::size_t(j) * B, c + std::size_t(j) * B, B);
    }
  }
};

// T of the block, tool included; when axes is given, every joint's axis and origin
// ([3 n][B] each) on the way; when frames is given, the frame after the base, after each joint
// and after the tool ([n + 2][12][B]: R row by row, then p).
template <typename S, int B>
SPOTKIN_INLINE void walk(const Chain<S>& chain, const Placement<S>& tool, const LaneJoints<S, B>& lanes,
                         LaneFrame<S, B>& T, S (*axes)[B], S (*origins)[B], S (*frames)[12][B]) noexcept {
  auto keep = [&](int k) {
    if (!frames) return;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) std::memcpy(frames[k][3 * r + c], T.R[r][c], sizeof T.R[r][c]);
      std::memcpy(frames[k][9 + r], T.p[r], sizeof T.p[r]);
    }
  };
  T.set(chain.base());
  keep(0);
  const int n = chain.dof();
  for (int j = 0; j < n; ++j) {
    const Joint<S>& joint = chain.joints()[std::size_t(j)];
    apply(T, joint.pre);
    if (axes) {
      axis_in(T, joint, axes + 3 * j);
      for (int r = 0; r < 3; ++r) std::memcpy(origins[3 * j + r], T.p[r], sizeof T.p[r]);
    }
    const std::size_t o = std::size_t(j) * B;
    apply_motion(T, joint, lanes.c + o, lanes.s + o, lanes.shift + o);
    apply(T, joint.post);
    keep(j + 1);
  }
  apply(T, tool);
  keep(n + 1);
}

// Base -> tool transforms of count samples (q row-major count x n) as 4 x 4 matrices. Wide:
// double rows leave through 8 x 8 transposes too (store_rows; the AVX-512 clones).
template <typename S, int B, bool Wide = false>
SPOTKIN_INLINE void forward_blocks(const Chain<S>& chain, const S* q, S* out, std::ptrdiff_t count) {
  const int n = chain.dof();
  const Placement<S> tool = Placement<S>::rigid(chain.tool().template cast<double>());
  LaneJoints<S, B> lanes(n);
  LaneFrame<S, B> T;
  alignas(64) S rows[16][B];
  for (int e = 12; e < 16; ++e)
    for (int i = 0; i < B; ++i) rows[e][i] = e == 15 ? S(1) : S(0);
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += B) {
    const std::ptrdiff_t m = std::min<std::ptrdiff_t>(B, count - b0);
    lanes.load(chain, q + b0 * n, m);
    walk<S, B>(chain, tool, lanes, T, nullptr, nullptr, nullptr);
    if constexpr (std::is_same_v<S, float> || Wide) {  // 16 columns of lanes, transposed in registers
      for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) std::memcpy(rows[4 * r + c], T.R[r][c], sizeof rows[0]);
        std::memcpy(rows[4 * r + 3], T.p[r], sizeof rows[0]);
      }
      store_rows<S, B, Wide>(rows, 16, m, out + 16 * b0);
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
// tool frame, both blocks rotated by R_tool^T. Staged (float only): the block's Jacobians are
// staged by entry ([rows n][B]) and stored through store_rows' in-register transposes; measured
// on AVX-512 (Zen 5, 6 joints): 23.3 -> 20.7 ns, but 24.9 -> 27.5 ns on AVX2, so only the
// AVX-512 clone stages. Otherwise each entry is stored from its lane, as the double FK does.
template <typename S, int B, bool Staged>
SPOTKIN_INLINE void jacobian_blocks(const Chain<S>& chain, const S* q, S* out, std::ptrdiff_t count, int rows,
                                    bool in_tool_frame) {
  const int n = chain.dof();
  const Placement<S> tool = Placement<S>::rigid(chain.tool().template cast<double>());
  LaneJoints<S, B> lanes(n);
  LaneFrame<S, B> T;
  const std::ptrdiff_t width = std::ptrdiff_t(rows) * n;
  constexpr bool kStaged = Staged && std::is_same_v<S, float>;
  S* store = scratch<S, 1>((2 * std::size_t(3 * n) + (kStaged ? std::size_t(width) : 0)) * B);
  auto* axes = reinterpret_cast<S(*)[B]>(store);
  auto* origins = reinterpret_cast<S(*)[B]>(store + std::size_t(3 * n) * B);
  auto* staged = reinterpret_cast<S(*)[B]>(store + 2 * std::size_t(3 * n) * B);
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += B) {
    const std::ptrdiff_t m = std::min<std::ptrdiff_t>(B, count - b0);
    lanes.template load<(B < kBlock)>(chain, q + b0 * n, m);
    walk<S, B>(chain, tool, lanes, T, axes, origins, nullptr);
    for (int j = 0; j < n; ++j) {
      const bool revolute = chain.joints()[std::size_t(j)].type == JointType::Revolute;
      const S(*z)[B] = axes + 3 * j;
      const S(*o)[B] = origins + 3 * j;
      S v[3][B], w[3][B];
      for (int i = 0; i < B; ++i) {
        const S d0 = T.p[0][i] - o[0][i], d1 = T.p[1][i] - o[1][i], d2 = T.p[2][i] - o[2][i];
        v[0][i] = revolute ? z[1][i] * d2 - z[2][i] * d1 : z[0][i];
        v[1][i] = revolute ? z[2][i] * d0 - z[0][i] * d2 : z[1][i];
        v[2][i] = revolute ? z[0][i] * d1 - z[1][i] * d0 : z[2][i];
        for (int r = 0; r < 3; ++r) w[r][i] = revolute ? z[r][i] : S(0);
      }
      if (in_tool_frame)
        for (auto* x : {v, w})
          for (int i = 0; i < B; ++i) {
            const S x0 = x[0][i], x1 = x[1][i], x2 = x[2][i];
            for (int c = 0; c < 3; ++c) x[c][i] = T.R[0][c][i] * x0 + T.R[1][c][i] * x1 + T.R[2][c][i] * x2;
          }
      if constexpr (kStaged) {
        for (int r = 0; r < 3; ++r) std::memcpy(staged[r * n + j], v[r], sizeof v[r]);
        if (rows == 6)
          for (int r = 0; r < 3; ++r) std::memcpy(staged[(r + 3) * n + j], w[r], sizeof w[r]);
      } else {
        for (std::ptrdiff_t i = 0; i < m; ++i) {
          S* J = out + width * (b0 + i);
          for (int r = 0; r < 3; ++r) J[r * n + j] = v[r][i];
          if (rows == 6)
            for (int r = 0; r < 3; ++r) J[(r + 3) * n + j] = w[r][i];
        }
      }
    }
    if constexpr (kStaged) store_rows<S, B>(staged, int(width), m, out + width * b0);
  }
}

// (n + 2) frames per sample (base, after each joint, tool), as Chain::frames: the walk FK
// takes, so the last frame is FK's pose bit for bit.
template <typename S, int B>
SPOTKIN_INLINE void frames_blocks(const Chain<S>& chain, const S* q, S* out, std::ptrdiff_t count) {
  const int n = chain.dof();
  const std::ptrdiff_t stride = 16 * (n + 2);
  const Placement<S> tool = Placement<S>::rigid(chain.tool().template cast<double>());
  LaneJoints<S, B> lanes(n);
  LaneFrame<S, B> T;
  auto* frames = reinterpret_cast<S(*)[12][B]>(scratch<S, 1>(std::size_t(n + 2) * 12 * B));
  for (std::ptrdiff_t b0 = 0; b0 < count; b0 += B) {
    const std::ptrdiff_t m = std::min<std::ptrdiff_t>(B, count - b0);
    lanes.load(chain, q + b0 * n, m);
    walk<S, B>(chain, tool, lanes, T, nullptr, nullptr, frames);
    for (std::ptrdiff_t i = 0; i < m; ++i)
      for (int k = 0; k < n + 2; ++k) {
        S* o = out + stride * (b0 + i) + 16 * k;
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) o[4 * r + c] = frames[k][3 * r + c][i];
          o[4 * r + 3] = frames[k][9 + r][i];
        }
        o[12] = o[13] = o[14] = S(0);
        o[15] = S(1);
      }
  }
}

// The entry points: blocks of kBlock lanes, or of kSmallBlock for a call of fewer than kBlock
// samples (a single pose pays for 4 lanes, not 16). The translation unit is compiled without
// fused multiply-adds (-ffp-contract=off, CMakeLists.txt), so the same equations give the same
// bits lane by lane at either width (tested at every level: single calls equal a batch's rows).
template <bool Wide = false, typename S>
SPOTKIN_INLINE void forward_batch(const Chain<S>& chain, const S* q, S* out, std::ptrdiff_t count) {
  if (count < kBlock) return forward_blocks<S, kSmallBlock>(chain, q, out, count);
  forward_blocks<S, kBlock, Wide>(chain, q, out, count);
}
template <typename S>
SPOTKIN_INLINE void frames_batch(const Chain<S>& chain, const S* q, S* out, std::ptrdiff_t count) {
  if (count < kBlock) return frames_blocks<S, kSmallBlock>(chain, q, out, count);
  frames_blocks<S, kBlock>(chain, q, out, count);
}
template <bool Staged = false, typename S>
SPOTKIN_INLINE void jacobian_batch(const Chain<S>& chain, const S* q, S* out, std::ptrdiff_t count, int rows,
                                   bool in_tool_frame) {
  if (count < kBlock) return jacobian_blocks<S, kSmallBlock, false>(chain, q, out, count, rows, in_tool_frame);
  jacobian_blocks<S, kBlock, Staged>(chain, q, out, count, rows, in_tool_frame);
}

}  // namespace spotkin::chain_lanes
