// A floating body (free-flyer, 6 DoF) carrying serial chains (legs, arms), each
// mounted at a fixed placement on the body (the chain's base).
//
// Coordinates, as Pinocchio's free-flyer (JointModelFreeFlyer):
//   q = [x, y, z, qx, qy, qz, qw, joints of chain 0, chain 1, ...]   body pose in the world
//   v = [v_body, w_body, joint rates]   the body's linear and angular velocity in the body frame
//   a = dv/dt, tau = [force, moment on the body in the body frame, joint torques].
// Gravity g is a world vector; the body sees g_b = R^T g. The quaternion need
// not be unit: R is the rotation of q / |q|.
#pragma once

#include <vector>

#include "spotkin/dynamics/aba.hpp"
#include "spotkin/dynamics/coriolis.hpp"
#include "spotkin/dynamics/crba.hpp"
#include "spotkin/dynamics/rnea.hpp"
#include "spotkin/scratch.hpp"

namespace spotkin::dynamics {

template <typename M, int L>
class FloatingModel {
 public:
  using P = Pack<M, L>;
  FloatingModel() = default;
  FloatingModel(const LinkInertial& body, std::vector<ChainModel<M, L>> chains) : chains_(std::move(chains)) {
    body.check("body");
    double m, h[3], J[3][3];
    body.about_origin(m, h, J);
    body_.m = M(m);
    for (int r = 0; r < 3; ++r) {
      body_.h[r] = M(h[r]);
      for (int c = 0; c < 3; ++c) body_.J[r][c] = M(J[r][c]);
    }
    for (const auto& c : chains_) {
      offsets_.push_back(joints_);
      joints_ += c.dof();
    }
  }
  int joints() const noexcept { return joints_; }
  int nq() const noexcept { return 7 + joints_; }
  int nv() const noexcept { return 6 + joints_; }
  const std::vector<ChainModel<M, L>>& chains() const noexcept { return chains_; }
  int offset(std::size_t k) const noexcept { return offsets_[k]; }
  SPOTKIN_INLINE RigidInertia<P> body_inertia() const noexcept {
    RigidInertia<P> I;
    I.m = P(body_.m);
    for (int r = 0; r < 3; ++r) {
      I.h[r] = P(body_.h[r]);
      for (int c = 0; c < 3; ++c) I.J(r, c) = P(body_.J[r][c]);
    }
    return I;
  }

 private:
  BodyConstants<M> body_;
  std::vector<ChainModel<M, L>> chains_;
  std::vector<int> offsets_;
  int joints_ = 0;
};

// One block's configuration: the body's rotation, every chain's poses, the
// velocity (and acceleration or torque) rows, gravity in the body frame.
template <typename M, int L>
struct FloatingBlock {
  using P = Pack<M, L>;
  ScratchStack& stack;  // the thread's, looked up once (each lookup calls the TLS resolver)
  ScratchArray<P> q, v, a, out;
  ScratchArray<Pose<P>> X;
  M3<P> R;
  V3<P> g_body;
  P g[3];
  bool ok[L];

  // q is loaded whole (every lane) and X written whole by begin() before either is read; v and a
  // are zero where no rows are given, and not kept at all without `rates` (the centre of mass and
  // the CRBA read neither).
  FloatingBlock(const FloatingModel<M, L>& model, int out_width, bool rates = true)
      : stack(ScratchStack::local()),
        q(stack, static_cast<std::size_t>(model.nq()), uninitialized),
        v(stack, rates ? static_cast<std::size_t>(model.nv()) : 0, P(M(0))),
        a(stack, rates ? static_cast<std::size_t>(model.nv()) : 0, P(M(0))),
        out(stack, static_cast<std::size_t>(out_width)),
        X(stack, static_cast<std::size_t>(model.joints()), uninitialized) {}

