// Options of the equilibrium iteration used by the implicit schemes.
#pragma once

#include <string>

#include "types.hpp"

namespace nvib {

// newton: full Newton-Raphson (tangent every iteration);
// modified: tangent and factorisation once per step;
// none: the incremental format (what Yang et al. 2017 use, section 6): one
//       linearised solve per step, and the step is accepted without an
//       equilibrium check. The residual it leaves is evaluated (one more force
//       evaluation per step) and reported, never enforced: see
//       last_residuals() and Result::max_residual.
enum class Iteration { newton, modified, none };
enum class Jacobian { analytic, finite_difference };

inline const char* to_string(Iteration it) {
  switch (it) {
    case Iteration::newton: return "newton";
    case Iteration::modified: return "modified";
    case Iteration::none: return "none";
  }
  return "?";
}

struct NewtonOptions {
  int max_iter = 20;
  double rtol = 1e-10;  // relative to the force scale of the step
  double atol = 1e-12;  // absolute, in force units
  Jacobian jacobian = Jacobian::analytic;

  void validate() const {
    detail::require(max_iter >= 1 && max_iter <= 1000, "max_iter: needs 1 <= max_iter <= 1000, got " + std::to_string(max_iter));
    detail::require(std::isfinite(rtol) && rtol >= 0.0, "rtol: needs a finite rtol >= 0, got " + detail::fmt(rtol));
    detail::require(std::isfinite(atol) && atol >= 0.0, "atol: needs a finite atol >= 0, got " + detail::fmt(atol));
    detail::require(rtol > 0.0 || atol > 0.0, "rtol, atol: at least one tolerance must be > 0");
  }
};

}  // namespace nvib
