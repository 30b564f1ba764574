// Newton's method as a component: the implicit schemes (and the static
// equilibrium solve) describe their equation, this solves it.
//
// A problem supplies, for its unknown x (the displacement at the end of a step):
//   void predict(Vector& x)              the predictor
//   void update(const Vector& x)         its kinematics from the unknown (at the predictor)
//   void increment(const Vector& dx)     optional: the kinematics carried by the increment dx of the
//                                        unknown; update(x) is called instead where it is absent
//   Residual residual(Vector& r)         r at the current kinematics, {max |r_i|, force scale}
//   IterationMatrix matrix()             S = cM M + cC C_t + cK K_t, tangents at the current kinematics
//   IterationMatrix start_matrix()       the same with the tangents at the start of the step
//   Residual incremental_residual(Vector& r, const LinearSolver&)   (mode incremental only)
//   bool linear()                        the model is linear: one factorisation per run, one solve per step
//   double residual_roundoff()           optional: the round-off in r at the current iterate
// The component owns the iteration: modes, convergence test, iteration limit,
// counters and failure reports. The linear system (the iteration matrix assembled
// from the model and factorised, system.hpp) is a policy.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "../base/interrupt.hpp"
#include "../base/loops.hpp"
#include "../base/types.hpp"
#include "options.hpp"
#include "system.hpp"

namespace nvib {

struct Residual {
  double norm = 0.0;   // max |r_i| (NaN if some entry is NaN)
  double scale = 0.0;  // the largest inertia or force term: the tolerance is atol + rtol scale
};

template <class LinearSolver = IterationSystem>
class NewtonSolver {
 public:
  NewtonSolver() = default;
  NewtonSolver(const Newton& options, Index n) : opt_(options) {
    opt_.validate();
    ls_.resize(n);
    r_.setZero(n);
    du_.setZero(n);
    residuals_.reserve(static_cast<size_t>(opt_.max_iter) + 2);
  }

  const Newton& options() const { return opt_; }
  LinearSolver& linear_solver() { return ls_; }
  // Residual norms of the last solve (for iteration = incremental or
  // one_iteration: the one before the step and the one it leaves).
  const std::vector<double>& residuals() const { return residuals_; }
  // The accepted residual relative to its force scale (at most about rtol
  // after convergence; what incremental / one_iteration leave); NaN where not
  // evaluated (a linear model, exact after one solve).
  double accepted_residual() const { return accepted_; }
  const Failure& failure() const { return failure_; }
  // Forget the factorisation (a new run).
  void reset() { factorized_ = false; }

  // Solves the problem's equation for x. t and step name the step in failure reports.
  template <class Problem, class ModelT>
  Status solve(Problem& p, ModelT& model, Vector& x, double t, std::int64_t step, Stats& st) {
    residuals_.clear();
    accepted_ = std::numeric_limits<double>::quiet_NaN();
    if (failure_.status != Status::success) failure_ = Failure{};  // (only fail() sets it, status first)
    p.predict(x);
    p.update(x);
    const bool linear = p.linear();
    if (!linear && opt_.iteration == NewtonMode::incremental) return incremental(p, model, x, t, step, st);
    bool du_small = false, du_settled = false;
    for (int k = 0;; ++k) {
      const Residual res = p.residual(r_);
      residuals_.push_back(res.norm);
      if (!std::isfinite(res.norm)) return nonfinite_residual(t, step);
      const double tol = opt_.atol + opt_.rtol * res.scale;
      if (k > 0 && res.norm <= tol) {
        accepted_ = relative(res);
        return Status::success;
      }
      if (k == 0 && res.norm == 0.0) {  // the predictor is in equilibrium to the last bit
        accepted_ = 0.0;
        return Status::success;
      }
      // A residual within the round-off of its own evaluation (8 eps times the magnitudes of the terms
      // that cancel in it, K u among them, not the net force the tolerance is scaled by) is as small as
      // working precision allows once the increment that led to it has settled (below 100 rtol of x, the
      // 1e-8 of u a displacement-increment test uses by default) or the residual no longer falls: then
      // it is accepted, whatever the increment's noise (2e-12 to 1e-11 of u on stiff finite-element
      // models, too much for a test at 1e-13). Evaluated only when the plain test fails.
      const bool falling = k > 0 && res.norm < residuals_[static_cast<size_t>(k) - 1];
      if (k > 0 && (du_settled || !falling) && res.norm <= tol + roundoff(p)) {
        accepted_ = relative(res);
        return Status::success;
      }
      // Beyond that bound, a negligible increment that no longer lowers the residual means Newton has
      // stalled (a tangent that lies).
      if (k > 0 && du_small && !falling) return stalled(t, step, tol);
      if (k >= opt_.max_iter) return not_converged(t, step, tol);

      bool refactor = false;
      if (linear) {
        refactor = !factorized_;
      } else {
        switch (opt_.iteration) {
          case NewtonMode::newton: refactor = true; break;
          case NewtonMode::modified:
          case NewtonMode::one_iteration: refactor = k == 0; break;
          case NewtonMode::initial: refactor = !factorized_; break;
          case NewtonMode::incremental: break;  // handled above
        }
      }
      if (refactor) {
        const IterationMatrix im = opt_.iteration == NewtonMode::initial && !linear ? p.start_matrix() : p.matrix();
        const Status s = factorize(p, model, im, t, step, st);
        if (s != Status::success) return s;
      }
      double du_norm, x_norm;
      iterate(p, x, st, du_norm, x_norm);
      du_small = du_norm <= opt_.atol + 1e-3 * opt_.rtol * x_norm;
      du_settled = du_norm <= opt_.atol + 100.0 * opt_.rtol * x_norm;
      if (linear) return Status::success;  // in equilibrium after one solve, up to round-off
      if (opt_.iteration == NewtonMode::one_iteration) return accept_unchecked(p, t, step);
    }
  }

