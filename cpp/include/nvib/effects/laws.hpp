// The built-in laws: each a scalar force f(d, d', t) on a measure d = g . u
// (loads: -P(t) along g), written once as one struct that declares its
// parameters (names and defaults), its flags, its value, derivatives,
// potential and powers. EffectSet, Effect and the binding read these.
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <tuple>
#include <type_traits>
#include <utility>

#include "../base/errors.hpp"
#include "signal.hpp"

namespace nvib {
namespace effects {

// Runtime tag of a law; the order is the evaluation order of EffectSet's groups.
enum class Law {
  spring, damper, hardening_spring, cubic_spring, power_damper, pendulum_gravity, hertz_contact,
  constant_force, harmonic_force, ground_acceleration,
};

// A declared parameter: its name and default (kRequired: none).
struct LawParameter {
  const char* name;
  double fallback;
};
constexpr double kRequired = std::numeric_limits<double>::quiet_NaN();

// A law's parameters as it evaluates them (derived from the declared ones) and its signal.
struct LawParams {
  double p0 = 0.0, p1 = 0.0, p2 = 0.0;
  const Signal* signal = nullptr;  // a_g(t) for ground_acceleration, r(t) for hertz_contact (may be absent)
};

// What a law does not declare: no stiffness, no damping, no potential, linear,
// independent of time, every finite parameter valid.
struct LawBase {
  static constexpr bool uses_velocity = false, is_load = false;
  static constexpr const char* signal = nullptr;  // name of its signal parameter
  static constexpr bool signal_required = false;
  static double stiffness(const LawParams&, double, double) { return 0.0; }  // df/dd
  static double damping(const LawParams&, double) { return 0.0; }           // df/dd'
  static double potential(const LawParams&, double, double) { return 0.0; }
  static bool is_linear(const LawParams&) { return true; }
  static bool uses_time(const LawParams&) { return false; }
  static void validate(const double*) {}
};

struct Spring : LawBase {
  static constexpr Law id = Law::spring;
  static constexpr const char* doc = "linear spring f = k d";
  static constexpr std::array<LawParameter, 1> parameters{{{"k", kRequired}}};
  static LawParams prepare(const double* x) { return {x[0]}; }
  static double value(const LawParams& p, double d, double, double) { return p.p0 * d; }
  static double stiffness(const LawParams& p, double, double) { return p.p0; }
  static double potential(const LawParams& p, double d, double) { return 0.5 * p.p0 * d * d; }
};

struct Damper : LawBase {
  static constexpr Law id = Law::damper;
  static constexpr const char* doc = "linear damper f = c d'";
  static constexpr bool uses_velocity = true;
  static constexpr std::array<LawParameter, 1> parameters{{{"c", kRequired}}};
  static LawParams prepare(const double* x) { return {x[0]}; }
  static double value(const LawParams& p, double, double dd, double) { return p.p0 * dd; }
  static double damping(const LawParams& p, double) { return p.p0; }
};

struct HardeningSpring : LawBase {
  static constexpr Law id = Law::hardening_spring;
  static constexpr const char* doc = "hardening spring f = k0 (1 + a d^2) d";
  static constexpr std::array<LawParameter, 2> parameters{{{"k0", kRequired}, {"a", kRequired}}};
  static LawParams prepare(const double* x) { return {x[0], x[1]}; }
  static double value(const LawParams& p, double d, double, double) { return p.p0 * (1.0 + p.p1 * d * d) * d; }
  static double stiffness(const LawParams& p, double d, double) { return p.p0 * (1.0 + 3.0 * p.p1 * d * d); }
  static double potential(const LawParams& p, double d, double) {
    return p.p0 * (0.5 * d * d + 0.25 * p.p1 * d * d * d * d);
  }
  static bool is_linear(const LawParams&) { return false; }
};

struct CubicSpring : LawBase {
  static constexpr Law id = Law::cubic_spring;
  static constexpr const char* doc = "cubic spring f = k3 d^3";
  static constexpr std::array<LawParameter, 1> parameters{{{"k3", kRequired}}};
  static LawParams prepare(const double* x) { return {x[0]}; }
  static double value(const LawParams& p, double d, double, double) { return p.p0 * d * d * d; }
  static double stiffness(const LawParams& p, double d, double) { return 3.0 * p.p0 * d * d; }
  static double potential(const LawParams& p, double d, double) { return 0.25 * p.p0 * d * d * d * d; }
  static bool is_linear(const LawParams&) { return false; }
};

struct PowerDamper : LawBase {
  static constexpr Law id = Law::power_damper;
  static constexpr const char* doc = "power-law damper f = c |d'|^p sign(d')";
  static constexpr bool uses_velocity = true;
  static constexpr std::array<LawParameter, 2> parameters{{{"c", kRequired}, {"p", kRequired}}};
  static void validate(const double* x) { NVIB_CHECK(x[1] > 0.0, "p", "the exponent must be > 0, got " + detail::fmt(x[1])); }
  static LawParams prepare(const double* x) { return {x[0], x[1]}; }
  static double value(const LawParams& p, double, double dd, double) {
    return dd == 0.0 ? 0.0 : std::copysign(p.p0 * std::pow(std::abs(dd), p.p1), dd);
  }
  // At d' = 0 the slope is unbounded for p < 1 and 0 for p > 1; Newton then
  // uses the linear damper's c (p <= 1) or 0.
  static double damping(const LawParams& p, double dd) {
    const double s = std::abs(dd);
    if (s == 0.0) return p.p1 > 1.0 ? 0.0 : p.p0;
    return p.p0 * p.p1 * std::pow(s, p.p1 - 1.0);
  }
  static bool is_linear(const LawParams& p) { return p.p1 == 1.0; }
};

struct PendulumGravity : LawBase {
  static constexpr Law id = Law::pendulum_gravity;
  static constexpr const char* doc = "pendulum under gravity f = m g l sin(d)";
  static constexpr std::array<LawParameter, 3> parameters{{{"m", kRequired}, {"g", kRequired}, {"l", kRequired}}};
  static LawParams prepare(const double* x) { return {x[0] * x[1] * x[2]}; }
  static double value(const LawParams& p, double d, double, double) { return p.p0 * std::sin(d); }
  static double stiffness(const LawParams& p, double d, double) { return p.p0 * std::cos(d); }
  static double potential(const LawParams& p, double d, double) { return p.p0 * (1.0 - std::cos(d)); }
  static bool is_linear(const LawParams&) { return false; }
};

// Unilateral Hertz contact f = n (max(d - r(t), 0) / G)^{3/2}: n identical
// contacts (two wheels on a wheelset), r(t) an optional irregularity.
struct HertzContact : LawBase {
  static constexpr Law id = Law::hertz_contact;
  static constexpr const char* doc = "Hertz contact f = contacts (max(d - r(t), 0) / G)^(3/2)";
  static constexpr std::array<LawParameter, 2> parameters{{{"G", kRequired}, {"contacts", 1.0}}};
  static constexpr const char* signal = "irregularity";
  static void validate(const double* x) {
    NVIB_CHECK(x[0] > 0.0, "G", "must be > 0, got " + detail::fmt(x[0]));
    NVIB_CHECK(x[1] > 0.0, "contacts", "must be > 0, got " + detail::fmt(x[1]));
  }
  static LawParams prepare(const double* x) { return {x[0], x[1]}; }
  static double compression(const LawParams& p, double d, double t) { return p.signal ? d - p.signal->value(t) : d; }
  static double value(const LawParams& p, double d, double, double t) {
    const double delta = compression(p, d, t);
    return delta > 0.0 ? p.p1 * std::pow(delta / p.p0, 1.5) : 0.0;
  }
  static double stiffness(const LawParams& p, double d, double t) {
    const double delta = compression(p, d, t);
    return delta > 0.0 ? 1.5 * p.p1 / p.p0 * std::sqrt(delta / p.p0) : 0.0;
  }
  static double potential(const LawParams& p, double d, double t) {
    const double delta = compression(p, d, t);
    return delta > 0.0 ? p.p1 * p.p0 * std::pow(delta / p.p0, 2.5) / 2.5 : 0.0;
  }
  static bool is_linear(const LawParams&) { return false; }
  static bool uses_time(const LawParams& p) { return p.signal != nullptr; }
};

struct ConstantForce : LawBase {
  static constexpr Law id = Law::constant_force;
  static constexpr const char* doc = "constant load P = value along g";
  static constexpr bool is_load = true;
  static constexpr std::array<LawParameter, 1> parameters{{{"value", kRequired}}};
  static LawParams prepare(const double* x) { return {x[0]}; }
  static double value(const LawParams& p, double, double, double) { return -p.p0; }
};

struct HarmonicForce : LawBase {
  static constexpr Law id = Law::harmonic_force;
  static constexpr const char* doc = "harmonic load P = amplitude sin(omega t + phase) along g";
  static constexpr bool is_load = true;
  static constexpr std::array<LawParameter, 3> parameters{{{"amplitude", kRequired}, {"omega", kRequired},
                                                           {"phase", 0.0}}};
  static LawParams prepare(const double* x) { return {x[0], x[1], x[2]}; }
  static double value(const LawParams& p, double, double, double t) { return -p.p0 * std::sin(p.p1 * t + p.p2); }
  static bool uses_time(const LawParams&) { return true; }
};

// P = -M r a_g(t): the measure's g is r, turned into M r when the effects are built.
struct GroundAcceleration : LawBase {
  static constexpr Law id = Law::ground_acceleration;
  static constexpr const char* doc = "ground acceleration a_g(t): load P = -M r a_g(t), r the measure";
  static constexpr bool is_load = true;
  static constexpr std::array<LawParameter, 0> parameters{};
  static constexpr const char* signal = "signal";
  static constexpr bool signal_required = true;
  static LawParams prepare(const double*) { return {}; }
  static double value(const LawParams& p, double, double, double t) { return p.signal->value(t); }  // g^T f = -P
  static bool uses_time(const LawParams&) { return true; }
};

template <class... L>
struct LawList {
  static constexpr std::size_t size = sizeof...(L);
  // fn(L{}) for the law whose id is `law`: the one runtime switch over laws.
  template <class Fn>
  static decltype(auto) dispatch(Law law, Fn&& fn) {
    using First = std::tuple_element_t<0, std::tuple<L...>>;
    using R = decltype(fn(First{}));
    if constexpr (std::is_void_v<R>) {
      (void)((law == L::id ? (fn(L{}), true) : false) || ...);
    } else {
      R r{};
      (void)((law == L::id ? (r = fn(L{}), true) : false) || ...);
      return r;
    }
  }
  template <class Fn>
  static void for_each(Fn&& fn) {
    (fn(L{}), ...);
  }
};

using AllLaws = LawList<Spring, Damper, HardeningSpring, CubicSpring, PowerDamper, PendulumGravity, HertzContact,
                        ConstantForce, HarmonicForce, GroundAcceleration>;

template <class Fn>
decltype(auto) dispatch(Law law, Fn&& fn) {
  return AllLaws::dispatch(law, std::forward<Fn>(fn));
}

// The law's type name ("hardening_spring").
inline const char* to_string(Law l) {
  static constexpr const char* names[] = {"spring", "damper", "hardening_spring", "cubic_spring", "power_damper",
                                          "pendulum_gravity", "hertz_contact", "constant_force", "harmonic_force",
                                          "ground_acceleration"};
  return names[static_cast<int>(l)];
}

// Derived properties, from the flags alone.
template <class L>
constexpr bool uses_displacement() {
  return !L::uses_velocity && !L::is_load;
}
template <class L>
constexpr bool is_dissipative() {
  return L::uses_velocity;
}
// Power put in from outside: loads (P . v) and a moving rail (the contact
// potential V(d - r(t)) changes at the rate -f r'(t)).
// side: which limit of the signal's rate at a kink (Signal::derivative).
template <class L>
double input_power(const LawParams& p, double d, double dd, double t, int side = 0) {
  if constexpr (L::is_load) return -L::value(p, d, dd, t) * dd;
  if constexpr (L::id == Law::hertz_contact)
    return p.signal ? -L::value(p, d, dd, t) * p.signal->derivative(t, side) : 0.0;
  (void)p, (void)d, (void)dd, (void)t, (void)side;
  return 0.0;
}
template <class L>
double dissipated_power(const LawParams& p, double dd) {
  if constexpr (is_dissipative<L>()) return L::value(p, 0.0, dd, 0.0) * dd;
  (void)p, (void)dd;
  return 0.0;
}

}  // namespace effects
}  // namespace nvib
