// Mass matrix: diagonal (lumped), sparse symmetric positive definite (a
// consistent finite-element mass, factorised once by a sparse Cholesky with a
// fill-reducing ordering) or dense symmetric positive definite (small models
// only: above kDenseMax DOFs it is refused, naming what to use instead).
#pragma once

#include <memory>
#include <string>

#include <Eigen/SparseCholesky>

#include "../linalg/sparse_cholesky.hpp"

#include "../base/types.hpp"

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
    auto data = std::make_shared<Data>();
    data->kind = Kind::diagonal;
    data->d = m;
    data->dinv = m.cwiseInverse();
    data->ndinv = -data->dinv;
    return Mass(std::move(data));
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
    auto data = std::make_shared<Data>();
    data->kind = Kind::sparse;
    data->d = M.diagonal();
    auto llt = std::make_shared<OrderedCholesky<false>>();  // AMD ordering
    llt->analyze(M);
    llt->factorize_values(M);
    data->sllt = llt;
    NVIB_CHECK(data->sllt->info() == Eigen::Success, "mass", "the sparse mass matrix is not positive definite");
    data->S = std::move(M);
    Mass out(std::move(data));
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
    auto data = std::make_shared<Data>();
    data->kind = Kind::dense;
    data->M = M;
    data->dllt = std::make_shared<Eigen::LLT<Matrix>>(M);
    NVIB_CHECK(data->dllt->info() == Eigen::Success, "mass", "the dense mass matrix is not positive definite");
    data->d = M.diagonal();
    return Mass(std::move(data));
  }

  Kind kind() const { return data_->kind; }
  bool is_diagonal() const { return data_->kind == Kind::diagonal; }
  Index size() const { return data_->d.size(); }
  const Vector& diagonal_entries() const { return data_->d; }
  // Stored entries: n (lumped), nnz (sparse), n^2 (dense).
  Index nonzeros() const {
    return data_->kind == Kind::diagonal ? size() : data_->kind == Kind::sparse ? static_cast<Index>(data_->S.nonZeros()) : size() * size();
  }

  // f(i, j, m_ij) for every stored entry (the diagonal, the sparse pattern, or every entry), by columns.
  template <class F>
  void for_each_entry(F&& f) const {
    if (data_->kind == Kind::diagonal) {
      for (Index i = 0; i < size(); ++i) f(i, i, data_->d[i]);
    } else if (data_->kind == Kind::sparse) {
      for (Index j = 0; j < data_->S.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(data_->S, j); it; ++it) f(static_cast<Index>(it.row()), j, it.value());
    } else {
      for (Index j = 0; j < size(); ++j)
        for (Index i = 0; i < size(); ++i) f(i, j, data_->M(i, j));
    }
  }

  Matrix matrix() const {
    if (data_->kind == Kind::diagonal) return data_->d.asDiagonal();
    if (data_->kind == Kind::sparse) return Matrix(data_->S);
    return data_->M;
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
    if (data_->kind == Kind::diagonal)
      out = data_->d.cwiseProduct(x);
    else if (data_->kind == Kind::sparse)
      out.noalias() = data_->S * x;
    else
      out.noalias() = data_->M * x;
  }

  // x <- M^{-1} x
  template <class Out>
  void solve_in_place(Eigen::MatrixBase<Out> const& x_) const {
    auto& x = const_cast<Eigen::MatrixBase<Out>&>(x_);
    if (data_->kind == Kind::diagonal) {
      x.array() *= data_->dinv.array();
    } else if (data_->kind == Kind::sparse) {
      if constexpr (Out::InnerStrideAtCompileTime == 1) {
        data_->sllt->solve_in_place(x.derived().data(), work_);
      } else {
        Vector y = x;
        data_->sllt->solve_in_place(y.data(), work_);
        x = y;
      }
    } else {
      data_->dllt->solveInPlace(x);
    }
  }

  // x <- -M^{-1} x (one pass for a lumped mass: the explicit schemes' acceleration)
  template <class Out>
  void solve_negated_in_place(Eigen::MatrixBase<Out> const& x_) const {
    auto& x = const_cast<Eigen::MatrixBase<Out>&>(x_);
    if (data_->kind == Kind::diagonal) {
      scale(data_->ndinv.size(), x.derived().data(), data_->ndinv.data());
    } else {
      solve_in_place(x);
      x = -x;
    }
  }

  // p_i *= w_i (unrolled up to 8 entries: detail::for_each_index)
  static void scale(Index n, double* __restrict p, const double* __restrict w) {
    detail::for_each_index(n, [=](Index i) { p[i] *= w[i]; });
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

  // What never changes after construction: shared by the copies (one per stepper).
  struct Data {
    Kind kind = Kind::diagonal;
    Vector d, dinv, ndinv;
    Matrix M;
    SparseMatrix S;
    std::shared_ptr<const Eigen::LLT<Matrix>> dllt;
    std::shared_ptr<const OrderedCholesky<false>> sllt;
  };
  explicit Mass(std::shared_ptr<const Data> data) : data_(std::move(data)) {}

  std::shared_ptr<const Data> data_ = std::make_shared<const Data>();
  mutable Vector work_;  // the permuted right-hand side of a sparse solve
};

}  // namespace nvib
