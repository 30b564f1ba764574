// Mass matrix: diagonal (lumped), sparse symmetric positive definite (a
// consistent finite-element mass, factorised once by a sparse Cholesky with a
// fill-reducing ordering) or dense symmetric positive definite (small models
// only: above kDenseMax DOFs it is refused, naming what to use instead).
#pragma once

#include <memory>
#include <string>

#include <Eigen/SparseCholesky>

#include "types.hpp"

namespace nvib {

class Mass {
 public:
  enum class Kind { diagonal, sparse, dense };
  // A dense n x n mass and its factorisation take 16 n^2 bytes: 64 MB at this size.
  static constexpr Index kDenseMax = 2000;

  Mass() = default;

  static Mass diagonal(const Vector& m) {
    NVIB_CHECK(m.size() > 0, "mass", "at least one degree of freedom is needed");
    for (Index i = 0; i < m.size(); ++i) {
      NVIB_CHECK(std::isfinite(m[i]), "mass", "entry " + std::to_string(i) + " is not finite");
      NVIB_CHECK(m[i] > 0.0, "mass", "entry " + std::to_string(i) + " is " + detail::fmt(m[i]) +
                                      ", every mass must be > 0");
      NVIB_CHECK(std::isfinite(1.0 / m[i]), "mass", "entry " + std::to_string(i) + " is " + detail::fmt(m[i]) +
                                                     ", too small for its inverse to be finite");
    }
    Mass out;
    out.kind_ = Kind::diagonal;
    out.d_ = m;
    out.dinv_ = m.cwiseInverse();
    out.ndinv_ = -out.dinv_;
    return out;
  }

  // A sparse symmetric positive definite mass; one with only diagonal entries is lumped.
  static Mass sparse(SparseMatrix M) {
    const Index n = M.rows();
    NVIB_CHECK(n > 0 && n == M.cols(), "mass",
               "a sparse mass must be square, got " + std::to_string(n) + "x" + std::to_string(M.cols()));
    M.prune(0.0);
    M.makeCompressed();
    bool diagonal_only = true;
    for (Index j = 0; j < n; ++j)
      for (SparseMatrix::InnerIterator it(M, j); it; ++it) {
        NVIB_CHECK(std::isfinite(it.value()), "mass", "the matrix has non-finite entries");
        diagonal_only = diagonal_only && it.row() == j;
      }
    if (diagonal_only) {
      Vector d = M.diagonal();
      return diagonal(d);
    }
    check_symmetric(SparseMatrix(M - SparseMatrix(M.transpose())), max_abs(M));
    Mass out;
    out.kind_ = Kind::sparse;
    out.d_ = M.diagonal();
    auto llt = std::make_shared<Eigen::SimplicialLLT<SparseMatrix>>(M);  // AMD ordering
    NVIB_CHECK(llt->info() == Eigen::Success, "mass", "the sparse mass matrix is not positive definite");
    out.sllt_ = std::move(llt);
    out.S_ = std::move(M);
    out.work_.setZero(n);
    return out;
  }

  static Mass dense(const Matrix& M) {
    NVIB_CHECK(M.rows() > 0 && M.rows() == M.cols(), "mass",
               "a dense mass must be square, got " + std::to_string(M.rows()) + "x" + std::to_string(M.cols()));
    NVIB_CHECK(M.rows() <= kDenseMax, "mass",
               "a dense mass of " + std::to_string(M.rows()) + " DOFs would take " +
                   detail::fmt(16.0 * static_cast<double>(M.rows()) * static_cast<double>(M.rows()) / 1e6) +
                   " MB; above " + std::to_string(kDenseMax) +
                   " DOFs give it as a sparse matrix (scipy.sparse), or lumped (a 1-D array of masses)");
    NVIB_CHECK(M.allFinite(), "mass", "the matrix has non-finite entries");
    check_symmetric(M - M.transpose(), M.cwiseAbs().maxCoeff());
    Mass out;
    out.kind_ = Kind::dense;
    out.M_ = M;
    out.dllt_ = std::make_shared<Eigen::LLT<Matrix>>(M);
    NVIB_CHECK(out.dllt_->info() == Eigen::Success, "mass", "the dense mass matrix is not positive definite");
    out.d_ = M.diagonal();
    return out;
  }

