// Sparse Cholesky factorisations, LL^T (the consistent mass) and LDL^T (Newton's iteration
// matrix), with the fill-reducing ordering applied here instead of inside Eigen's simplicial
// solvers. Eigen's own path copies and permutes the matrix into a newly allocated one at every
// factorisation and permutes each right-hand side through a heap-allocated mask; here the
// permuted upper triangle P A P^T is laid out once, with the place of every stored entry of A's
// lower triangle in it, so that a refactorisation writes the values into place and a solve
// permutes through the caller's storage. Ordering (AMD on A's pattern) and arithmetic are Eigen's,
// so the factors are the same.
#pragma once

#include <algorithm>
#include <type_traits>
#include <vector>

#include <Eigen/OrderingMethods>
#include <Eigen/SparseCholesky>

#include "../base/types.hpp"

namespace nvib {

template <bool LDLT>
class OrderedCholesky
    : public std::conditional_t<LDLT, Eigen::SimplicialLDLT<SparseMatrix, Eigen::Upper, Eigen::NaturalOrdering<int>>,
                                Eigen::SimplicialLLT<SparseMatrix, Eigen::Upper, Eigen::NaturalOrdering<int>>> {
 public:
  // A: symmetric, square; its lower triangle is read (the pattern of every later A must be this one's).
  void analyze(const SparseMatrix& A) {
    const Index n = A.rows();
    {
      SparseMatrix full(n, n);
      full = A.selfadjointView<Eigen::Lower>();
      Eigen::AMDOrdering<int> amd;
      Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> pinv;
      amd(full, pinv);  // the inverse permutation, as Eigen's ordering methods return it
      perm_.resize(static_cast<size_t>(n));
      for (Index i = 0; i < n; ++i) perm_[static_cast<size_t>(pinv.indices()[i])] = static_cast<int>(i);
    }
    // Entry (i, j), i >= j, of A goes to (min(p_i, p_j), max(p_i, p_j)) of P A P^T: upper triangle.
    std::vector<Eigen::Triplet<double, int>> upper;
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it)
        if (it.row() >= j) {
          const int a = perm_[static_cast<size_t>(it.row())], b = perm_[static_cast<size_t>(j)];
          upper.emplace_back(std::min(a, b), std::max(a, b), 0.0);
        }
    PA_.resize(n, n);
    PA_.setFromTriplets(upper.begin(), upper.end());
    PA_.makeCompressed();
    place_.clear();
    for (Index j = 0; j < A.outerSize(); ++j)
      for (Index k = A.outerIndexPtr()[j]; k < A.outerIndexPtr()[j + 1]; ++k) {
        const Index i = A.innerIndexPtr()[k];
        if (i < j) {
          place_.push_back(-1);  // the upper triangle of A is not read
          continue;
        }
        const int a = perm_[static_cast<size_t>(i)], b = perm_[static_cast<size_t>(j)];
        const int r = std::min(a, b), c = std::max(a, b);
        const int* rows = PA_.innerIndexPtr();
        const int *first = rows + PA_.outerIndexPtr()[c], *last = rows + PA_.outerIndexPtr()[c + 1];
        place_.push_back(static_cast<int>(std::lower_bound(first, last, r) - rows));
      }
    this->analyzePattern_preordered(PA_, LDLT);
  }

  // The numeric factorisation of A (analyze()'s pattern, in the same storage order); info() says
  // whether it succeeded.
  void factorize_values(const SparseMatrix& A) {
    const double* a = A.valuePtr();
    double* pa = PA_.valuePtr();
    for (size_t k = 0; k < place_.size(); ++k)
      if (place_[k] >= 0) pa[place_[k]] = a[k];
    this->template factorize_preordered<LDLT>(PA_);
  }

  // x <- A^{-1} x, through work (n entries, the caller's: the factors may be shared by threads).
  void solve_in_place(double* x, Vector& work) const {
    const Index n = static_cast<Index>(perm_.size());
    for (Index i = 0; i < n; ++i) work[perm_[static_cast<size_t>(i)]] = x[i];
    if (this->m_matrix.nonZeros() > 0) this->matrixL().solveInPlace(work);
    if constexpr (LDLT) work = this->m_diag.asDiagonal().inverse() * work;  // Eigen's own expression
    if (this->m_matrix.nonZeros() > 0) this->matrixU().solveInPlace(work);
    for (Index i = 0; i < n; ++i) x[i] = work[perm_[static_cast<size_t>(i)]];
  }

  // The pivot of each row of A (not of P A P^T): D of LDL^T, or the squared diagonal of L of LL^T.
  Vector dof_pivots() const {
    const Index n = static_cast<Index>(perm_.size());
    Vector out(n);
    for (Index i = 0; i < n; ++i) {
      const int k = perm_[static_cast<size_t>(i)];
      if constexpr (LDLT) {
        out[i] = this->m_diag[k];
      } else {
        const double l = this->m_matrix.coeff(k, k);
        out[i] = l * l;
      }
    }
    return out;
  }

  // D of LDL^T, by reference (Eigen's vectorD() returns a copy).
  const Vector& pivots() const { return this->m_diag; }

 private:
  std::vector<int> perm_;   // i -> its row in P A P^T
  std::vector<int> place_;  // A's k-th stored value -> its index in PA_'s values (-1: not read)
  SparseMatrix PA_;
};

}  // namespace nvib
