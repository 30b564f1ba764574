// Mass matrix: diagonal (lumped), sparse symmetric positive definite (a
// consistent finite-element mass, factorised once by a sparse Cholesky with a
// fill-reducing ordering, supernodal where its factor fills in) or dense symmetric positive definite (small models
// only: above kDenseMax DOFs it is refused, naming what to use instead).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>

#include <Eigen/SparseCholesky>

#include "../linalg/sparse_cholesky.hpp"

#include "../base/types.hpp"

namespace nvib {

class Mass {
 public:
  enum class Kind { diagonal, sparse, dense };
  // A dense n x n mass and its factorisation take 16 n^2 bytes: 64 MB at this size.
  static constexpr Index kDenseMax = 2000;

  // A pivot below this fraction of the largest diagonal entry makes the mass nearly singular (warning()).
  static constexpr double kNearSingular = 1e-12;
  // How a DOF is named in messages: "DOF 3" by default; a model with DOF names adds the name.
  using DofName = std::function<std::string(Index)>;

  Mass() = default;

  static Mass diagonal(const Vector& m, const DofName& name = {}) {
    NVIB_CHECK(m.size() > 0, "mass", "at least one degree of freedom is needed");
    for (Index i = 0; i < m.size(); ++i) {
      NVIB_CHECK(std::isfinite(m[i]), "mass", "entry " + std::to_string(i) + " is not finite" + named(name, i));
      NVIB_CHECK(m[i] > 0.0, "mass", "entry " + std::to_string(i) + " is " + detail::fmt(m[i]) +
                                      ", every mass must be > 0" + named(name, i));
      NVIB_CHECK(std::isfinite(1.0 / m[i]), "mass", "entry " + std::to_string(i) + " is " + detail::fmt(m[i]) +
                                                     ", too small for its inverse to be finite" + named(name, i));
    }
    auto data = std::make_shared<Data>();
    data->kind = Kind::diagonal;
    data->d = m;
    data->dinv = m.cwiseInverse();
    data->ndinv = -data->dinv;
    data->uniform = (m.array() == m[0]).all();
    data->warning = near_singular(m, m, name, "mass");
    return Mass(std::move(data));
  }

  // A sparse symmetric positive definite mass; one with only diagonal entries is lumped.
  static Mass sparse(SparseMatrix M, const DofName& name = {}) {
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
      return diagonal(d, name);
    }
    check_symmetric(SparseMatrix(M - SparseMatrix(M.transpose())), max_abs(M));
    auto data = std::make_shared<Data>();
    data->kind = Kind::sparse;
    data->d = M.diagonal();
    auto llt = std::make_shared<SparseCholesky<false>>();  // supernodal or simplicial, by its fill
    llt->analyze(M);
    llt->factorize_values(M);
    data->sllt = llt;
    if (data->sllt->info() != Eigen::Success) refuse_not_positive_definite(M, name, "sparse");
    data->warning = near_singular(llt->dof_pivots(), data->d, name, "pivot");
    data->S = std::move(M);
    Mass out(std::move(data));
    out.work_.setZero(n);
    return out;
  }

  static Mass dense(const Matrix& M, const DofName& name = {}) {
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
    if (data->dllt->info() != Eigen::Success) refuse_not_positive_definite(SparseMatrix(M.sparseView(1.0, 0.0)), name, "dense");
    data->d = M.diagonal();
    data->warning = near_singular(data->dllt->matrixLLT().diagonal().cwiseAbs2(), data->d, name, "pivot");
    return Mass(std::move(data));
  }

  Kind kind() const { return data_->kind; }
  // Empty, or what a mass that was accepted still wants said (nearly singular: which DOF).
  const std::string& warning() const { return data_->warning; }
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
  // -1 / m_i of a lumped mass: x_i *= it is solve_negated_in_place().
  const Vector& negated_inverse() const { return data_->ndinv; }
  // A lumped mass of one value for every DOF (then negated_inverse() is that of its first).
  bool is_uniform() const { return data_->kind == Kind::diagonal && data_->uniform; }

  // S += c M (S dense)
  void add_to(MatRef S, double c) const {
    for_each_entry([&](Index i, Index j, double m) { S(i, j) += c * m; });
  }

 private:
  static std::string label(const DofName& name, Index i) { return name ? name(i) : "DOF " + std::to_string(i); }
  static std::string named(const DofName& name, Index i) { return name ? " (" + name(i) + ")" : std::string(); }

