// Cubic spring f = k3 d^3.
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct CubicSpring : LawBase {
  static constexpr const char* key = "cubic_spring";
  static constexpr const char* doc = "cubic spring f = k3 d^3";
  static constexpr std::array<Parameter, 1> parameters{{{"k3", kRequired, "cubic coefficient"}}};
  struct Params {
    double k3;
  };
  static Params prepare(const double* x, const Signal*) { return {x[0]}; }
  static double value(const Params& p, double d, double, double) { return p.k3 * d * d * d; }
  static Slopes slopes(const Params& p, double d, double, double) { return {3.0 * p.k3 * d * d, 0.0}; }
  static double potential(const Params& p, double d, double) { return 0.25 * p.k3 * d * d * d * d; }
  static bool is_linear(const Params&) { return false; }
};

}  // namespace effects
}  // namespace nvib
