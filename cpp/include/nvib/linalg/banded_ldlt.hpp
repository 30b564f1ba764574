// LDL^T without pivoting of a symmetric band matrix: the iteration matrix of a chain, a shear
// building or a beam (half-bandwidth b, every entry within b of the diagonal). n b^2 / 2 flops to
// factorise and 2 n b to solve, in place on the band stored row by row, the loops over a row's
// band unrolled for b <= 3 (a shear building is b = 1: the Thomas algorithm, with no division on
// the substitutions' critical paths). A general sparse factorisation spends its time on indices and
// a dense LU with pivoting on n^2 entries (on the six-storey building, 3 to 5 times the
// instructions: callgrind).
//
// The pattern of S comes once, as compressed columns (analyze()); its values come in the band's own
// layout (size() values: row i's entries A(i, i - b) .. A(i, i) at i (b + 1) + 0 .. b), which the
// caller assembles into directly through layout(). No pivoting: S = c_M M + c_C C + c_K K is dominated by its mass term at the steps the implicit schemes take; a pivot that is not
// finite or below 1e-14 of the largest (the dense LU's test) makes factorize() return false and the
// caller fall back to an LU with pivoting.
// Allocates only in analyze().
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "../base/types.hpp"

namespace nvib {

class BandedLDLT {
 public:
  // The half-bandwidth of A's pattern: max |i - j| over its stored entries.
  static Index half_bandwidth(const SparseMatrix& A) {
    Index b = 0;
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) b = std::max<Index>(b, std::abs(Index(it.row()) - j));
    return b;
  }

