// Power-law damper f = c |d'|^p sign(d') (fluid viscous dampers, p typically 0.2 to 1).
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct PowerDamper : LawBase {
  static constexpr const char* key = "power_damper";
  static constexpr const char* doc = "power-law damper f = c |d'|^p sign(d')";
  static constexpr bool uses_displacement = false, uses_velocity = true;
  static constexpr std::array<Parameter, 2> parameters{{{"c", kRequired, "coefficient"}, {"p", kRequired, "exponent"}}};
  struct Params {
    double c, p;
  };
  static void validate(const double* x) { NVIB_CHECK(x[1] > 0.0, "p", "the exponent must be > 0, got " + detail::fmt(x[1])); }
  static Params prepare(const double* x, const Signal*) { return {x[0], x[1]}; }
  static double value(const Params& p, double, double dd, double) {
    return dd == 0.0 ? 0.0 : std::copysign(p.c * std::pow(std::abs(dd), p.p), dd);
  }
  // At d' = 0 the slope is unbounded for p < 1 and 0 for p > 1; Newton then uses the linear damper's
  // c (p <= 1) or 0.
  static Slopes slopes(const Params& p, double, double dd, double) {
    const double s = std::abs(dd);
    if (s == 0.0) return {0.0, p.p > 1.0 ? 0.0 : p.c};
    return {0.0, p.c * p.p * std::pow(s, p.p - 1.0)};
  }
  static bool is_linear(const Params& p) { return p.p == 1.0; }
};

}  // namespace effects
}  // namespace nvib
