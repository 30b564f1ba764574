// Unilateral Hertz contact f = n (max(d - r(t), 0) / G)^{3/2}: n identical contacts (two wheels on a
// wheelset), G the contact constant, r(t) an optional irregularity (the paper's vehicle, section 5.2).
#pragma once

#include "../law.hpp"

namespace nvib {
namespace effects {

struct HertzContact : LawBase {
  static constexpr const char* key = "hertz_contact";
  static constexpr const char* doc = "Hertz contact f = contacts (max(d - r(t), 0) / G)^(3/2)";
  static constexpr std::array<Parameter, 2> parameters{
      {{"G", kRequired, "contact constant [units / force^(2/3)]"}, {"contacts", 1.0, "identical contacts"}}};
  static constexpr const char* signal = "irregularity";
  struct Params {
    double G, contacts;
    const Signal* r;  // the irregularity, or nullptr
  };
  static void validate(const double* x) {
    NVIB_CHECK(x[0] > 0.0, "G", "must be > 0, got " + detail::fmt(x[0]));
    NVIB_CHECK(x[1] > 0.0, "contacts", "must be > 0, got " + detail::fmt(x[1]));
  }
  static Params prepare(const double* x, const Signal* s) { return {x[0], x[1], s}; }
  static double compression(const Params& p, double d, double t) { return p.r ? d - p.r->value(t) : d; }
  static double value(const Params& p, double d, double, double t) {
    const double delta = compression(p, d, t);
    return delta > 0.0 ? p.contacts * std::pow(delta / p.G, 1.5) : 0.0;
  }
  static Slopes slopes(const Params& p, double d, double, double t) {
    const double delta = compression(p, d, t);
    return {delta > 0.0 ? 1.5 * p.contacts / p.G * std::sqrt(delta / p.G) : 0.0, 0.0};
  }
  static double potential(const Params& p, double d, double t) {
    const double delta = compression(p, d, t);
    return delta > 0.0 ? p.contacts * p.G * std::pow(delta / p.G, 2.5) / 2.5 : 0.0;
  }
  // A moving rail: the contact potential V(d - r(t)) changes at the rate -f r'(t).
  static double input_power(const Params& p, double d, double dd, double t, int side) {
    return p.r ? -value(p, d, dd, t) * p.r->derivative(t, side) : 0.0;
  }
  // The contact opens and closes where the compression d - r(t) crosses 0 (the force's second derivative is
  // unbounded there).
  static double event(const Params& p, const NoState&, double d, double, double t) { return compression(p, d, t); }
  static bool is_linear(const Params&) { return false; }
  static bool uses_time(const Params& p) { return p.r != nullptr; }
};

}  // namespace effects
}  // namespace nvib
