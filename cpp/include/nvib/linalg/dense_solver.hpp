// The dense linear solver of the Newton component: K_t and C_t as n x n
// matrices from the model's tangent, S = cK K_t + cM M + cC C_t assembled in
// the storage of an LU with partial pivoting. For small models, and for
// forces whose tangent is only known as a whole matrix.
#pragma once

#include "../core/types.hpp"
#include "dense_lu.hpp"
#include "iteration_matrix.hpp"

namespace nvib {

class DenseLinearSolver {
 public:
  static constexpr const char* name = "dense LU";

  void resize(Index n) {
    Kt_.setZero(n, n);
    Ct_.setZero(n, n);
    lu_.resize(n);
  }

  template <class ModelT>
  bool factorize(ModelT& model, const IterationMatrix& im, Stats& st, bool finite_difference) {
    if (Kt_.rows() != model.size()) resize(model.size());
    st.linear_solver = name;
    model.tangent(*im.u, *im.v, im.t, Kt_, Ct_, st, finite_difference);
    Matrix& S = lu_.assembly();
    const Index n = S.rows();
    const double *K = Kt_.data(), *C = Ct_.data();
    double* out = S.data();
    for (Index ij = 0; ij < n * n; ++ij) out[ij] = im.cK * K[ij];
    const Mass& mass = model.mass();
    if (mass.is_diagonal()) {
      const double* m = mass.diagonal_entries().data();
      for (Index i = 0; i < n; ++i) out[i + i * n] += im.cM * m[i];
    } else {
      mass.for_each_entry([&](Index i, Index j, double m) { out[i + j * n] += im.cM * m; });
    }
    if (model.uses_velocity())
      for (Index ij = 0; ij < n * n; ++ij) out[ij] += im.cC * C[ij];
    return lu_.factorize_assembled();
  }

  void solve_in_place(Vector& x) const { lu_.solve_in_place(x); }
  // out = C_t x (the last tangent)
  void multiply_C(const Vector& x, Vector& out) const { out.noalias() = Ct_ * x; }
  Vector tangent_diagonal() const { return Kt_.diagonal(); }

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
