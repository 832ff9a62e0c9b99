// Fixed-base chain dynamics over a range of samples, L lanes at a time: load a
// block of rows into lanes, compute the block's poses once, run the algorithm,
// store. A sample with a NaN or an Inf in any of its inputs gets NaN in its
// whole output row. Inputs are Rows (stride 0 broadcasts one row to every sample);
// a null qd / qdd is zero (G = RNEA(q, 0, 0), h = RNEA(q, qd, 0)).
#pragma once

#include "spotkin/dynamics/aba.hpp"
#include "spotkin/dynamics/coriolis.hpp"
#include "spotkin/dynamics/crba.hpp"
#include "spotkin/dynamics/rnea.hpp"
#include "spotkin/scratch.hpp"

namespace spotkin::dynamics {

template <typename M, int L>
struct ChainBlock {
  using P = Pack<M, L>;
  int n;
  ScratchStack& stack;  // the thread's, looked up once (each lookup calls the TLS resolver)
  ScratchArray<P> q, qd, qdd, out;
  ScratchArray<Pose<P>> X;
  P g[3];
  bool ok[L];

  // q is loaded whole (every lane) and X written whole by begin() before either is read, so neither
  // is zeroed first (for one sample, the zeroing was a tenth of a gravity call); qd and qdd are
  // zero where no rows are given, and not kept at all without `rates`; `out` is zeroed only with
  // `zero_out` (the CRBA's writer clears its own).
  explicit ChainBlock(int dof, int out_width, bool rates = true, bool zero_out = true)
      : n(dof),
        stack(ScratchStack::local()),
        q(stack, dof, uninitialized),
        qd(stack, rates ? dof : 0, P(M(0))),
        qdd(stack, rates ? dof : 0, P(M(0))),
        out(stack, out_width, ZeroIf{zero_out}),
        X(stack, dof, uninitialized) {}

  // Loads q (poses computed), optional qd, qdd (or tau) and gravity.
  SPOTKIN_INLINE void begin(const ChainModel<M, L>& model, const Rows<M>& q_rows, const Rows<M>* qd_rows,
                            const Rows<M>* qdd_rows, const Rows<M>* g_rows, std::ptrdiff_t b0, int m,
                            bool poses = true) noexcept {
    for (int i = 0; i < L; ++i) ok[i] = true;
    load(q_rows, b0, m, n, q.data(), ok);
    if (qd_rows) load(*qd_rows, b0, m, n, qd.data(), ok);
    if (qdd_rows) load(*qdd_rows, b0, m, n, qdd.data(), ok);
    if (g_rows) load(*g_rows, b0, m, 3, g, ok);
    if (poses) model.poses(q.data(), X.data());
  }
  SPOTKIN_INLINE Motion<P> root_acceleration() const noexcept {  // a_0 = -g (RBDA section 5.3)
    return {zero3<P>(), {{-g[0], -g[1], -g[2]}}};
  }
};

// tau = RNEA(q, qd, qdd, g); qd_rows / qdd_rows null for zeros.
template <typename M, int L>
SPOTKIN_INLINE void rnea_batch(const ChainModel<M, L>& model, Rows<M> q, const Rows<M>* qd, const Rows<M>* qdd,
                               Rows<M> g, M* tau, std::ptrdiff_t begin, std::ptrdiff_t end, bool stream) {
  using P = Pack<M, L>;
  const int n = model.dof();
  ChainBlock<M, L> blk(n, n);
  ScratchArray<Force<P>> f(blk.stack, static_cast<std::size_t>(n),
                           uninitialized);  // written before read
  for (std::ptrdiff_t b0 = begin; b0 < end; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, end - b0));
    blk.begin(model, q, qd, qdd, &g, b0, m);
    if (qd || qdd)
      rnea_chain(model, blk.X.data(), blk.qd.data(), blk.qdd.data(), zero_motion<P>(),
                 blk.root_acceleration(), blk.out.data(), f.data());
    else  // G(q)
      gravity_chain(model, blk.X.data(), blk.root_acceleration().v, blk.out.data(), f.data());
    store(blk.out.data(), n, b0, m, blk.ok, tau, stream);
  }
  if (stream) stream_fence();
}