 private:
  // The textbook incremental format: tangent at the start of the step, one
  // solve of the linearised increment equation, no equilibrium iteration.
  template <class Problem, class ModelT>
  Status incremental(Problem& p, ModelT& model, Vector& x, double t, std::int64_t step, Stats& st) {
    const Status s = factorize(p, model, p.start_matrix(), t, step, st);
    if (s != Status::success) return s;
    const Residual res = p.incremental_residual(r_, ls_);
    residuals_.push_back(res.norm);
    if (!std::isfinite(res.norm)) return nonfinite_residual(t, step);
    double du_norm, x_norm;
    iterate(p, x, st, du_norm, x_norm);
    return accept_unchecked(p, t, step);
  }

  // x += -S^{-1} r, then the kinematics: by increments where the problem can
  // (their round-off is relative to the kinematics, not to the large terms
  // that cancel when they are recomputed from x), else from x. The solve is
  // S^{-1} r in place, negated as it is added: the same bits as solving for -r
  // (every operation of a solve is odd in its right-hand side). Returns the
  // max-norms of the increment and of the new x.
  template <class Problem>
  void iterate(Problem& p, Vector& x, Stats& st, double& du_norm, double& x_norm) {
    ls_.solve_in_place(r_);
    ++st.num_linear_solves;
    ++st.num_newton_iters;
    const double* __restrict r = r_.data();
    double* __restrict du = du_.data();
    double* __restrict xp = x.data();
    double dn = 0.0, xn = 0.0;
    detail::for_each_index(x.size(), [&](Index i) {  // (unrolled up to 8 DOFs)
      const double d = -r[i], xi = xp[i] + d;
      du[i] = d;
      xp[i] = xi;
      dn = std::max(dn, std::abs(d));
      xn = std::max(xn, std::abs(xi));
    });
    du_norm = dn;
    x_norm = xn;
    if constexpr (has_increment<Problem>::value)
      p.increment(du_);
    else
      p.update(x);
  }

  // Accepts the step without an equilibrium check, but not unseen: the
  // residual it leaves is evaluated (one force evaluation) and reported.
  template <class Problem>
  Status accept_unchecked(Problem& p, double t, std::int64_t step) {
    const Residual after = p.residual(r_);
    residuals_.push_back(after.norm);
    if (!std::isfinite(after.norm)) return nonfinite_residual(t, step);
    accepted_ = relative(after);
    return Status::success;
  }

