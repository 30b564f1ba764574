// Hardening (Duffing) spring f = k0 (1 + a d^2) d: the storeys of the paper's building and its
// hardening oscillator (Yang et al. 2017, sections 4.2 and 5.1).
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct HardeningSpring : LawBase {
  static constexpr const char* key = "hardening_spring";
  static constexpr const char* doc = "hardening spring f = k0 (1 + a d^2) d";
  static constexpr std::array<Parameter, 2> parameters{
      {{"k0", kRequired, "stiffness at d = 0"}, {"a", kRequired, "hardening coefficient [1/units^2]"}}};
  struct Params {
    double k0, a;
  };
  static Params prepare(const double* x, const Signal*) { return {x[0], x[1]}; }
  static double value(const Params& p, double d, double, double) { return p.k0 * (1.0 + p.a * d * d) * d; }
  static Slopes slopes(const Params& p, double d, double, double) { return {p.k0 * (1.0 + 3.0 * p.a * d * d), 0.0}; }
  static double potential(const Params& p, double d, double) { return p.k0 * (0.5 * d * d + 0.25 * p.a * d * d * d * d); }
  static bool is_linear(const Params&) { return false; }
};

}  // namespace effects
}  // namespace nvib
