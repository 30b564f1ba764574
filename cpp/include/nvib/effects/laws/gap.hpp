// Compression-only spring that acts once a gap has closed: f = k (d + gap) for d < -gap, else 0
// (pounding between adjacent structures, a bumper; the measure d shortens as the gap closes, as for
// a spring between the two bodies). Stateless and non-smooth: its slope jumps where the gap closes.
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct Gap : LawBase {
  static constexpr const char* key = "gap";
  static constexpr const char* doc = "compression-only spring after a gap closes: f = k (d + gap) for d < -gap, else 0";
  static constexpr std::array<Parameter, 2> parameters{
      {{"k", kRequired, "contact stiffness"}, {"gap", 0.0, "initial opening (>= 0)"}}};
  struct Params {
    double k, gap;
  };
  static void validate(const double* x) {
    NVIB_CHECK(x[0] > 0.0, "k", "must be > 0, got " + detail::fmt(x[0]));
    NVIB_CHECK(x[1] >= 0.0, "gap", "must be >= 0, got " + detail::fmt(x[1]));
  }
  static Params prepare(const double* x, const Signal*) { return {x[0], x[1]}; }
  static double value(const Params& p, double d, double, double) { return d < -p.gap ? p.k * (d + p.gap) : 0.0; }
  static Slopes slopes(const Params& p, double d, double, double) { return {d < -p.gap ? p.k : 0.0, 0.0}; }
  static double potential(const Params& p, double d, double) {
    const double c = d + p.gap;
    return d < -p.gap ? 0.5 * p.k * c * c : 0.0;
  }
  // The gap closes and opens where d + gap crosses 0 (the slope jumps from 0 to k).
  static double event(const Params& p, const NoState&, double d, double, double) { return d + p.gap; }
  static bool is_linear(const Params&) { return false; }
};

}  // namespace effects
}  // namespace nvib