  template <class Problem, class ModelT>
  Status factorize(Problem& p, ModelT& model, const IterationMatrix& im, double t, std::int64_t step, Stats& st) {
    // A large model's factorisation can take a second: poll before it, on a clock. Polling at every one
    // takes the GIL (Python's hook) each step of a small yielding model, which serialises solve_many's threads.
    if (poll_.tick()) poll_interrupt();
    const bool regular = ls_.factorize(model, im, st, opt_.jacobian == Jacobian::finite_difference, opt_.linear_solver);
    if (ls_.reused())
      ++st.num_reused_factorizations;  // an S identical to the last keeps its factors
    else
      ++st.num_factorizations;
    factorized_ = true;
    if (regular) return Status::success;
    // An overflowing force overflows its tangent too: that is divergence, not a singular matrix.
    const Index bad = ls_.first_nonfinite_tangent_row();
    if (bad >= 0) {
      fail(Status::diverged, t, step,
           "diverged at t = " + detail::fmt(t) + " (step " + std::to_string(step) +
               "): the tangent of the forces is not finite at DOF " + std::to_string(bad));
      failure_.dof = bad;
      return Status::diverged;
    }
    if constexpr (has_regularization<Problem>::value) {
      IterationMatrix reg = im;
      if (p.regularize(reg, ls_)) return factorize(p, model, reg, t, step, st);
    }
    return fail(Status::singular_matrix, t, step,
                "singular iteration matrix at t = " + detail::fmt(t) + " (step " + std::to_string(step) + ")");
  }

  // In the units of the relative tolerance: norm <= atol + rtol scale is
  // relative() <= rtol, so a converged step reports at most rtol.
  double relative(const Residual& r) const {
    const double floor = opt_.rtol > 0.0 ? opt_.atol / opt_.rtol : 0.0;
    const double scale = r.scale + floor;
    return scale > 0.0 ? r.norm / scale : r.norm;
  }

  Status fail(Status s, double t, std::int64_t step, std::string message) {
    failure_.status = s;
    failure_.step = step;
    failure_.t = t;
    failure_.message = std::move(message);
    failure_.residuals = residuals_;
    return s;
  }
  // Names the first non-finite residual entry, the time and the step.
  Status nonfinite_residual(double t, std::int64_t step) {
    Index dof = 0;
    while (dof + 1 < r_.size() && std::isfinite(r_[dof])) ++dof;
    fail(Status::diverged, t, step,
         "diverged at t = " + detail::fmt(t) + " (step " + std::to_string(step) +
             "): the equilibrium residual is not finite at DOF " + std::to_string(dof) + " (residual[" +
             std::to_string(dof) + "] = " + detail::fmt(r_[dof]) + ")");
    failure_.dof = dof;
    return Status::diverged;
  }
  Status not_converged(double t, std::int64_t step, double tol) {
    return fail(Status::newton_failed, t, step,
                "Newton did not converge in " + std::to_string(opt_.max_iter) + " iterations at t = " +
                    detail::fmt(t) + " (step " + std::to_string(step) + "; residual " +
                    detail::fmt(residuals_.back()) + " > tolerance " + detail::fmt(tol) + ")");
  }
  Status stalled(double t, std::int64_t step, double tol) {
    return fail(Status::newton_failed, t, step,
                "Newton stalled at t = " + detail::fmt(t) + " (step " + std::to_string(step) +
                    "): the increment is negligible but the residual " + detail::fmt(residuals_.back()) +
                    " stays above the tolerance " + detail::fmt(tol) +
                    " (a wrong tangent, or forces that are not smooth there)");
  }

  // The problem's estimate of the round-off in its residual (0 if it gives none).
  template <class Problem>
  double roundoff(Problem& p) {
    if constexpr (has_roundoff<Problem>::value)
      return p.residual_roundoff();
    else
      return 0.0;
  }

  template <class P, class = void>
  struct has_roundoff : std::false_type {};
  template <class P>
  struct has_roundoff<P, std::void_t<decltype(std::declval<P&>().residual_roundoff())>> : std::true_type {};
  template <class P, class = void>
  struct has_increment : std::false_type {};
  template <class P>
  struct has_increment<P, std::void_t<decltype(std::declval<P&>().increment(std::declval<const Vector&>()))>>
      : std::true_type {};
  template <class P, class = void>
  struct has_regularization : std::false_type {};
  template <class P>
  struct has_regularization<P, std::void_t<decltype(std::declval<P&>().regularize(
                                   std::declval<IterationMatrix&>(), std::declval<LinearSolver&>()))>>
      : std::true_type {};

  Newton opt_;
  LinearSolver ls_;
  Vector r_, du_;
  std::vector<double> residuals_;
  bool factorized_ = false;
  double accepted_ = std::numeric_limits<double>::quiet_NaN();
  Failure failure_;
  ClockPoll poll_;
};

}  // namespace nvib
