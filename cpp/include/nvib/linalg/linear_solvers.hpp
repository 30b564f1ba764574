// Linear solvers of the Newton component. A policy owns the iteration matrix
// S = cM M + cC C_t + cK K_t and its factorisation:
//   bool factorize(model, IterationMatrix, Stats&, bool finite_difference)   false if S is singular
//   void solve_in_place(Vector& x)          x <- S^{-1} x
//   void multiply_C(const Vector& x, Vector& out) const   out = C_t x (the last tangent)
//   Vector tangent_diagonal()                           the diagonal of the last K_t
//   Index first_nonfinite_tangent_row() const             -1 if the last tangent is finite
// DenseLinearSolver (dense_solver.hpp), SparseLinearSolver (sparse_solver.hpp),
// and AutoLinearSolver, which chooses between them by size and density and
// says which in Stats::linear_solver.
#pragma once

#include <string>

#include "../core/mass.hpp"
#include "../core/types.hpp"
#include "dense_solver.hpp"
#include "iteration_matrix.hpp"
#include "sparse_solver.hpp"

namespace nvib {

class AutoLinearSolver {
 public:
  // Up to this size the dense LU is used whatever the pattern (it is faster there);
  // up to kDenseFullMax also when S is more than a quarter full.
  static constexpr Index kDenseBelow = 64, kDenseFullMax = 500;

  void resize(Index) { chosen_ = false; }
  const char* name() const { return !chosen_ ? "" : dense_ ? DenseLinearSolver::name : sparse_.name(); }
  bool is_dense() const { return dense_; }

  template <class ModelT>
  bool factorize(ModelT& model, const IterationMatrix& im, Stats& st, bool finite_difference,
                 LinearSolverChoice choice = LinearSolverChoice::automatic) {
    if (!chosen_) choose(model, finite_difference, choice);
    return dense_ ? dense_solver_.factorize(model, im, st, finite_difference) : sparse_.factorize(model, im, st);
  }
  void solve_in_place(Vector& x) const {
    if (dense_)
      dense_solver_.solve_in_place(x);
    else
      sparse_.solve_in_place(x);
  }
  void multiply_C(const Vector& x, Vector& out) const {
    if (dense_)
      dense_solver_.multiply_C(x, out);
    else
      sparse_.multiply_C(x, out);
  }
  Vector tangent_diagonal() { return dense_ ? dense_solver_.tangent_diagonal() : sparse_.tangent_diagonal(); }
  Index first_nonfinite_tangent_row() const {
    return dense_ ? dense_solver_.first_nonfinite_tangent_row() : sparse_.first_nonfinite_tangent_row();
  }

 private:
  template <class ModelT>
  void choose(const ModelT& model, bool finite_difference, LinearSolverChoice choice) {
    const Index n = model.size();
    chosen_ = true;
    const bool sparse_possible = model.has_sparse_tangent() && !finite_difference;
    NVIB_CHECK(choice != LinearSolverChoice::sparse || sparse_possible, "linear_solver",
               finite_difference ? "'sparse' needs jacobian='analytic' (a finite-difference tangent is dense)"
                                 : "'sparse' needs a model whose tangent is known entry by entry (declared effects "
                                   "and laws on measures; not a force callable)");
    if (!sparse_possible || choice == LinearSolverChoice::dense) {
      const double mb = 16.0 * static_cast<double>(n) * static_cast<double>(n) / 1e6;
      NVIB_CHECK(n <= Mass::kDenseMax, finite_difference ? "jacobian" : "model",
                 finite_difference
                     ? "a finite-difference tangent differentiates the whole force, a dense " + std::to_string(n) +
                           " x " + std::to_string(n) + " matrix (" + detail::fmt(mb) + " MB); above " +
                           std::to_string(Mass::kDenseMax) + " DOFs use jacobian='analytic'"
                     : "the force of this model gives its tangent only as a dense " + std::to_string(n) + " x " +
                           std::to_string(n) + " matrix (" + detail::fmt(mb) + " MB); above " +
                           std::to_string(Mass::kDenseMax) +
                           " DOFs declare its forces as effects (their tangent is sparse), or use an explicit scheme");
      dense_ = true;
    } else if (choice == LinearSolverChoice::sparse) {
      sparse_.setup(model);
      dense_ = false;
    } else if (n <= kDenseBelow) {
      dense_ = true;
    } else {
      sparse_.setup(model);
      const double fill = static_cast<double>(sparse_.nonzeros()) / (static_cast<double>(n) * static_cast<double>(n));
      dense_ = n <= kDenseFullMax && fill > 0.25;
    }
    if (dense_) dense_solver_.resize(n);
  }

  bool chosen_ = false, dense_ = true;
  DenseLinearSolver dense_solver_;
  SparseLinearSolver sparse_;
};

}  // namespace nvib