  SPOTKIN_INLINE void begin(const FloatingModel<M, L>& model, const Rows<M>& q_rows, const Rows<M>* v_rows,
                            const Rows<M>* a_rows, const Rows<M>* g_rows, std::ptrdiff_t b0, int m,
                            bool kinematics = true) noexcept {
    for (int i = 0; i < L; ++i) ok[i] = true;
    load(q_rows, b0, m, model.nq(), q.data(), ok);
    if (v_rows) load(*v_rows, b0, m, model.nv(), v.data(), ok);
    if (a_rows) load(*a_rows, b0, m, model.nv(), a.data(), ok);
    if (g_rows) load(*g_rows, b0, m, 3, g, ok);
    if (!kinematics) return;  // the inputs only (the CRBA walks its chains itself)
    // R of the quaternion (x, y, z, w) / |q|: s = 2 / |q|^2.
    const P x = q[3], y = q[4], z = q[5], w = q[6];
    const P s = P(M(2)) / (x * x + y * y + z * z + w * w);
    R(0, 0) = P(M(1)) - s * (y * y + z * z), R(0, 1) = s * (x * y - z * w), R(0, 2) = s * (x * z + y * w);
    R(1, 0) = s * (x * y + z * w), R(1, 1) = P(M(1)) - s * (x * x + z * z), R(1, 2) = s * (y * z - x * w);
    R(2, 0) = s * (x * z - y * w), R(2, 1) = s * (y * z + x * w), R(2, 2) = P(M(1)) - s * (x * x + y * y);
    if (g_rows) g_body = mul_t(R, V3<P>{{g[0], g[1], g[2]}});
    for (std::size_t k = 0; k < model.chains().size(); ++k)
      model.chains()[k].poses(q.data() + 7 + model.offset(k), X.data() + model.offset(k));
  }
  // The body's velocity and (gravity-shifted, RBDA section 5.3) acceleration as spatial vectors.
  SPOTKIN_INLINE Motion<P> body_velocity() const noexcept { return {{{v[3], v[4], v[5]}}, {{v[0], v[1], v[2]}}}; }
  SPOTKIN_INLINE Motion<P> body_acceleration() const noexcept {
    return {{{a[3], a[4], a[5]}}, {{a[0] - g_body[0], a[1] - g_body[1], a[2] - g_body[2]}}};
  }
};

// tau = RNEA(q, v, a, g) (RBDA Table 5.1 with the body as the root, its
// acceleration given); null v / a rows are zero.
template <typename M, int L>
SPOTKIN_INLINE void floating_rnea_batch(const FloatingModel<M, L>& model, Rows<M> q, const Rows<M>* v,
                                        const Rows<M>* a, Rows<M> g, M* tau, std::ptrdiff_t begin,
                                        std::ptrdiff_t end, bool stream) {
  using P = Pack<M, L>;
  FloatingBlock<M, L> blk(model, model.nv());
  // written before read
  ScratchArray<Force<P>> f(blk.stack, static_cast<std::size_t>(model.joints()), uninitialized);
  for (std::ptrdiff_t b0 = begin; b0 < end; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, end - b0));
    blk.begin(model, q, v, a, &g, b0, m);
    const Motion<P> vb = blk.body_velocity(), ab = blk.body_acceleration();
    const RigidInertia<P> I = model.body_inertia();
    Force<P> fb = apply(I, ab);
    if (v) {
      const Force<P> fv = crf(vb, apply(I, vb));
      fb.n += fv.n, fb.f += fv.f;
    }
    for (std::size_t k = 0; k < model.chains().size(); ++k) {
      const int o = model.offset(k);
      const Force<P> fk =
          v || a ? rnea_chain(model.chains()[k], blk.X.data() + o, blk.v.data() + 6 + o,
                              blk.a.data() + 6 + o, vb, ab, blk.out.data() + 6 + o, f.data() + o)
                 : gravity_chain(model.chains()[k], blk.X.data() + o, ab.v, blk.out.data() + 6 + o,
                                 f.data() + o);  // G(q): at rest
      fb.n += fk.n, fb.f += fk.f;
    }
    for (int r = 0; r < 3; ++r) blk.out[r] = fb.f[r], blk.out[3 + r] = fb.n[r];
    store(blk.out.data(), model.nv(), b0, m, blk.ok, tau, stream);
  }
  if (stream) stream_fence();
}

