// The linear system of the Newton component: the iteration matrix assembled
// from the model (iteration_matrix.hpp) and factorised (linalg/), dense or
// sparse, chosen once per stepper by size and density (or forced) and named in
// Stats::linear_solver. The Newton component asks it for
//   bool factorize(model, IterationMatrix, Stats&, bool finite_difference, choice)   false if S is singular
//   void solve_in_place(Vector& x)                      x <- S^{-1} x
//   void multiply_C(const Vector& x, Vector& out) const out = C_t x (the last tangent)
//   Vector tangent_diagonal()                           the diagonal of the last K_t
//   Index first_nonfinite_tangent_row() const           -1 if the last tangent is finite
#pragma once

#include <string>

#include "../base/types.hpp"
#include "../linalg/dense_lu.hpp"
#include "../linalg/sparse_factorization.hpp"
#include "../model/mass.hpp"
#include "iteration_matrix.hpp"
#include "options.hpp"

namespace nvib {

class IterationSystem {
 public:
  // Up to this size the dense LU is used whatever the pattern (it is faster there);
  // up to kDenseFullMax also when S is more than a quarter full.
  static constexpr Index kDenseBelow = 64, kDenseFullMax = 500;
  static constexpr const char* kDenseName = "dense LU";

  void resize(Index) { chosen_ = false; }
  const char* name() const { return !chosen_ ? "" : dense_ ? kDenseName : sparse_lu_.name(); }
  bool is_dense() const { return dense_; }

  template <class ModelT>
  bool factorize(ModelT& model, const IterationMatrix& im, Stats& st, bool finite_difference,
                 LinearSolverChoice choice = LinearSolverChoice::automatic) {
    if (!chosen_) choose(model, finite_difference, choice);
    if (dense_) {
      if (dense_S_.size() != model.size()) {
        dense_S_.resize(model.size());
        lu_.resize(model.size());
      }
      st.linear_solver = kDenseName;
      dense_S_.assemble(model, im, st, finite_difference, lu_.assembly());
      return lu_.factorize_assembled();
    }
    if (!sparse_S_.assemble(model, im, st)) return false;
    const bool ok = sparse_lu_.factorize(sparse_S_.matrix());
    st.linear_solver = sparse_lu_.name();
    return ok;
  }
  void solve_in_place(Vector& x) const {
    if (dense_)
      lu_.solve_in_place(x);
    else
      sparse_lu_.solve_in_place(x);
  }
  void multiply_C(const Vector& x, Vector& out) const {
    if (dense_)
      dense_S_.multiply_C(x, out);
    else
      sparse_S_.multiply_C(x, out);
  }
  Vector tangent_diagonal() { return dense_ ? dense_S_.tangent_diagonal() : sparse_S_.tangent_diagonal(); }
  Index first_nonfinite_tangent_row() const {
    return dense_ ? dense_S_.first_nonfinite_tangent_row() : sparse_S_.first_nonfinite_tangent_row();
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
      setup_sparse(model);
      dense_ = false;
    } else if (n <= kDenseBelow) {
      dense_ = true;
    } else {
      setup_sparse(model);
      const double fill = static_cast<double>(sparse_S_.nonzeros()) / (static_cast<double>(n) * static_cast<double>(n));
      dense_ = n <= kDenseFullMax && fill > 0.25;
    }
    if (dense_) {
      dense_S_.resize(n);
      lu_.resize(n);
    }
  }
  template <class ModelT>
  void setup_sparse(const ModelT& model) {
    sparse_S_.setup(model);
    sparse_lu_.analyze(sparse_S_.matrix(), sparse_S_.symmetric());
  }

  bool chosen_ = false, dense_ = true;
  DenseIterationMatrix dense_S_;
  DenseLU lu_;
  SparseIterationMatrix sparse_S_;
  SparseFactorization sparse_lu_;
};

}  // namespace nvib