// A(q) per sample, in layout (SymmetricLayout): the lower triangle in a packed lane buffer
// (SymmetricWriter), gathered into the layout as the rows are stored.
template <typename M, int L>
SPOTKIN_INLINE void crba_batch(const ChainModel<M, L>& model, Rows<M> q, M* A, std::ptrdiff_t begin,
                               std::ptrdiff_t end, bool stream, SymmetricLayout layout = SymmetricLayout::Full) {
  using P = Pack<M, L>;
  const int n = model.dof(), width = symmetric_width(n, layout);
  // no rate rows; put.clear() zeroes the output
  ChainBlock<M, L> blk(n, SymmetricWriter<P>::size(n), false, false);
  // each written whole before it is read (crba_chain sets Ic from the bodies, joint_trig the rest)
  ScratchArray<SymInertia<P>> Ic(blk.stack, static_cast<std::size_t>(n), uninitialized);
  ScratchArray<P> trig(blk.stack, 2 * static_cast<std::size_t>(n),
                       uninitialized);  // sines, cosines
  ScratchArray<M> scratch(blk.stack, 3 * static_cast<std::size_t>(n * L), uninitialized);
  ScratchArray<int> gather(blk.stack, static_cast<std::size_t>(n * n), uninitialized);
  const int* index = symmetric_gather(n, layout, gather.data());
  P *sines = trig.data(), *cosines = sines + n;
  const SymmetricWriter<P> put{blk.out.data(), n};
  put.clear();
  for (std::ptrdiff_t b0 = begin; b0 < end; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, end - b0));
    blk.begin(model, q, nullptr, nullptr, nullptr, b0, m, false);
    model.joint_trig(blk.q.data(), scratch.data(), sines, cosines);
    crba_chain(model, blk.q.data(), sines, cosines, Ic.data(), put, [](int, const Force<P>&) SPOTKIN_LAMBDA_INLINE {},
               static_cast<SymInertia<P>*>(nullptr));
    store_symmetric(blk.out.data(), width, b0, m, blk.ok, A, stream, index);
  }
  if (stream) stream_fence();
}

// C(q, qd), row-major n x n per sample.
template <typename M, int L>
SPOTKIN_INLINE void coriolis_batch(const ChainModel<M, L>& model, Rows<M> q, Rows<M> qd, M* C,
                                   std::ptrdiff_t begin, std::ptrdiff_t end, bool stream) {
  using P = Pack<M, L>;
  const int n = model.dof();
  ChainBlock<M, L> blk(n, n * n);
  ScratchArray<CoriolisWork<P>> w(static_cast<std::size_t>(n));
  for (std::ptrdiff_t b0 = begin; b0 < end; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, end - b0));
    blk.begin(model, q, &qd, nullptr, nullptr, b0, m);
    coriolis_chain(model, blk.X.data(), blk.qd.data(), blk.out.data(), w.data());
    store(blk.out.data(), n * n, b0, m, blk.ok, C, stream);
  }
  if (stream) stream_fence();
}

// qdd = ABA(q, qd, tau, g).
template <typename M, int L>
SPOTKIN_INLINE void aba_batch(const ChainModel<M, L>& model, Rows<M> q, Rows<M> qd, Rows<M> tau, Rows<M> g,
                              M* qdd, std::ptrdiff_t begin, std::ptrdiff_t end, bool stream) {
  using P = Pack<M, L>;
  const int n = model.dof();
  ChainBlock<M, L> blk(n, n);
  ScratchArray<AbaWork<P>> w(static_cast<std::size_t>(n));
  for (std::ptrdiff_t b0 = begin; b0 < end; b0 += L) {
    const int m = static_cast<int>(std::min<std::ptrdiff_t>(L, end - b0));
    blk.begin(model, q, &qd, &tau, &g, b0, m);  // tau in the qdd slot
    aba_down_up(model, blk.X.data(), blk.qd.data(), blk.qdd.data(), zero_motion<P>(), w.data(), false,
                static_cast<Inertia6<P>*>(nullptr), static_cast<Force<P>*>(nullptr));
    aba_down(model, blk.X.data(), w.data(), blk.root_acceleration(), blk.out.data());
    store(blk.out.data(), n, b0, m, blk.ok, qdd, stream);
  }
  if (stream) stream_fence();
}

}  // namespace spotkin::dynamics