// A(q), (6 + n) x (6 + n) in layout (SymmetricLayout): the chains' blocks by CRBA (RBDA Table 6.2,
// crba_chain), their columns' forces and composite inertias carried to the body. Only the lower
// entries are written per block; the blocks between chains stay zero.
template <typename M, int L>
SPOTKIN_INLINE void floating_crba_batch(const FloatingModel<M, L>& model, Rows<M> q, M* A, std::ptrdiff_t begin,
                                        std::ptrdiff_t end, bool stream, SymmetricLayout layout = SymmetricLayout::Full) {
  using P = Pack<M, L>;
  const int nv = model.nv(), width = symmetric_width(nv, layout);
  FloatingBlock<M, L> blk(model, SymmetricWriter<P>::size(nv), false);
  // each written whole before it is read (crba_chain sets Ic from the bodies, joint_trig the rest)
  ScratchArray<SymInertia<P>> Ic(blk.stack, static_cast<std::size_t>(model.joints()),
                                 uninitialized);
  ScratchArray<P> trig(blk.stack, 2 * static_cast<std::size_t>(model.joints()),
                       uninitialized);  // sines, cosines
  ScratchArray<M> scratch(blk.stack, 3 * static_cast<std::size_t>(model.joints() * L),
                          uninitialized);
  ScratchArray<int> gather(blk.stack, static_cast<std::size_t>(nv * nv), uninitialized);
  const int* index = symmetric_gather(nv, layout, gather.data());
  P *sines = trig.data(), *cosines = sines + model.joints();
  const SymmetricWriter<P> put{blk.out.data(), nv};
  put.clear();
  for (std::ptrdiff_t b0 = begin; b0 < end; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, end - b0));
    blk.begin(model, q, nullptr, nullptr, nullptr, b0, m, false);
    SymInertia<P> Ib = symmetric(model.body_inertia());
    for (std::size_t k = 0; k < model.chains().size(); ++k) {
      const auto& chain = model.chains()[k];
      const int o = model.offset(k);
      const P* qc = blk.q.data() + 7 + o;
      chain.joint_trig(qc, scratch.data(), sines, cosines);
      crba_chain(
          chain, qc, sines, cosines, Ic.data() + o, [&](int i, int j, const P& x) SPOTKIN_LAMBDA_INLINE { put(6 + o + i, 6 + o + j, x); },
          [&](int j, const Force<P>& F) SPOTKIN_LAMBDA_INLINE {  // the body's rows: force, then moment
            for (int r = 0; r < 3; ++r) put(6 + o + j, r, F.f[r]), put(6 + o + j, 3 + r, F.n[r]);
          },
          &Ib);
    }
    // the body block, linear first: [[m 1, -[h]x], [[h]x, J]]
    const V3<P>& h = Ib.h;
    for (int r = 0; r < 3; ++r) put(r, r, Ib.m);
    put(3, 3, Ib.J[0]), put(4, 4, Ib.J[1]), put(5, 5, Ib.J[2]);
    put(4, 3, Ib.J[3]), put(5, 3, Ib.J[4]), put(5, 4, Ib.J[5]);
    put(3, 1, -h[2]), put(3, 2, h[1]), put(4, 0, h[2]), put(4, 2, -h[0]), put(5, 0, -h[1]), put(5, 1, h[0]);
    store_symmetric(blk.out.data(), width, b0, m, blk.ok, A, stream, index);
  }
  if (stream) stream_fence();
}

// Solves the symmetric positive definite 6x6 system K x = b in place (LDL^T, no pivoting).
template <typename P>
SPOTKIN_INLINE void solve_spd6(P K[6][6], P b[6]) noexcept {
  P d[6];
  for (int j = 0; j < 6; ++j) {
    P dj = K[j][j];
    for (int k = 0; k < j; ++k) dj -= K[j][k] * K[j][k] * d[k];
    d[j] = dj;
    for (int i = j + 1; i < 6; ++i) {
      P x = K[i][j];
      for (int k = 0; k < j; ++k) x -= K[i][k] * K[j][k] * d[k];
      K[i][j] = x / dj;
    }
  }
  for (int i = 0; i < 6; ++i)
    for (int k = 0; k < i; ++k) b[i] -= K[i][k] * b[k];
  for (int i = 0; i < 6; ++i) b[i] = b[i] / d[i];
  for (int i = 5; i >= 0; --i)
    for (int k = i + 1; k < 6; ++k) b[i] -= K[k][i] * b[k];
}

