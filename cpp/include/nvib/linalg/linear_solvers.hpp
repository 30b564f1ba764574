// Linear solvers of the Newton component. A policy owns the iteration matrix
// S = cM M + cC C_t + cK K_t and its factorisation:
//   void resize(Index n)
//   bool factorize(model, IterationMatrix, Stats&, bool finite_difference)   false if S is singular
//   void solve_in_place(Vector& x)          x <- S^{-1} x
//   void multiply_C(const Vector& x, Vector& out) const   out = C_t x (the last tangent)
//   Index first_nonfinite_tangent_row() const             -1 if the last tangent is finite
// Dense LU here; sparse factorisations are further policies with the same face.
#pragma once

#include "../core/types.hpp"
#include "dense_lu.hpp"

namespace nvib {

// S = cM M + cC C_t + cK K_t with the tangents taken at (u, v, t).
struct IterationMatrix {
  double cM = 0.0, cC = 0.0, cK = 1.0;
  const Vector* u = nullptr;
  const Vector* v = nullptr;
  double t = 0.0;
};

class DenseLinearSolver {
 public:
  static constexpr const char* name = "dense LU";

  void resize(Index n) {
    Kt_.setZero(n, n);
    Ct_.setZero(n, n);
    lu_.resize(n);
  }

  // S = (cK K_t + cM M) + cC C_t, assembled in the factorisation's own storage.
  template <class ModelT>
  bool factorize(ModelT& model, const IterationMatrix& im, Stats& st, bool finite_difference) {
    model.tangent(*im.u, *im.v, im.t, Kt_, Ct_, st, finite_difference);
    Matrix& S = lu_.assembly();
    const Index n = S.rows();
    const double *K = Kt_.data(), *C = Ct_.data();
    double* out = S.data();
    const Mass& mass = model.mass();
    for (Index ij = 0; ij < n * n; ++ij) out[ij] = im.cK * K[ij];
    if (mass.is_diagonal()) {
      const double* m = mass.diagonal_entries().data();
      for (Index i = 0; i < n; ++i) out[i + i * n] += im.cM * m[i];
    } else {
      for (Index j = 0; j < n; ++j)
        for (Index i = 0; i < n; ++i) out[i + j * n] += im.cM * mass.entry(i, j);
    }
    if (model.uses_velocity())
      for (Index ij = 0; ij < n * n; ++ij) out[ij] += im.cC * C[ij];
    return lu_.factorize_assembled();
  }

  void solve_in_place(Vector& x) const { lu_.solve_in_place(x); }
  void multiply_C(const Vector& x, Vector& out) const { out.noalias() = Ct_ * x; }
  const Matrix& K() const { return Kt_; }

  Index first_nonfinite_tangent_row() const {
    if (Kt_.allFinite() && Ct_.allFinite()) return -1;
    Index dof = 0;
    while (dof + 1 < Kt_.rows() && Kt_.row(dof).allFinite() && Ct_.row(dof).allFinite()) ++dof;
    return dof;
  }

 private:
  Matrix Kt_, Ct_;
  DenseLU lu_;
};

}  // namespace nvib