  // pivots[i]: DOF i's pivot of the Cholesky factorisation (its mass for a lumped one); d: the diagonal.
  // A pivot below kNearSingular x the largest diagonal entry: the mass is nearly singular there.
  static std::string near_singular(const Vector& pivots, const Vector& d, const DofName& name, const char* what) {
    if (pivots.size() == 0) return {};
    Index k = 0;
    const double smallest = pivots.minCoeff(&k), largest = d.cwiseAbs().maxCoeff();
    if (!(smallest < kNearSingular * largest)) return {};
    const bool lumped = std::string(what) == "mass";
    return "the mass matrix is nearly singular: " + std::string(lumped ? "the mass" : "the Cholesky pivot") + " of " +
           label(name, k) + " is " + detail::fmt(smallest) + ", " + detail::fmt(smallest / largest) +
           " of the largest diagonal mass " + detail::fmt(largest) +
           (lumped ? " (a DOF almost without mass)"
                   : " (a DOF almost without mass of its own, or rows of the mass that nearly depend on others)") +
           ": its accelerations are amplified by the inverse and the explicit schemes' step limit shrinks with "
           "the square root of that mass; check the units and the assembly of the mass";
  }

  // The mass failed its Cholesky factorisation: find the first DOF (in order, no pivoting) whose
  // pivot is not > 0 and say whether it is zero (a DOF without mass: singular) or negative (indefinite).
  [[noreturn]] static void refuse_not_positive_definite(const SparseMatrix& M, const DofName& name, const char* kind) {
    const std::string head = std::string("the ") + kind + " mass matrix is not positive definite: ";
    const Index n = M.rows();
    const Vector d = M.diagonal();
    const double scale = std::max(d.cwiseAbs().maxCoeff(), max_abs(M));
    for (Index i = 0; i < n; ++i) {
      NVIB_CHECK(d[i] != 0.0, "mass", head + "it is singular: " + label(name, i) + " has no mass (its diagonal entry is 0)");
      NVIB_CHECK(d[i] > 0.0, "mass", head + "it is indefinite: " + label(name, i) + " has the negative mass " +
                                         detail::fmt(d[i]) + " on the diagonal");
    }
    Index k = -1;
    double p = 0.0;
    if (n <= kDenseMax) {
      Matrix A(M);  // unpivoted Cholesky, right-looking, until the first pivot that is not > 0
      for (Index j = 0; j < n; ++j) {
        p = A(j, j);
        if (!(p > 0.0)) {
          k = j;
          break;
        }
        const Index r = n - j - 1;
        if (r == 0) break;
        A.col(j).tail(r) /= std::sqrt(p);
        A.bottomRightCorner(r, r).selfadjointView<Eigen::Lower>().rankUpdate(A.col(j).tail(r), -1.0);
      }
    } else {
      Eigen::SimplicialLDLT<SparseMatrix, Eigen::Lower, Eigen::NaturalOrdering<int>> ldlt(M);
      if (ldlt.info() == Eigen::Success) {
        const Vector D = ldlt.vectorD();
        for (Index j = 0; j < n && k < 0; ++j)
          if (!(D[j] > 0.0)) k = j, p = D[j];
      }
    }
    NVIB_CHECK(k >= 0, "mass", head + "a pivot of its Cholesky factorisation is not > 0 (round-off on a nearly singular matrix)");
    const std::string where = "the pivot of " + label(name, k) + " after eliminating the DOFs before it is " + detail::fmt(p);
    NVIB_CHECK(std::abs(p) > kNearSingular * scale, "mass",
               head + "it is singular: " + where + " (0 up to round-off): " + label(name, k) +
                   " has no mass of its own, its row depends on the rows before it");
    throw ArgumentError("mass", head + "it is indefinite: " + where +
                                    " < 0 (off-diagonal entries too large for the diagonal: a negative mass in some "
                                    "direction)");
  }

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
    bool uniform = false;
    Vector d, dinv, ndinv;
    Matrix M;
    SparseMatrix S;
    std::shared_ptr<const Eigen::LLT<Matrix>> dllt;
    std::shared_ptr<const SparseCholesky<false>> sllt;
    std::string warning;
  };
  explicit Mass(std::shared_ptr<const Data> data) : data_(std::move(data)) {}

  std::shared_ptr<const Data> data_ = std::make_shared<const Data>();
  mutable Vector work_;  // the permuted right-hand side of a sparse solve
};

}  // namespace nvib
