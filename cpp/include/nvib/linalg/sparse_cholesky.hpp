// Sparse Cholesky factorisations, LL^T (the consistent mass) and LDL^T (Newton's iteration
// matrix): SparseCholesky chooses, by the factor's fill, between the supernodal factorisation
// (supernodal_cholesky.hpp: dense kernels on groups of columns, for factors with large fronts, such
// as 3-D solids) and the simplicial one, OrderedCholesky, with the fill-reducing ordering applied
// here instead of inside Eigen's simplicial solvers. Eigen's own path copies and permutes the matrix into a newly allocated one at every
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
#include "supernodal_cholesky.hpp"

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

// The sparse Cholesky factorisation of a symmetric matrix whose pattern is fixed, supernodal where its
// factor's fronts are large enough for dense kernels to pay, simplicial otherwise. The choice is made
// by the supernodal analysis (its ordering, and the column counts of the factor without forming it):
// kSupernodalAbove flops per stored entry of L and more (the mean front; 2 on a chain, 30 to 900 on
// 2-D and 3-D meshes) go to the supernodal factorisation, which at 40 and more was at least 1.8x faster
// and at 2 was 10 to 25 % slower (benchmarks/results/factorize.md). The same contract as
// OrderedCholesky (analyze, factorize_values, info, solve_in_place, pivots, dof_pivots).
template <bool LDLT>
class SparseCholesky {
 public:
  static constexpr double kSupernodalAbove = 10.0;

  // A: symmetric, square; its lower triangle is read (the pattern of every later A must be this one's).
  void analyze(const SparseMatrix& A) {
    supernodal_ = SupernodalCholesky<LDLT>();
    supernodal_.analyze(A);
    const double entries = std::max<double>(1.0, static_cast<double>(supernodal_.simplicial_nonzeros()));
    use_supernodal_ = supernodal_.simplicial_flops() / entries >= kSupernodalAbove;
    if (!use_supernodal_) {
      supernodal_ = SupernodalCholesky<LDLT>();  // its workspaces freed
      simplicial_.analyze(A);
    }
  }
  bool supernodal() const { return use_supernodal_; }

  void factorize_values(const SparseMatrix& A) {
    if (use_supernodal_)
      supernodal_.factorize_values(A);
    else
      simplicial_.factorize_values(A);
  }
  Eigen::ComputationInfo info() const { return use_supernodal_ ? supernodal_.info() : simplicial_.info(); }
  // x <- A^{-1} x, through work (n entries, the caller's: the factors may be shared by threads).
  void solve_in_place(double* x, Vector& work) const {
    if (use_supernodal_)
      supernodal_.solve_in_place(x, work);
    else
      simplicial_.solve_in_place(x, work);
  }
  // The pivots (D of LDL^T, or the squared diagonal of L), in the factor's order, and by row of A.
  const Vector& pivots() const { return use_supernodal_ ? supernodal_.pivots() : simplicial_.pivots(); }
  Vector dof_pivots() const { return use_supernodal_ ? supernodal_.dof_pivots() : simplicial_.dof_pivots(); }

 private:
  bool use_supernodal_ = false;
  SupernodalCholesky<LDLT> supernodal_;
  OrderedCholesky<LDLT> simplicial_;
};

}  // namespace nvib