  Kind kind() const { return kind_; }
  bool is_diagonal() const { return kind_ == Kind::diagonal; }
  Index size() const { return d_.size(); }
  const Vector& diagonal_entries() const { return d_; }
  // Stored entries: n (lumped), nnz (sparse), n^2 (dense).
  Index nonzeros() const {
    return kind_ == Kind::diagonal ? size() : kind_ == Kind::sparse ? static_cast<Index>(S_.nonZeros()) : size() * size();
  }

  // f(i, j, m_ij) for every stored entry (the diagonal, the sparse pattern, or every entry), by columns.
  template <class F>
  void for_each_entry(F&& f) const {
    if (kind_ == Kind::diagonal) {
      for (Index i = 0; i < size(); ++i) f(i, i, d_[i]);
    } else if (kind_ == Kind::sparse) {
      for (Index j = 0; j < S_.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(S_, j); it; ++it) f(static_cast<Index>(it.row()), j, it.value());
    } else {
      for (Index j = 0; j < size(); ++j)
        for (Index i = 0; i < size(); ++i) f(i, j, M_(i, j));
    }
  }

  Matrix matrix() const {
    if (kind_ == Kind::diagonal) return d_.asDiagonal();
    if (kind_ == Kind::sparse) return Matrix(S_);
    return M_;
  }
  SparseMatrix sparse_matrix() const {
    SparseMatrix out(size(), size());
    std::vector<Eigen::Triplet<double, int>> entries;
    entries.reserve(static_cast<size_t>(nonzeros()));
    for_each_entry([&](Index i, Index j, double m) {
      if (m != 0.0) entries.emplace_back(static_cast<int>(i), static_cast<int>(j), m);
    });
    out.setFromTriplets(entries.begin(), entries.end());
    return out;
  }

  // out = M x
  template <class In, class Out>
  void apply(const Eigen::MatrixBase<In>& x, Eigen::MatrixBase<Out> const& out_) const {
    auto& out = const_cast<Eigen::MatrixBase<Out>&>(out_);
    if (kind_ == Kind::diagonal)
      out = d_.cwiseProduct(x);
    else if (kind_ == Kind::sparse)
      out.noalias() = S_ * x;
    else
      out.noalias() = M_ * x;
  }

  // x <- M^{-1} x
  template <class Out>
  void solve_in_place(Eigen::MatrixBase<Out> const& x_) const {
    auto& x = const_cast<Eigen::MatrixBase<Out>&>(x_);
    if (kind_ == Kind::diagonal) {
      x.array() *= dinv_.array();
    } else if (kind_ == Kind::sparse) {
      work_ = x;
      x = sllt_->solve(work_);
    } else {
      dllt_->solveInPlace(x);
    }
  }

  // x <- -M^{-1} x (one pass for a lumped mass: the explicit schemes' acceleration)
  template <class Out>
  void solve_negated_in_place(Eigen::MatrixBase<Out> const& x_) const {
    auto& x = const_cast<Eigen::MatrixBase<Out>&>(x_);
    if (kind_ == Kind::diagonal) {
      double* p = x.derived().data();
      const double* w = ndinv_.data();
      for (Index i = 0, n = ndinv_.size(); i < n; ++i) p[i] *= w[i];
    } else {
      solve_in_place(x);
      x = -x;
    }
  }

  // S += c M (S dense)
  void add_to(MatRef S, double c) const {
    for_each_entry([&](Index i, Index j, double m) { S(i, j) += c * m; });
  }

 private:
  template <class A>
  static void check_symmetric(const A& difference, double scale) {
    NVIB_CHECK(max_abs(difference) <= 1e-12 * scale, "mass", "the mass matrix is not symmetric");
  }
  static double max_abs(const SparseMatrix& A) {
    double m = 0.0;
    for (Index k = 0; k < A.nonZeros(); ++k) m = std::max(m, std::abs(A.valuePtr()[k]));
    return m;
  }
  static double max_abs(const Matrix& A) { return A.size() ? A.cwiseAbs().maxCoeff() : 0.0; }

  Kind kind_ = Kind::diagonal;
  Vector d_, dinv_, ndinv_;
  Matrix M_;
  SparseMatrix S_;
  // Factorisations: immutable once made, shared by copies of the model.
  std::shared_ptr<const Eigen::LLT<Matrix>> dllt_;
  std::shared_ptr<const Eigen::SimplicialLLT<SparseMatrix>> sllt_;
  mutable Vector work_;  // the right-hand side of a sparse solve
};

}  // namespace nvib
