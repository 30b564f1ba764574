// Newmark's method (Newmark 1959), the equation of each step solved by the
// Newton component (full Newton, modified, initial tangent, the textbook
// incremental format, or one iteration). It is generalized-alpha with
// alpha_m = alpha_f = 0 and runs on the same stepper.
#pragma once

#include <string>

#include "generalized_alpha.hpp"

namespace nvib {

template <class ModelT>
class NewmarkStepper;

struct Newmark {
  static constexpr const char* name = "Newmark";
  static constexpr const char* key = "newmark";
  static constexpr const char* doc =
      "Newmark's method (1959): the trapezoidal rule by default (beta = 1/4, gamma = 1/2), beta = 1/6 the "
      "linear-acceleration method; each step solved by Newton's method (see Newton).";
  static constexpr bool is_explicit = false;
  double beta = 0.25, gamma = 0.5;
  Newton newton{};

  explicit Newmark(double b = 0.25, double g = 0.5, Newton nw = {}) : beta(b), gamma(g), newton(nw) { validate(); }

  template <class Self, class V>
  static void parameters(Self& s, V&& v) {
    v(s.beta, param::real("beta", "weight of a_{n+1} in the displacement")
                  .above(0.0)
                  .at_most(1.0)
                  .because("beta = 0 is explicit; use CentralDifference"));
    v(s.gamma, param::real("gamma", "weight of a_{n+1} in the velocity")
                   .range(0.5, 1.5)
                   .because("gamma < 1/2 amplifies the response"));
    v(s.newton, param::newton("newton", "options of the Newton iteration"));
  }
  // Newmark is also used conditionally stable (beta < 1/4, e.g. linear
  // acceleration), so generalized-alpha's unconditional-stability check does not apply.
  void validate() const {
    param::check_ranges(*this);
    newton.validate();
  }
  GeneralizedAlpha as_generalized_alpha() const {
    GeneralizedAlpha ga;  // valid defaults, then Newmark's parameters without ga's check
    ga.alpha_m = 0.0;
    ga.alpha_f = 0.0;
    ga.beta = beta;
    ga.gamma = gamma;
    ga.newton = newton;
    return ga;
  }
  std::string label() const {
    if (beta == 0.25 && gamma == 0.5) return "Newmark";
    return "Newmark(" + detail::short_number(beta) + "," + detail::short_number(gamma) + ")";
  }
  // The incremental format is first order on nonlinear models: the
  // linearisation error of each step, O(h^2), is carried and never corrected.
  int order_u() const { return std::abs(gamma - 0.5) < 1e-12 && newton.iteration != NewtonMode::incremental ? 2 : 1; }
  int order_v() const { return order_u(); }
  template <class M>
  using stepper = NewmarkStepper<M>;
};

template <class ModelT>
class NewmarkStepper : public GeneralizedAlphaStepper<ModelT> {
 public:
  NewmarkStepper(const Newmark& scheme, ModelT model, double h)
      : GeneralizedAlphaStepper<ModelT>(scheme.as_generalized_alpha(), std::move(model), h) {}
};

}  // namespace nvib
