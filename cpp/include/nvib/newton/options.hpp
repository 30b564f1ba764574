// The options of the Newton component (one validated object, declared once
// for the binding and the command line): light, so that a scheme's
// declaration need not pull in the solvers.
#pragma once

#include <string>

#include "../base/errors.hpp"
#include "../base/parameters.hpp"

namespace nvib {

// Which linear solver the Newton component uses: automatic (banded LDL^T for a symmetric iteration
// matrix that fits its band, a dense LU for small or nearly full ones, sparse otherwise, and on a
// large linear part with a few nonlinear DOFs the linear part's factors with a low-rank update:
// IterationSystem), or forced.
enum class LinearSolverChoice { automatic, dense, sparse, banded, low_rank };
inline const char* to_string(LinearSolverChoice c) {
  switch (c) {
    case LinearSolverChoice::automatic: return "auto";
    case LinearSolverChoice::dense: return "dense";
    case LinearSolverChoice::sparse: return "sparse";
    case LinearSolverChoice::banded: return "banded";
    case LinearSolverChoice::low_rank: return "low_rank";
  }
  return "?";
}

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
      "Options of the Newton iteration of the implicit schemes: iteration ('newton', 'modified', 'initial', "
      "'incremental' or 'one_iteration'), max_iter, rtol (relative to the force scale of the step), atol "
      "(force units), jacobian ('analytic' or 'finite_difference') and linear_solver ('auto', 'dense', "
      "'sparse', 'banded' or 'low_rank': the linear part factorised once and the effects' tangent applied as "
      "a low-rank update; Stats.linear_solver says which was used).";
  NewtonMode iteration = NewtonMode::newton;  // the equilibrium iteration (its mode)
  int max_iter = 20;
  double rtol = 1e-10;  // relative to the force scale of the step
  double atol = 1e-12;  // absolute, in force units
  Jacobian jacobian = Jacobian::analytic;
  LinearSolverChoice linear_solver = LinearSolverChoice::automatic;

  template <class Self, class V>
  static void parameters(Self& s, V&& v) {
    v(s.iteration, param::choice("iteration", "equilibrium iteration",
                                 {"newton", "modified", "initial", "incremental", "one_iteration"})
                       .renamed_from("mode"));
    v(s.max_iter, param::integer("max_iter", "iterations allowed per step").range(1, 1000));
    v(s.rtol, param::real("rtol", "residual tolerance relative to the force scale of the step").at_least(0.0));
    v(s.atol, param::real("atol", "absolute residual tolerance, in force units").at_least(0.0));
    v(s.jacobian, param::choice("jacobian", "how the tangent is obtained", {"analytic", "finite_difference"}));
    v(s.linear_solver,
      param::choice("linear_solver",
                    "dense LU, sparse LDLT/LU, banded LDLT, low-rank update of the linear part, or chosen by pattern and size",
                    {"auto", "dense", "sparse", "banded", "low_rank"}));
  }
  void validate() const {
    param::check_ranges(*this);
    NVIB_CHECK(rtol > 0.0 || atol > 0.0, "rtol, atol", "at least one tolerance must be > 0");
  }
  // The modes that accept a step without an equilibrium check.
  bool accepts_unconverged() const { return iteration == NewtonMode::incremental || iteration == NewtonMode::one_iteration; }
};

}  // namespace nvib
