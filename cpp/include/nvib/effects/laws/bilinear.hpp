// Bilinear hysteresis with kinematic hardening: an elastic spring k in series with a slider of
// strength fy, the slider's back force growing as H dp with its slip dp (b = 0: elastic-perfectly
// plastic). The return mapping and its consistent tangent are those of one-dimensional rate-
// independent plasticity with linear kinematic hardening (Simo & Hughes 1998, Computational
// Inelasticity, Springer, sections 1.2-1.4, boxes 1.4 and 1.5); the post-yield stiffness is
// b k, so H = b k / (1 - b). OpenSees' ElasticPP (b = 0) and Steel01 without isotropic hardening
// (a1 = a3 = 0) are this law.
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct Bilinear : LawBase {
  static constexpr const char* key = "bilinear";
  static constexpr const char* doc = "bilinear hysteresis, kinematic hardening: stiffness k, yield force fy, post-yield stiffness b k";
  static constexpr const char* source = "Simo & Hughes 1998, Computational Inelasticity, sections 1.2-1.4";
  static constexpr std::array<Parameter, 3> parameters{{{"k", kRequired, "elastic stiffness"},
                                                        {"fy", kRequired, "yield force"},
                                                        {"b", 0.0, "post-yield stiffness ratio, 0 <= b < 1"}}};
  struct Params {
    double k, fy, H, kt;  // kt = k H / (k + H) = b k: the slope while yielding
  };
  struct State {
    double dp;          // slip of the slider (plastic deformation)
    double dissipated;  // energy dissipated: fy times the accumulated |slip|
    double d;           // the deformation it was committed at
  };
  static constexpr std::array<const char*, 3> state_names{{"plastic_deformation", "dissipated", "deformation"}};

  static void validate(const double* x) {
    NVIB_CHECK(x[0] > 0.0, "k", "must be > 0, got " + detail::fmt(x[0]));
    NVIB_CHECK(x[1] > 0.0, "fy", "must be > 0, got " + detail::fmt(x[1]));
    NVIB_CHECK(x[2] >= 0.0 && x[2] < 1.0, "b", "needs 0 <= b < 1 (b = 1 is a linear spring), got " + detail::fmt(x[2]));
  }
  static Params prepare(const double* x, const Signal*) {
    const double k = x[0], H = x[2] * x[0] / (1.0 - x[2]);
    return {k, x[1], H, k * H / (k + H)};
  }

  // Elastic trial, then the closest-point return to |f - H dp| <= fy (exact for one increment). At the
  // committed deformation itself, on the yield surface (where a step that yielded ends), the slope is the
  // loading one, b k: the tangent a step that goes on loading sees, as OpenSees' Steel01 returns its
  // committed tangent there.
  static Trial<State> trial(const Params& p, const State& c, double d, double, double) {
    Trial<State> r{p.k * (d - c.dp), p.k, 0.0, {c.dp, c.dissipated, d}};  // the elastic trial
    const double xi = r.f - p.H * c.dp;  // the force on the slider
    const double excess = std::abs(xi) - p.fy;
    if (d == c.d) {
      if (excess >= -1e-9 * p.fy) r.kd = p.kt;
    } else if (excess > 0.0) {
      const double slip = excess / (p.k + p.H);  // |increment of dp|
      const double s = xi > 0.0 ? 1.0 : -1.0;
      r.f -= p.k * slip * s;
      r.kd = p.kt;
      r.state.dp += s * slip;
      r.state.dissipated += p.fy * slip;
    }
    return r;
  }
  // The yield point: the elastic trial's margin to the yield surface, fy - |k (d - dp) - H dp|, over fy
  // (positive inside, 0 on it). Reversal from yielding needs no event: the slope changes where d' = 0, so
  // the force stays smooth in time.
  static double event(const Params& p, const State& c, double d, double, double) {
    return (p.fy - std::abs(p.k * (d - c.dp) - p.H * c.dp)) / p.fy;
  }
  // The spring's energy and the back spring's (given back by a reversed slip).
  static double recoverable(const Params& p, const State& s, double d) {
    const double e = d - s.dp;
    return 0.5 * p.k * e * e + 0.5 * p.H * s.dp * s.dp;
  }
  static double dissipated(const Params&, const State& s) { return s.dissipated; }
  static bool is_linear(const Params&) { return false; }
};

}  // namespace effects
}  // namespace nvib