  // The pattern of every matrix to come (symmetric; A's stored entries, both triangles).
  void analyze(const SparseMatrix& A) {
    n_ = A.rows();
    b_ = half_bandwidth(A);
    w_ = b_ + 1;
    band_.assign(static_cast<size_t>(n_ * w_), 0.0);
    d_.setZero(n_);
    inv_.assign(b_ == 1 ? static_cast<size_t>(n_) : 0, 0.0);
    place_.clear();
    place_.reserve(static_cast<size_t>(A.nonZeros()));
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it)
        place_.push_back(static_cast<int>(it.row() >= j ? at(it.row(), j) : at(j, it.row())));  // (i, j), i < j: (j, i)
  }
  Index half_bandwidth() const { return b_; }
  // Values in the band's layout.
  Index size() const { return n_ * w_; }
  // Where the k-th stored value of analyze()'s A goes in the band's layout: its lower triangle only
  // (-1 for an entry above the diagonal, whose twin below is the one read).
  std::vector<int> layout(const SparseMatrix& A) const {
    std::vector<int> to(place_);
    size_t k = 0;
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it, ++k)
        if (it.row() < j) to[k] = -1;
    return to;
  }
  // A's values (analyze()'s pattern, both triangles) from a matrix in the band's layout.
  void to_compressed(const double* values, SparseMatrix& A) const {
    double* a = A.valuePtr();
    for (size_t k = 0; k < place_.size(); ++k) a[k] = values[place_[k]];
  }

  // Factorises the matrix given in the band's layout (size() values); false if a pivot is zero, not
  // finite or below 1e-14 of the largest.
  bool factorize(const double* values) {
    switch (b_) {
      case 0: factor<0>(values); break;
      case 1: return tridiagonal(values);
      case 2: factor<2>(values); break;
      case 3: factor<3>(values); break;
      default: factor<-1>(values);
    }
    double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
    bool finite = true;
    const double* D = d_.data();
    for (Index i = 0; i < n_; ++i) {
      const double p = std::abs(D[i]);
      finite &= p <= std::numeric_limits<double>::max();  // (false for NaN and infinity)
      lo = std::min(lo, p);
      hi = std::max(hi, p);
    }
    return n_ > 0 && pivots_ok(finite, lo, hi);
  }

  // x <- A^{-1} x
  void solve_in_place(double* x) const {
    switch (b_) {
      case 0: substitute<0>(x); return;
      case 1: substitute<1>(x); return;
      case 2: substitute<2>(x); return;
      case 3: substitute<3>(x); return;
      default: substitute<-1>(x);
    }
  }

  // D, by row.
  const Vector& pivots() const { return d_; }

 private:
  // b = 1, the Thomas algorithm: the recurrence D(i) = A(i, i) - A(i, i-1)^2 / D(i-1) is the
  // factorisation's critical path (one division and one subtraction a row); 1 / D(i-1) and
  // l_i = A(i, i-1) / D(i-1) are off it (a second division, then a product: two divisions a row keep the
  // divider from setting the pace), kept for the substitutions, which then carry no division. The
  // pivots are tested (factorize()'s test) as they come, in the same loop.
  bool tridiagonal(const double* __restrict a) {
    const Index n = n_;
    if (n == 0) return false;
    double* __restrict L = band_.data();
    double* __restrict D = d_.data();
    double* __restrict inv = inv_.data();
    constexpr double big = std::numeric_limits<double>::max();
    double dprev = D[0] = a[1];
    double lo = std::abs(dprev), hi = lo;
    bool finite = lo <= big;  // (false for NaN and infinity)
    for (Index i = 1; i < n; ++i) {
      const double s = a[2 * i], r = 1.0 / dprev, l = s * r;
      inv[i - 1] = r;
      L[2 * i] = l;
      dprev = D[i] = a[2 * i + 1] - (s * s) / dprev;
      const double p = std::abs(dprev);
      finite &= p <= big;
      lo = std::min(lo, p);
      hi = std::max(hi, p);
    }
    inv[n - 1] = 1.0 / dprev;
    return pivots_ok(finite, lo, hi);
  }
  // The pivots' test, from their magnitudes' smallest and largest: every one finite, none below 1e-14 of
  // the largest.
  static bool pivots_ok(bool finite, double lo, double hi) { return finite && lo > 1e-14 * hi; }

  // Row i's entry in column j (i - b <= j <= i): L(i, j) below the diagonal once factorised.
  Index at(Index i, Index j) const { return i * w_ + (j - i + b_); }

  // Row by row (Cholesky's up-looking order): for j < i, t_j = A(i, j) - sum_{k < j} t_k L(j, k) with
  // t_k = L(i, k) D(k); L(i, j) = t_j / D(j); D(i) = A(i, i) - sum_k t_k L(i, k). B: b known at compile
  // time (B < 0: b_ at run time). The values are read from `a` (the band's layout) as the rows go.
  template <int B>
  void factor(const double* __restrict a) {
    const Index n = n_, b = B >= 0 ? B : b_, w = b + 1;
    double* __restrict L = band_.data();
    double* __restrict D = d_.data();
    if constexpr (B == 0) {
      for (Index i = 0; i < n; ++i) D[i] = L[i] = a[i];
    } else {
      double t[B > 0 ? B : 1];  // t_k of row i for b <= 3 (the general path keeps them in the row itself)
      for (Index i = 0; i < n; ++i) {
        double* row = L + i * w;  // row[j - i + b] = A(i, j), then L(i, j)
        const double* in = a + i * w;
        const Index j0 = std::max<Index>(0, i - b);
        double di = in[b];
        if constexpr (B > 0) {
          for (Index j = j0; j < i; ++j) {
            const double* rj = L + j * w;  // rj[k - j + b] = L(j, k)
            double s = in[j - i + b];
            for (Index k = std::max<Index>(j0, j - b); k < j; ++k) s -= t[k - i + b] * rj[k - j + b];
            t[j - i + b] = s;
            const double l = s / D[j];
            row[j - i + b] = l;
            di -= s * l;
          }
        } else {
          // t_j is needed by the columns after j, L(i, j) only at the end: the row holds t, then is scaled to L.
          for (Index j = j0; j < i; ++j) {
            const double* rj = L + j * w;
            double s = in[j - i + b];
            for (Index k = std::max<Index>(j0, j - b); k < j; ++k) s -= row[k - i + b] * rj[k - j + b];
            row[j - i + b] = s;
          }
          for (Index j = j0; j < i; ++j) {
            const double s = row[j - i + b], l = s / D[j];
            row[j - i + b] = l;
            di -= s * l;
          }
        }
        D[i] = di;
        row[b] = di;
      }
      (void)t;
    }
  }

  template <int B>
  void substitute(double* __restrict x) const {
    const Index n = n_, b = B >= 0 ? B : b_, w = b + 1;
    const double* __restrict L = band_.data();
    const double* __restrict D = d_.data();
    if constexpr (B == 1) {  // L y = x, then L^T x = D^{-1} y: one multiplication and one subtraction a row each way
      const double* __restrict inv = inv_.data();
      for (Index i = 1; i < n; ++i) x[i] -= L[2 * i] * x[i - 1];
      x[n - 1] *= inv[n - 1];
      for (Index i = n - 2; i >= 0; --i) x[i] = x[i] * inv[i] - L[2 * i + 2] * x[i + 1];
      return;
    }
    for (Index i = 1; i < n; ++i) {  // L y = x
      const double* row = L + i * w;
      double s = x[i];
      for (Index j = std::max<Index>(0, i - b); j < i; ++j) s -= row[j - i + b] * x[j];
      x[i] = s;
    }
    for (Index i = 0; i < n; ++i) x[i] /= D[i];  // D z = y
    for (Index i = n - 2; i >= 0; --i) {  // L^T x = z
      double s = x[i];
      for (Index j = i + 1, e = std::min<Index>(n - 1, i + b); j <= e; ++j) s -= L[j * w + (i - j + b)] * x[j];
      x[i] = s;
    }
  }

  Index n_ = 0, b_ = 0, w_ = 1;
  std::vector<double> band_;  // row i at i (b + 1): L(i, i - b) ... L(i, i - 1), D(i)
  Vector d_;
  std::vector<double> inv_;  // b = 1: 1 / D(i), for the substitutions
  std::vector<int> place_;  // A's k-th stored value -> the index of (i, j) or its twin (j, i) below the diagonal in band_
};

}  // namespace nvib