// a = ABA(q, v, tau, g): the chains' articulated inertias gathered at the body,
// IA_b a~_b = tau_b - pA_b solved, then the chains' joint accelerations (RBDA
// Table 7.1 with the floating-base step of section 9.3).
template <typename M, int L>
SPOTKIN_INLINE void floating_aba_batch(const FloatingModel<M, L>& model, Rows<M> q, Rows<M> v, Rows<M> tau,
                                       Rows<M> g, M* a, std::ptrdiff_t begin, std::ptrdiff_t end, bool stream) {
  using P = Pack<M, L>;
  FloatingBlock<M, L> blk(model, model.nv());
  ScratchArray<AbaWork<P>> w(static_cast<std::size_t>(model.joints()));
  for (std::ptrdiff_t b0 = begin; b0 < end; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, end - b0));
    blk.begin(model, q, &v, &tau, &g, b0, m);  // tau in the a slot
    const Motion<P> vb = blk.body_velocity();
    const RigidInertia<P> I = model.body_inertia();
    Inertia6<P> IA = general(I);
    Force<P> pA = crf(vb, apply(I, vb));
    for (std::size_t k = 0; k < model.chains().size(); ++k) {
      const int o = model.offset(k);
      Inertia6<P> IAk = general(model.chains()[k].inertia(0));  // overwritten by the chain's pass
      Force<P> pAk = zero_force<P>();
      aba_down_up(model.chains()[k], blk.X.data() + o, blk.v.data() + 6 + o, blk.a.data() + 6 + o, vb,
                  w.data() + o, true, &IAk, &pAk);
      add_to(IA, IAk);
      pA.n += pAk.n, pA.f += pAk.f;
    }
    P K[6][6], x[6];  // (w, v) order
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        K[r][c] = IA.A(r, c), K[r][3 + c] = IA.B(r, c);
        K[3 + r][c] = IA.B(c, r), K[3 + r][3 + c] = IA.C(r, c);
      }
    for (int r = 0; r < 3; ++r) x[r] = blk.a[3 + r] - pA.n[r], x[3 + r] = blk.a[r] - pA.f[r];
    solve_spd6(K, x);
    const Motion<P> ab{{{x[0], x[1], x[2]}}, {{x[3], x[4], x[5]}}};  // includes -g_b (RBDA section 5.3)
    for (std::size_t k = 0; k < model.chains().size(); ++k) {
      const int o = model.offset(k);
      aba_down(model.chains()[k], blk.X.data() + o, w.data() + o, ab, blk.out.data() + 6 + o);
    }
    for (int r = 0; r < 3; ++r) blk.out[r] = ab.v[r] + blk.g_body[r], blk.out[3 + r] = ab.w[r];
    store(blk.out.data(), model.nv(), b0, m, blk.ok, a, stream);
  }
  if (stream) stream_fence();
}

// Centre of mass in the world (3) and its Jacobian (3 x (6 + n)), d com / dt = J v:
// body columns [R, -R [c_b]x], joint j's column R (m_sub v_j + w_j x h_sub) / m_total
// with (w_j, v_j) joint j's motion in the body frame and (m_sub, h_sub) the mass and
// first moment (body frame) of everything it moves. out: com then J, row-major.
template <typename M, int L>
SPOTKIN_INLINE void floating_com_batch(const FloatingModel<M, L>& model, Rows<M> q, M* out_rows, bool jacobian,
                                       std::ptrdiff_t begin, std::ptrdiff_t end, bool stream) {
  using P = Pack<M, L>;
  const int nv = model.nv(), width = jacobian ? 3 * nv : 3;
  FloatingBlock<M, L> blk(model, width, false);
  // each written before it is read (S only with the Jacobian)
  ScratchArray<Motion<P>> S(blk.stack, jacobian ? static_cast<std::size_t>(model.joints()) : 0,
                            uninitialized);
  ScratchArray<P> ms(blk.stack, static_cast<std::size_t>(model.joints()), uninitialized);
  ScratchArray<V3<P>> hs(blk.stack, static_cast<std::size_t>(model.joints()), uninitialized);
  for (std::ptrdiff_t b0 = begin; b0 < end; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, end - b0));
    blk.begin(model, q, nullptr, nullptr, nullptr, b0, m);
    const RigidInertia<P> Ib = model.body_inertia();
    P mass = Ib.m;
    V3<P> h = Ib.h;
    for (std::size_t k = 0; k < model.chains().size(); ++k) {
      const auto& chain = model.chains()[k];
      const int o = model.offset(k), n = chain.dof();
      Pose<P> T = blk.X[static_cast<std::size_t>(o)];
      for (int j = 0; j < n; ++j) {
        if (j > 0) T = compose(T, blk.X[static_cast<std::size_t>(o + j)]);
        if (jacobian) S[o + j] = to_parent(T, chain.subspace(j));  // the centre alone needs no motions
        const RigidInertia<P> I = chain.inertia(j);
        ms[o + j] = I.m;
        hs[o + j] = mul(T.R, I.h) + scale(T.p, I.m);
      }
      for (int j = n - 1; j > 0; --j) ms[o + j - 1] += ms[o + j], hs[o + j - 1] += hs[o + j];
      if (n > 0) mass += ms[o], h += hs[o];
    }
    const P inv = P(M(1)) / mass;
    const V3<P> cb = scale(h, inv);
    const V3<P> com = mul(blk.R, cb);
    P* out = blk.out.data();
    if (!jacobian) {
      for (int r = 0; r < 3; ++r) out[r] = blk.q[r] + com[r];
    } else {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) {
          out[r * nv + c] = blk.R(r, c);
          out[r * nv + 3 + c] = blk.R(r, (c + 2) % 3) * cb[(c + 1) % 3] - blk.R(r, (c + 1) % 3) * cb[(c + 2) % 3];
        }
      for (int j = 0; j < model.joints(); ++j) {
        const V3<P> col = mul(blk.R, scale(scale(S[j].v, ms[j]) + cross(S[j].w, hs[j]), inv));
        for (int r = 0; r < 3; ++r) out[r * nv + 6 + j] = col[r];
      }
    }
    store(out, width, b0, m, blk.ok, out_rows, stream);
  }
  if (stream) stream_fence();
}

