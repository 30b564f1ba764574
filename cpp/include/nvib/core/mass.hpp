// Mass matrix: diagonal (lumped) or dense symmetric positive definite.
#pragma once

#include "types.hpp"

namespace nvib {

class Mass {
 public:
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
    out.diag_ = true;
    out.d_ = m;
    out.dinv_ = m.cwiseInverse();
    out.ndinv_ = -out.dinv_;
    out.llt_.compute(Matrix());  // a defined (empty) factorisation, so copies copy defined state
    return out;
  }

  static Mass dense(const Matrix& M) {
    NVIB_CHECK(M.rows() > 0 && M.rows() == M.cols(), "mass",
                    "a dense mass must be square, got " + std::to_string(M.rows()) + "x" +
                        std::to_string(M.cols()));
    NVIB_CHECK(M.allFinite(), "mass", "the matrix has non-finite entries");
    const double scale = M.cwiseAbs().maxCoeff();
    NVIB_CHECK((M - M.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * scale, "mass",
                    "the dense mass matrix is not symmetric");
    Mass out;
    out.diag_ = false;
    out.M_ = M;
    out.llt_.compute(M);
    NVIB_CHECK(out.llt_.info() == Eigen::Success, "mass",
                    "the dense mass matrix is not positive definite");
    out.d_ = M.diagonal();
    return out;
  }

  bool is_diagonal() const { return diag_; }
  Index size() const { return d_.size(); }
  const Vector& diagonal_entries() const { return d_; }
  double entry(Index i, Index j) const { return diag_ ? (i == j ? d_[i] : 0.0) : M_(i, j); }

  Matrix matrix() const {
    if (diag_) return d_.asDiagonal();
    return M_;
  }

  // out = M x
  template <class In, class Out>
  void apply(const Eigen::MatrixBase<In>& x, Eigen::MatrixBase<Out> const& out_) const {
    auto& out = const_cast<Eigen::MatrixBase<Out>&>(out_);
    if (diag_)
      out = d_.cwiseProduct(x);
    else
      out.noalias() = M_ * x;
  }

  // x <- M^{-1} x
  template <class Out>
  void solve_in_place(Eigen::MatrixBase<Out> const& x_) const {
    auto& x = const_cast<Eigen::MatrixBase<Out>&>(x_);
    if (diag_)
      x.array() *= dinv_.array();
    else
      llt_.solveInPlace(x);
  }

  // x <- -M^{-1} x (one pass for a lumped mass: the explicit schemes' acceleration)
  template <class Out>
  void solve_negated_in_place(Eigen::MatrixBase<Out> const& x_) const {
    auto& x = const_cast<Eigen::MatrixBase<Out>&>(x_);
    if (diag_) {
      double* p = x.derived().data();
      const double* w = ndinv_.data();
      for (Index i = 0, n = ndinv_.size(); i < n; ++i) p[i] *= w[i];
    } else {
      llt_.solveInPlace(x);
      x = -x;
    }
  }

  // S += c M
  void add_to(MatRef S, double c) const {
    if (diag_)
      S.diagonal() += c * d_;
    else
      S += c * M_;
  }

 private:
  bool diag_ = true;
  Vector d_, dinv_, ndinv_;
  Matrix M_;
  Eigen::LLT<Matrix> llt_;
};

}  // namespace nvib
