// Factorising and solving a sparse matrix whose pattern is fixed: sparse LDL^T
// for a symmetric matrix, supernodal or simplicial by its fill (SparseCholesky,
// sparse_cholesky.hpp), falling back to sparse LU with COLAMD when LDL^T without
// pivoting meets a zero or tiny pivot; sparse LU otherwise. The symbolic analysis
// is done once (analyze); each factorize() reuses it. LDL^T refactorises and
// solves without allocating; sparse LU allocates in every factorisation and solve.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/SparseLU>

#include "../base/types.hpp"
#include "sparse_cholesky.hpp"

namespace nvib {

class SparseFactorization {
 public:
  const char* name() const { return lu_now_ ? "sparse LU" : ldlt_.supernodal() ? "supernodal LDLT" : "sparse LDLT"; }
  // The same, as the base of a low-rank update (newton/low_rank.hpp).
  const char* name_with_low_rank() const {
    return lu_now_ ? "sparse LU + low-rank update"
                   : ldlt_.supernodal() ? "supernodal LDLT + low-rank update" : "sparse LDLT + low-rank update";
  }

  // The pattern of every matrix to come (S's, values ignored); symmetric: try LDL^T first.
  void analyze(const SparseMatrix& S, bool symmetric) {
    symmetric_ = symmetric;
    lu_now_ = !symmetric_;
    if (symmetric_)
      ldlt_.analyze(S);
    else
      lu_.analyzePattern(S);
    lu_analyzed_ = !symmetric_;
    work_.setZero(S.rows());
  }

  // False when S is singular to working precision.
  bool factorize(const SparseMatrix& S) {
    lu_now_ = !symmetric_;
    if (symmetric_) {
      ldlt_.factorize_values(S);
      if (ldlt_.info() == Eigen::Success && regular(ldlt_.pivots())) return true;
      lu_now_ = true;  // a zero or tiny pivot without pivoting: LU with pivoting may still do
    }
    if (!lu_analyzed_) {
      lu_.analyzePattern(S);
      lu_analyzed_ = true;
    }
    lu_.factorize(S);
    return lu_.info() == Eigen::Success;
  }

  void solve_in_place(Vector& x) const {
    if (lu_now_) {
      work_ = x;
      x = lu_.solve(work_);
    } else {
      ldlt_.solve_in_place(x.data(), work_);
    }
  }

 private:
  // The pivots of LDL^T: finite and none below 1e-14 of the largest (as the dense LU's test).
  static bool regular(const Vector& d) {
    double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
    for (Index i = 0; i < d.size(); ++i) {
      const double a = std::abs(d[i]);
      if (!std::isfinite(a)) return false;
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
    return d.size() > 0 && lo > 1e-14 * hi;
  }

  bool symmetric_ = true, lu_now_ = false, lu_analyzed_ = false;
  SparseCholesky<true> ldlt_;
  Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<int>> lu_;
  mutable Vector work_;
};

}  // namespace nvib
