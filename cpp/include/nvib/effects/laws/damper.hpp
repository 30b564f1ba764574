// Linear (viscous) damper f = c d'.
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct Damper : LawBase {
  static constexpr const char* key = "damper";
  static constexpr const char* doc = "linear damper f = c d'";
  static constexpr bool uses_displacement = false, uses_velocity = true, assembled = true;
  static constexpr std::array<Parameter, 1> parameters{{{"c", kRequired, "damping coefficient"}}};
  struct Params {
    double c;
  };
  static Params prepare(const double* x, const Signal*) { return {x[0]}; }
  static double value(const Params& p, double, double dd, double) { return p.c * dd; }
  static Slopes slopes(const Params& p, double, double, double) { return {0.0, p.c}; }
};

}  // namespace effects
}  // namespace nvib
