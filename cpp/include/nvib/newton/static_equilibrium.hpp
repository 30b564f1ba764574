// Static equilibrium G(u, 0, t) = 0 (the constant loads balanced), solved by
// the Newton component. Where the tangent stiffness is singular (a body held
// only by a contact that is not yet closed, a free-floating vehicle), the
// iteration matrix gets a mass-proportional term, like an implicit dynamic
// step, until the tangent is regular again.
#pragma once

#include <algorithm>
#include <limits>

#include "../base/types.hpp"
#include "newton.hpp"

namespace nvib {

template <class ModelT>
class StaticEquilibrium {
  using Solver = NewtonSolver<IterationSystem>;
  friend Solver;

 public:
  StaticEquilibrium(ModelT& model, double t, const Vector& guess) : model_(model), t_(t), guess_(guess) {
    zero_.setZero(model.size());
  }

  // Solves with the given options; the status and, on failure, newton.failure() tell how it went.
  Status solve(Solver& newton, Vector& u, Stats& st) {
    Vector r(model_.size());
    model_.force(guess_, zero_, t_, r, st);
    scale_ = r.template lpNorm<Eigen::Infinity>();  // the loads to balance, seen from the guess
    return newton.solve(*this, model_, u, t_, 0, st);
  }

 private:
  // Never the one-solve shortcut: a singular linear model has no equilibrium to find.
  bool linear() const { return false; }
  void predict(Vector& x) {
    x = guess_;
    u_ = &x;
  }
  void update(const Vector&) {}
  Residual residual(Vector& r) {
    Stats st;
    model_.force(*u_, zero_, t_, r, st);
    double norm = 0.0;
    for (Index i = 0; i < r.size(); ++i) norm = std::isnan(r[i]) ? r[i] : std::max(norm, std::abs(r[i]));
    return {norm, scale_};
  }
  double residual_roundoff() {
    Vector mag(zero_.size());
    model_.force_magnitude(*u_, zero_, t_, mag);
    return 8.0 * std::numeric_limits<double>::epsilon() * mag.template lpNorm<Eigen::Infinity>();
  }
  IterationMatrix matrix() const { return {0.0, 0.0, 1.0, u_, &zero_, t_}; }
  IterationMatrix start_matrix() const { return matrix(); }
  // mu ~ a squared frequency: a thousandth of the stiffest DOF's, or 1 rad^2/s^2
  // where nothing is stiff yet (a body on open contacts).
  bool regularize(IterationMatrix& im, IterationSystem& ls) const {
    if (im.cM > 0.0) return false;
    const Vector& m = model_.mass().diagonal_entries();
    const Vector k = ls.tangent_diagonal();
    double ratio = 0.0;
    for (Index i = 0; i < m.size(); ++i) ratio = std::max(ratio, std::abs(k[i]) / m[i]);
    im.cM = ratio > 0.0 ? 1e-3 * ratio : 1.0;
    return true;
  }
  template <class LinearSolver>
  Residual incremental_residual(Vector& r, const LinearSolver&) {
    return residual(r);
  }

  ModelT& model_;
  double t_;
  Vector guess_, zero_;
  Vector* u_ = nullptr;
  double scale_ = 0.0;
};

// u with G(u, 0, t) = 0 from the guess; throws ArgumentError naming `initial`
// when Newton does not converge (no equilibrium: a body no spring or contact holds).
template <class ModelT>
Vector static_equilibrium(ModelT& model, double t, const Vector& guess, double rtol = 1e-12, int max_iter = 200) {
  NVIB_CHECK(std::isfinite(t), "t", "must be finite");
  NVIB_CHECK(guess.size() == model.size(), "u_guess",
             "expected " + std::to_string(model.size()) + " entries, got " + std::to_string(guess.size()));
  NVIB_CHECK(guess.allFinite(), "u_guess", "contains NaN or Inf");
  Newton opt;
  opt.rtol = rtol;
  opt.atol = 0.0;
  opt.max_iter = max_iter;
  opt.validate();
  NewtonSolver<IterationSystem> newton(opt, model.size());
  StaticEquilibrium<ModelT> problem(model, t, guess);
  Vector u(model.size());
  Stats st;
  const Status s = problem.solve(newton, u, st);
  NVIB_CHECK(s == Status::success && u.allFinite(), "initial",
             "static_equilibrium did not converge in " + std::to_string(max_iter) +
                 " Newton iterations; a body that no spring or contact holds against a constant load has no "
                 "static equilibrium (was a support left out?) [" + newton.failure().message + "]");
  return u;
}

}  // namespace nvib
