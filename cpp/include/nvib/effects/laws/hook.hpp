// Tension-only spring that acts once its slack is taken up: f = k (d - slack) for d > slack, else 0
// (a restrainer cable, a hook). Stateless and non-smooth: its slope jumps where it engages.
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct Hook : LawBase {
  static constexpr const char* key = "hook";
  static constexpr const char* doc = "tension-only spring after its slack: f = k (d - slack) for d > slack, else 0";
  static constexpr std::array<Parameter, 2> parameters{
      {{"k", kRequired, "stiffness once engaged"}, {"slack", 0.0, "free extension before it engages (>= 0)"}}};
  struct Params {
    double k, slack;
  };
  static void validate(const double* x) {
    NVIB_CHECK(x[0] > 0.0, "k", "must be > 0, got " + detail::fmt(x[0]));
    NVIB_CHECK(x[1] >= 0.0, "slack", "must be >= 0, got " + detail::fmt(x[1]));
  }
  static Params prepare(const double* x, const Signal*) { return {x[0], x[1]}; }
  static double value(const Params& p, double d, double, double) { return d > p.slack ? p.k * (d - p.slack) : 0.0; }
  static Slopes slopes(const Params& p, double d, double, double) { return {d > p.slack ? p.k : 0.0, 0.0}; }
  static double potential(const Params& p, double d, double) {
    const double e = d - p.slack;
    return d > p.slack ? 0.5 * p.k * e * e : 0.0;
  }
  // The slack is taken up and given back where d - slack crosses 0 (the slope jumps from 0 to k).
  static double event(const Params& p, const NoState&, double d, double, double) { return d - p.slack; }
  static bool is_linear(const Params&) { return false; }
};

}  // namespace effects
}  // namespace nvib
