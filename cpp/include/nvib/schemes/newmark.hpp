// Newmark's method (Newmark 1959) with Newton iteration, modified Newton, or
// the incremental format without equilibrium iteration. It is generalized-alpha
// with alpha_m = alpha_f = 0 and runs on the same stepper.
#pragma once

#include <string>

#include "generalized_alpha.hpp"

namespace nvib {

struct Newmark {
  double beta = 0.25, gamma = 0.5;
  Iteration iteration = Iteration::newton;
  NewtonOptions newton{};

  explicit Newmark(double b = 0.25, double g = 0.5, Iteration it = Iteration::newton, NewtonOptions nw = {})
      : beta(b), gamma(g), iteration(it), newton(nw) {
    as_generalized_alpha();  // validates
  }
  GeneralizedAlpha as_generalized_alpha() const {
    detail::require(std::isfinite(beta) && beta > 0.0 && beta <= 1.0,
                    "beta: Newmark needs 0 < beta <= 1 (beta = 0 is explicit; use CentralDifference), got " +
                        detail::fmt(beta));
    detail::require(std::isfinite(gamma) && gamma >= 0.5 && gamma <= 1.5,
                    "gamma: Newmark needs 1/2 <= gamma <= 3/2 (gamma < 1/2 amplifies the response), got " +
                        detail::fmt(gamma));
    // Newmark is also used conditionally stable (beta < 1/4, e.g. linear acceleration);
    // build the generalized-alpha parameters without its unconditional-stability check.
    GeneralizedAlpha ga;  // valid defaults
    ga.alpha_m = 0.0;
    ga.alpha_f = 0.0;
    ga.beta = beta;
    ga.gamma = gamma;
    ga.iteration = iteration;
    ga.newton = newton;
    ga.newton.validate();
    return ga;
  }
  int order() const { return std::abs(gamma - 0.5) < 1e-12 ? 2 : 1; }
  static bool is_explicit() { return false; }
  std::string name() const {
    return "Newmark(beta=" + detail::fmt(beta) + ", gamma=" + detail::fmt(gamma) + ", iteration=" +
           to_string(iteration) + ")";
  }
};

template <class ModelT>
struct stepper_for<Newmark, ModelT> {
  struct type : GeneralizedAlphaStepper<ModelT> {
    type(const Newmark& scheme, ModelT model, double h)
        : GeneralizedAlphaStepper<ModelT>(scheme.as_generalized_alpha(), std::move(model), h) {}
  };
};

}  // namespace nvib
