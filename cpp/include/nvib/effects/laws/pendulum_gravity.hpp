// Gravity on a pendulum, f = m g l sin(d) on its angle d (the paper's pendulum, section 4.1).
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct PendulumGravity : LawBase {
  static constexpr const char* key = "pendulum_gravity";
  static constexpr const char* doc = "pendulum under gravity f = m g l sin(d)";
  static constexpr std::array<Parameter, 3> parameters{
      {{"m", kRequired, "mass"}, {"g", kRequired, "gravity"}, {"l", kRequired, "length"}}};
  struct Params {
    double mgl;
  };
  static Params prepare(const double* x, const Signal*) { return {x[0] * x[1] * x[2]}; }
  static double value(const Params& p, double d, double, double) { return p.mgl * std::sin(d); }
  static Slopes slopes(const Params& p, double d, double, double) { return {p.mgl * std::cos(d), 0.0}; }
  static double potential(const Params& p, double d, double) { return p.mgl * (1.0 - std::cos(d)); }
  static bool is_linear(const Params&) { return false; }
};

}  // namespace effects
}  // namespace nvib
