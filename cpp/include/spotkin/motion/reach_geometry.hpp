// The plain geometry of the reach search (cpp/src/reach.cpp): poses, small linear solves, the
// capsules' distances and rotation vectors (python/spotkin/reference/reach_geometry.py). Matrices
// are row-major.
#pragma once

#include <cmath>
#include <utility>

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
// (Cholesky, A overwritten); false if A is not positive definite. Sizes fixed: loops unrolled.
template <int n, int columns = 1>
inline bool cholesky_solve(double* __restrict A, double* __restrict b) noexcept {
  double inv[n];  // 1 / L_jj: one division per row
  for (int j = 0; j < n; ++j) {
    double d = A[n * j + j];
    for (int k = 0; k < j; ++k) d -= A[n * j + k] * A[n * j + k];
    if (!(d > 0.0)) return false;
    d = std::sqrt(d);
    A[n * j + j] = d, inv[j] = 1.0 / d;
    for (int i = j + 1; i < n; ++i) {
      double s = A[n * i + j];
      for (int k = 0; k < j; ++k) s -= A[n * i + k] * A[n * j + k];
      A[n * i + j] = s * inv[j];
    }
  }
  for (int i = 0; i < n; ++i) {  // L y = b, row by row over the columns
    for (int k = 0; k < i; ++k)
      for (int c = 0; c < columns; ++c) b[columns * i + c] -= A[n * i + k] * b[columns * k + c];
    for (int c = 0; c < columns; ++c) b[columns * i + c] *= inv[i];
  }
  for (int i = n - 1; i >= 0; --i) {  // L^T x = y
    for (int k = i + 1; k < n; ++k)
      for (int c = 0; c < columns; ++c) b[columns * i + c] -= A[n * k + i] * b[columns * k + c];
    for (int c = 0; c < columns; ++c) b[columns * i + c] *= inv[i];
  }
  return true;
}

// Solves the n x n A x = b in place of b (Gaussian elimination with partial pivoting, `columns`
// right-hand sides, A overwritten); false when A is singular. Sizes fixed: loops unrolled.
template <int n, int columns = 1>
inline bool lu_solve(double* __restrict A, double* __restrict b) noexcept {
  double inv[n];  // 1 / U_kk: one division per row
  for (int k = 0; k < n; ++k) {
    int pivot = k;
    for (int i = k + 1; i < n; ++i)
      if (std::abs(A[n * i + k]) > std::abs(A[n * pivot + k])) pivot = i;
    if (!(std::abs(A[n * pivot + k]) > 0.0)) return false;
    if (pivot != k) {
      for (int j = 0; j < n; ++j) std::swap(A[n * k + j], A[n * pivot + j]);
      for (int j = 0; j < columns; ++j) std::swap(b[columns * k + j], b[columns * pivot + j]);
    }
    inv[k] = 1.0 / A[n * k + k];
    for (int i = k + 1; i < n; ++i) {
      const double f = A[n * i + k] * inv[k];
      for (int j = k; j < n; ++j) A[n * i + j] -= f * A[n * k + j];
      for (int j = 0; j < columns; ++j) b[columns * i + j] -= f * b[columns * k + j];
    }
  }
  for (int i = n - 1; i >= 0; --i) {  // U x = y, row by row over the columns
    for (int k = i + 1; k < n; ++k)
      for (int j = 0; j < columns; ++j) b[columns * i + j] -= A[n * i + k] * b[columns * k + j];
    for (int j = 0; j < columns; ++j) b[columns * i + j] *= inv[i];
  }
  return true;
}

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