// C(q, v), (6 + n) x (6 + n), for which dA/dt - 2C is skew-symmetric (coriolis.hpp), in world
// coordinates: the body's columns are its unit twists (linear, then angular, body frame) seen
// from the world, their rates v_body x J; the root's subtree is the whole robot, and bodies of
// different chains share no subtree (their block is 0).
template <typename M, int L>
SPOTKIN_INLINE void floating_coriolis_batch(const FloatingModel<M, L>& model, Rows<M> q, Rows<M> v, M* C,
                                            std::ptrdiff_t begin, std::ptrdiff_t end, bool stream) {
  using P = Pack<M, L>;
  const int nv = model.nv();
  FloatingBlock<M, L> blk(model, nv * nv);
  ScratchArray<CoriolisWork<P>> w(static_cast<std::size_t>(model.joints()));
  for (std::ptrdiff_t b0 = begin; b0 < end; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, end - b0));
    blk.begin(model, q, &v, nullptr, nullptr, b0, m);
    P* out = blk.out.data();
    for (int k = 0; k < nv * nv; ++k) out[k] = P(M(0));
    const Pose<P> Tb{blk.R, {{blk.q[0], blk.q[1], blk.q[2]}}};
    const Motion<P> vb = to_parent(Tb, blk.body_velocity());
    Motion<P> Sb[6], dSb[6];
    for (int i = 0; i < 3; ++i) {
      const V3<P> col{{blk.R(0, i), blk.R(1, i), blk.R(2, i)}};
      Sb[i] = {zero3<P>(), col};              // linear
      Sb[3 + i] = {col, cross(Tb.p, col)};   // angular, about the body's origin
    }
    for (int i = 0; i < 6; ++i) dSb[i] = crm(vb, Sb[i]);
    CoriolisWork<P> root;
    root.Ic = to_parent(Tb, model.body_inertia());
    coriolis_terms(root.Ic, vb, root.B11, root.f0);
    for (std::size_t k = 0; k < model.chains().size(); ++k) {
      const auto& chain = model.chains()[k];
      const int o = model.offset(k), n = chain.dof();
      coriolis_chain(chain, blk.X.data() + o, blk.v.data() + 6 + o, out + (6 + o) * nv + 6 + o, w.data() + o, nv,
                     &Tb, &vb);
      add_to(root.Ic, w[o].Ic);
      add_to(root.B11, w[o].B11);
      root.f0 += w[o].f0;
      for (int a = 0; a < n; ++a) {
        const CoriolisRow<P> row = coriolis_row(w[o + a]);
        const Force<P> y = coriolis_column(w[o + a]);
        for (int b = 0; b < 6; ++b) {
          out[(6 + o + a) * nv + b] = row(Sb[b], dSb[b]);
          out[b * nv + 6 + o + a] = dot(Sb[b], y);
        }
      }
    }
    for (int b = 0; b < 6; ++b) {
      root.S = Sb[b], root.dS = dSb[b];
      const Force<P> y = coriolis_column(root);
      for (int a = 0; a < 6; ++a) out[a * nv + b] = dot(Sb[a], y);
    }
    store(out, nv * nv, b0, m, blk.ok, C, stream);
  }
  if (stream) stream_fence();
}

}  // namespace spotkin::dynamics
