// LU factorisation with partial pivoting for the iteration matrices of the
// implicit schemes: plain loops up to kUnblockedMax unknowns, Eigen's blocked
// PartialPivLU above. Eigen's blocked code is built for large matrices; on a
// 6x6 iteration matrix it spent about 1500 instructions per factorisation and
// 1200 per solve (callgrind, building scene), against a few hundred here.
// Allocates only in resize(); compute() and solve_in_place() allocate nothing.
#pragma once

#include <cmath>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/LU>

#include "../base/types.hpp"

namespace nvib {

class DenseLU {
 public:
  static constexpr Index kUnblockedMax = 64;

  DenseLU() = default;
  explicit DenseLU(Index n) { resize(n); }

  void resize(Index n) {
    n_ = n;
    if (n <= kUnblockedMax) {
      lu_.resize(n, n);
      perm_.assign(static_cast<size_t>(n), 0);
    } else {
      big_ = Eigen::PartialPivLU<Matrix>(n);
      work_big_.resize(n);
      work_mat_.resize(n, n);
    }
  }

  // Factorises A (n x n). False when a pivot is zero, not finite, or below
  // 1e-14 times the largest (the matrix is singular to working precision).
  bool compute(const Matrix& A) {
    if (n_ > kUnblockedMax) {
      big_.compute(A);
      const auto d = big_.matrixLU().diagonal().cwiseAbs();
      const double mx = d.maxCoeff();
      return ok_ = std::isfinite(mx) && mx > 0.0 && d.minCoeff() > 1e-14 * mx;
    }
    lu_ = A;
    return factorize_in_place();
  }

  // The storage to assemble the matrix in, then factorize_assembled(): no copy.
  Matrix& assembly() { return n_ > kUnblockedMax ? work_mat_ : lu_; }
  bool factorize_assembled() { return n_ > kUnblockedMax ? compute(work_mat_) : factorize_in_place(); }

 private:
  // The kernels, for a size known at compile time (N > 0: the loops unroll,
  // as in a hand-written solver of that size) or at run time (N = 0).
  template <int N>
  static bool factor(double* a, Index* perm, Index n_run) {
    const Index n = N > 0 ? N : n_run;  // column-major: a[i + j n] = A(i, j)
    double dmax = 0.0, dmin = std::numeric_limits<double>::infinity();
    for (Index k = 0; k < n; ++k) {
      // pivot: the largest |a(i, k)| for i >= k
      Index p = k;
      double best = std::abs(a[k + k * n]);
      for (Index i = k + 1; i < n; ++i) {
        const double v = std::abs(a[i + k * n]);
        if (v > best) {
          best = v;
          p = i;
        }
      }
      perm[k] = p;
      if (p != k)
        for (Index j = 0; j < n; ++j) std::swap(a[k + j * n], a[p + j * n]);
      const double pivot = a[k + k * n];
      if (!(best > 0.0) || !std::isfinite(best)) return false;
      dmax = std::max(dmax, best);
      dmin = std::min(dmin, best);
      const double inv = 1.0 / pivot;
      for (Index i = k + 1; i < n; ++i) a[i + k * n] *= inv;
      for (Index j = k + 1; j < n; ++j) {
        const double akj = a[k + j * n];
        if (akj == 0.0) continue;
        double* colj = a + j * n;
        const double* colk = a + k * n;
        for (Index i = k + 1; i < n; ++i) colj[i] -= colk[i] * akj;
      }
    }
    return dmin > 1e-14 * dmax;
  }

  template <int N>
  static void substitute(const double* a, const Index* perm, double* b, Index n_run) {
    const Index n = N > 0 ? N : n_run;
    for (Index k = 0; k < n; ++k) {
      const Index p = perm[k];
      if (p != k) std::swap(b[k], b[p]);
    }
    for (Index j = 0; j < n; ++j) {  // L y = P b, unit diagonal, by columns
      const double bj = b[j];
      if (bj == 0.0) continue;
      const double* col = a + j * n;
      for (Index i = j + 1; i < n; ++i) b[i] -= col[i] * bj;
    }
    for (Index j = n - 1; j >= 0; --j) {  // U x = y, by columns
      b[j] /= a[j + j * n];
      const double bj = b[j];
      const double* col = a + j * n;
      for (Index i = 0; i < j; ++i) b[i] -= col[i] * bj;
    }
  }

  // f(std::integral_constant<int, N>) with N = n for n <= 8, else N = 0.
  template <class F>
  decltype(auto) by_size(F&& f) const {
    switch (n_) {
      case 1: return f(std::integral_constant<int, 1>{});
      case 2: return f(std::integral_constant<int, 2>{});
      case 3: return f(std::integral_constant<int, 3>{});
      case 4: return f(std::integral_constant<int, 4>{});
      case 5: return f(std::integral_constant<int, 5>{});
      case 6: return f(std::integral_constant<int, 6>{});
      case 7: return f(std::integral_constant<int, 7>{});
      case 8: return f(std::integral_constant<int, 8>{});
      default: return f(std::integral_constant<int, 0>{});
    }
  }

  bool factorize_in_place() {
    double* a = lu_.data();
    Index* perm = perm_.data();
    return ok_ = by_size([&](auto N) { return factor<decltype(N)::value>(a, perm, n_); });
  }

 public:
  bool ok() const { return ok_; }

  // x <- A^{-1} x
  void solve_in_place(Vector& x) const {
    if (n_ > kUnblockedMax) {
      work_big_ = x;
      x.noalias() = big_.solve(work_big_);
      return;
    }
    const double* a = lu_.data();
    const Index* perm = perm_.data();
    double* b = x.data();
    by_size([&](auto N) { substitute<decltype(N)::value>(a, perm, b, n_); });
  }

 private:
  Index n_ = 0;
  bool ok_ = false;
  Matrix lu_;
  std::vector<Index> perm_;
  Eigen::PartialPivLU<Matrix> big_;
  mutable Vector work_big_;
  Matrix work_mat_;  // the assembly storage above kUnblockedMax
};

}  // namespace nvib
