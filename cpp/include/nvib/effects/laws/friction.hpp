// Coulomb friction with a stick stiffness: the contact sticks elastically (stiffness k) until the
// force reaches the slip force fs = mu N, then slips at that force (a friction slider, a friction
// wedge, a sliding bearing). Elastic-perfectly plastic in the slip, with the same return mapping as
// the bilinear law with b = 0 (Simo & Hughes 1998, section 1.2); the force level is given as fs, or
// as a friction coefficient mu and a constant normal force N.
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct Friction : LawBase {
  static constexpr const char* key = "friction";
  static constexpr const char* doc = "Coulomb friction with stick stiffness k: slips at fs = mu N";
  static constexpr const char* source = "Simo & Hughes 1998, Computational Inelasticity, section 1.2";
  static constexpr std::array<Parameter, 4> parameters{{{"k", kRequired, "stick stiffness"},
                                                        unset("fs", "slip force (or mu and N)"),
                                                        unset("mu", "friction coefficient (with N)"),
                                                        unset("N", "normal force (with mu)")}};
  struct Params {
    double k, fs;
  };
  struct State {
    double slip;        // accumulated slip (signed)
    double dissipated;  // fs times the accumulated |slip|
    double d;           // the deformation it was committed at
  };
  static constexpr std::array<const char*, 3> state_names{{"slip", "dissipated", "deformation"}};

  static void validate(const double* x) {
    NVIB_CHECK(x[0] > 0.0, "k", "the stick stiffness must be > 0, got " + detail::fmt(x[0]));
    const bool fs = !is_unset(x[1]), mu = !is_unset(x[2]), N = !is_unset(x[3]);
    NVIB_CHECK(fs != (mu || N), fs ? "fs" : "fs, mu, N",
               fs ? "give the slip force fs, or mu and N, not both" : "give the slip force fs, or mu and N");
    if (fs) {
      NVIB_CHECK(x[1] > 0.0, "fs", "must be > 0, got " + detail::fmt(x[1]));
    } else {
      NVIB_CHECK(mu && N, mu ? "N" : "mu", "needed with " + std::string(mu ? "mu" : "N"));
      NVIB_CHECK(x[2] > 0.0, "mu", "must be > 0, got " + detail::fmt(x[2]));
      NVIB_CHECK(x[3] > 0.0, "N", "the normal force must be > 0 (compression), got " + detail::fmt(x[3]));
    }
  }
  static Params prepare(const double* x, const Signal*) { return {x[0], is_unset(x[1]) ? x[2] * x[3] : x[1]}; }

  // At the committed deformation itself, at the slip force (where a step that slipped ends), the slope
  // is 0: the one a step that goes on slipping sees.
  static Trial<State> trial(const Params& p, const State& c, double d, double, double) {
    const double f_trial = p.k * (d - c.slip);
    const double excess = std::abs(f_trial) - p.fs;
    if (d == c.d)
      return {excess > 0.0 ? std::copysign(p.fs, f_trial) : f_trial, excess >= -1e-9 * p.fs ? 0.0 : p.k, 0.0, c};
    if (excess <= 0.0) return {f_trial, p.k, 0.0, {c.slip, c.dissipated, d}};
    const double s = f_trial > 0.0 ? 1.0 : -1.0, slip = excess / p.k;
    return {s * p.fs, 0.0, 0.0, {c.slip + s * slip, c.dissipated + p.fs * slip, d}};
  }
  static double recoverable(const Params& p, const State& s, double d) {
    const double e = d - s.slip;
    return 0.5 * p.k * e * e;
  }
  static double dissipated(const Params&, const State& s) { return s.dissipated; }
  static bool is_linear(const Params&) { return false; }
};

}  // namespace effects
}  // namespace nvib
