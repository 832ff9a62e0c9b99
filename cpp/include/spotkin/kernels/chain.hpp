// A chain's batch kernels (FK, every frame, Jacobians), each dispatched to the clone of
// the active instruction-set level (SPOTKIN_CLONES, spotkin/isa.hpp). They are compiled
// in cpp/src/chain_kernels.cpp without fused multiply-adds, so that a sample's bits are
// the same in a block of 16 lanes and in the 4-lane blocks of small calls
// (spotkin/chain_lanes.hpp), and apart from the bindings.
#pragma once

#include <cstddef>

#include "spotkin/chain.hpp"

namespace spotkin::kernels {

// q (n, dof) -> the tool's poses (n, 4, 4).
void chain_fk(const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n);
void chain_fk(const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n);

// q (n, dof) -> every frame, base to tool (n, dof + 2, 4, 4).
void chain_frames(const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n);
void chain_frames(const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n);

// q (n, dof) -> the tool's Jacobians (n, rows, dof), in the base or the tool frame.
void chain_jacobian(const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n, int rows,
                    bool in_tool_frame);
void chain_jacobian(const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n, int rows,
                    bool in_tool_frame);

// q (n, dof) -> the Jacobians of a point fixed to frame `point`, in frame `frame`
// (spotkin/point_jacobian.hpp): (n, rows, dof).
void chain_point_jacobian(const Chain<double>& c, const double* q, double* out, std::ptrdiff_t n, int rows,
                          int point, int frame);
void chain_point_jacobian(const Chain<float>& c, const float* q, float* out, std::ptrdiff_t n, int rows,
                          int point, int frame);

}  // namespace spotkin::kernels
