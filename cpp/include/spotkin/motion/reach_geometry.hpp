// The plain geometry of the reach search (cpp/src/reach.cpp): poses, small linear solves, the
// capsules' distances and rotation vectors (python/spotkin/reference/reach_geometry.py). Matrices
// are row-major.
#pragma once

#include <cmath>

namespace spotkin::motion::geometry {

constexpr double kPi = 3.14159265358979323846;

// (x + pi) mod 2 pi - pi, in [-pi, pi): Python's modulo without fmod (exact enough for the
// residual).
inline double wrap_angle(double x) noexcept {
  const double y = x + kPi;
  return y - 2.0 * kPi * std::floor(y * (0.5 / kPi)) - kPi;
}

// C = A B, 4 x 4.
inline void mul4(const double* A, const double* B, double* C) noexcept {
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c)
      C[4 * r + c] = A[4 * r] * B[c] + A[4 * r + 1] * B[4 + c] + A[4 * r + 2] * B[8 + c] +
                     A[4 * r + 3] * B[12 + c];
}

// The pose [t, a, b, c] of T, with R = Rx(a) Ry(b) Rz(c) (ref.pose_of).
void pose_of(const double* T, double* pose) noexcept;

// Solves the n x n symmetric positive definite A x = b in place of b, `columns` right-hand sides
// (Cholesky, A overwritten); false if A is not positive definite.
bool cholesky_solve(double* A, int n, double* b, int columns = 1) noexcept;

// Solves the n x n A x = b in place of b (Gaussian elimination with partial pivoting, `columns`
// right-hand sides, A overwritten); false when A is singular.
bool lu_solve(double* A, int n, double* b, int columns) noexcept;

// The distance between the segments a-b and c-d (ref.segment_distance).
double segment_distance(const double* a, const double* b, const double* c,
                        const double* d) noexcept;

// The distance from the segment a-b to the box (centre, half-lengths), in the box's axes
// (ref.segment_box_distance).
double segment_box_distance(const double* a, const double* b, const double* centre,
                            const double* half) noexcept;

// The rotation vector of R (3 x 3) (ref.rotation_log).
void rotation_log(const double* R, double* out) noexcept;

}  // namespace spotkin::motion::geometry
