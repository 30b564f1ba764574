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

#include <algorithm>
#include <cmath>
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

  // Assembles S and factorises it, unless it is, bit for bit, the S factorised last (a piecewise-linear
  // law on the same branch): then the factors are kept and reused() says so.
  template <class ModelT>
  bool factorize(ModelT& model, const IterationMatrix& im, Stats& st, bool finite_difference,
                 LinearSolverChoice choice = LinearSolverChoice::automatic) {
    if (!chosen_) choose(model, finite_difference, choice);
    reused_ = false;
    if (dense_) {
      if (dense_S_.size() != model.size() || S_.rows() != model.size()) {
        dense_S_.resize(model.size());
        lu_.resize(model.size());
        S_.setZero(model.size(), model.size());
        have_last_ = false;
      }
      st.linear_solver = kDenseName;
      dense_S_.assemble(model, im, st, finite_difference, S_);
      if (have_last_ && same(S_.data(), last_.data(), S_.size())) return reused_ = true, last_ok_;
      lu_.assembly() = S_;
      last_ok_ = lu_.factorize_assembled();
      last_ = S_;
      have_last_ = true;
      return last_ok_;
    }
    if (!sparse_S_.assemble(model, im, st)) return have_last_ = false;
    const SparseMatrix& S = sparse_S_.matrix();
    st.linear_solver = sparse_lu_.name();
    if (have_last_ && same(S.valuePtr(), last_.data(), S.nonZeros())) return reused_ = true, last_ok_;
    last_ok_ = sparse_lu_.factorize(S);
    st.linear_solver = sparse_lu_.name();
    last_.resize(S.nonZeros(), 1);
    std::copy(S.valuePtr(), S.valuePtr() + S.nonZeros(), last_.data());
    have_last_ = true;
    return last_ok_;
  }
  // The last factorize() kept the factors of an identical S.
  bool reused() const { return reused_; }
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
      // the argument to blame: the dense solver the caller asked for on a model whose tangent is sparse,
      // the finite-difference tangent, or the model whose force gives only a dense tangent
      const bool asked = sparse_possible && choice == LinearSolverChoice::dense;
      NVIB_CHECK(n <= Mass::kDenseMax, asked ? "linear_solver" : finite_difference ? "jacobian" : "model",
                 asked ? "'dense' factorises the iteration matrix as a dense " + std::to_string(n) + " x " +
                             std::to_string(n) + " matrix (" + detail::fmt(mb) + " MB); above " +
                             std::to_string(Mass::kDenseMax) +
                             " DOFs use linear_solver='sparse' (or 'auto', the default: this model's tangent is sparse)"
                 : finite_difference
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

  static bool same(const double* a, const double* b, Index n) {
    for (Index k = 0; k < n; ++k)
      if (!(a[k] == b[k]) || std::signbit(a[k]) != std::signbit(b[k])) return false;
    return true;
  }

  bool chosen_ = false, dense_ = true;
  bool have_last_ = false, last_ok_ = false, reused_ = false;
  Matrix S_, last_;  // the assembled S (dense), and the S of the factors kept (dense, or the sparse values)
  DenseIterationMatrix dense_S_;
  DenseLU lu_;
  SparseIterationMatrix sparse_S_;
  SparseFactorization sparse_lu_;
};

}  // namespace nvib
