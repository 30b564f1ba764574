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
// counters and failure reports. The linear solver is a policy (dense LU here).
#pragma once

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "../linalg/linear_solvers.hpp"
#include "interrupt.hpp"
#include "parameters.hpp"
#include "types.hpp"

namespace nvib {

// newton:        tangent and factorisation every iteration;
// modified:      tangent once per step, at the predictor;
// initial:       tangent once per run, at the initial state (OpenSees' ModifiedNewton -initial);
// incremental:   the textbook incremental format (Chopra, Dynamics of Structures,
//                section 5.7): tangent at the start of the step, the step's force
//                increment linearised with it, no equilibrium iteration; the
//                equilibrium error of earlier steps is carried, never corrected,
//                so it is first order on nonlinear models;
// one_iteration: one Newton iteration on the full residual from the predictor,
//                then accept. Unlike the incremental format it starts from the
//                full residual, so earlier equilibrium errors are corrected.
// The last two accept every step; the residual they leave is measured (one
// more force evaluation per step) and reported, never enforced.
enum class NewtonMode { newton, modified, initial, incremental, one_iteration };
enum class Jacobian { analytic, finite_difference };


inline const char* to_string(NewtonMode m) {
  switch (m) {
    case NewtonMode::newton: return "newton";
    case NewtonMode::modified: return "modified";
    case NewtonMode::initial: return "initial";
    case NewtonMode::incremental: return "incremental";
    case NewtonMode::one_iteration: return "one_iteration";
  }
  return "?";
}
inline const char* to_string(Jacobian j) { return j == Jacobian::analytic ? "analytic" : "finite_difference"; }


// Options of the iteration: one validated object.
struct Newton {
  static constexpr const char* name = "Newton";
  static constexpr const char* doc =
      "Options of the Newton iteration of the implicit schemes: mode ('newton', 'modified', 'initial', "
      "'incremental' or 'one_iteration'), max_iter, rtol (relative to the force scale of the step), atol "
      "(force units), jacobian ('analytic' or 'finite_difference') and linear_solver ('auto', 'dense' or "
      "'sparse'; Stats.linear_solver says which was used).";
  NewtonMode mode = NewtonMode::newton;
  int max_iter = 20;
  double rtol = 1e-10;  // relative to the force scale of the step
  double atol = 1e-12;  // absolute, in force units
  Jacobian jacobian = Jacobian::analytic;
  LinearSolverChoice linear_solver = LinearSolverChoice::automatic;

  template <class Self, class V>
  static void parameters(Self& s, V&& v) {
    v(s.mode, param::choice("mode", "equilibrium iteration", {"newton", "modified", "initial", "incremental",
                                                                "one_iteration"}));
    v(s.max_iter, param::integer("max_iter", "iterations allowed per step").range(1, 1000));
    v(s.rtol, param::real("rtol", "residual tolerance relative to the force scale of the step").at_least(0.0));
    v(s.atol, param::real("atol", "absolute residual tolerance, in force units").at_least(0.0));
    v(s.jacobian, param::choice("jacobian", "how the tangent is obtained", {"analytic", "finite_difference"}));
    v(s.linear_solver, param::choice("linear_solver", "dense LU, sparse LDLT/LU, or chosen by size and density",
                                     {"auto", "dense", "sparse"}));
  }
  void validate() const {
    param::check_ranges(*this);
    NVIB_CHECK(rtol > 0.0 || atol > 0.0, "rtol, atol", "at least one tolerance must be > 0");
  }
  // The modes that accept a step without an equilibrium check.
  bool accepts_unconverged() const { return mode == NewtonMode::incremental || mode == NewtonMode::one_iteration; }
};

struct Residual {
  double norm = 0.0;   // max |r_i| (NaN if some entry is NaN)
  double scale = 0.0;  // the largest inertia or force term: the tolerance is atol + rtol scale
};

template <class LinearSolver = AutoLinearSolver>
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
    failure_ = Failure{};
    p.predict(x);
    p.update(x);
    const bool linear = p.linear();
    if (!linear && opt_.mode == NewtonMode::incremental) return incremental(p, model, x, t, step, st);
    bool du_small = false;
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
      // A negligible increment that no longer lowers the residual: the iterate
      // is as good as working precision allows only if the residual is within
      // the round-off of its own evaluation; otherwise Newton has stalled.
      if (k > 0 && du_small && res.norm >= residuals_[static_cast<size_t>(k) - 1]) {
        if (res.norm <= tol + roundoff(p)) {
          accepted_ = relative(res);
          return Status::success;
        }
        return stalled(t, step, tol);
      }
      if (k >= opt_.max_iter) return not_converged(t, step, tol);

      bool refactor = false;
      if (linear) {
        refactor = !factorized_;
      } else {
        switch (opt_.mode) {
          case NewtonMode::newton: refactor = true; break;
          case NewtonMode::modified:
          case NewtonMode::one_iteration: refactor = k == 0; break;
          case NewtonMode::initial: refactor = !factorized_; break;
          case NewtonMode::incremental: break;  // handled above
        }
      }
      if (refactor) {
        const IterationMatrix im = opt_.mode == NewtonMode::initial && !linear ? p.start_matrix() : p.matrix();
        const Status s = factorize(p, model, im, t, step, st);
        if (s != Status::success) return s;
      }
      iterate(p, x, st);
      du_small = du_.template lpNorm<Eigen::Infinity>() <=
                 opt_.atol + 1e-3 * opt_.rtol * x.template lpNorm<Eigen::Infinity>();
      if (linear) return Status::success;  // in equilibrium after one solve, up to round-off
      if (opt_.mode == NewtonMode::one_iteration) return accept_unchecked(p, t, step);
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
    iterate(p, x, st);
    return accept_unchecked(p, t, step);
  }

  // x += -S^{-1} r, then the kinematics: by increments where the problem can
  // (their round-off is relative to the kinematics, not to the large terms
  // that cancel when they are recomputed from x), else from x.
  template <class Problem>
  void iterate(Problem& p, Vector& x, Stats& st) {
    du_ = -r_;
    ls_.solve_in_place(du_);
    ++st.num_linear_solves;
    ++st.num_newton_iters;
    x += du_;
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
    poll_interrupt();  // a large model's factorisation can take a second
    const bool regular = ls_.factorize(model, im, st, opt_.jacobian == Jacobian::finite_difference, opt_.linear_solver);
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
};

}  // namespace nvib
