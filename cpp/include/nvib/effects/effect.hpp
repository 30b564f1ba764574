// One declared effect: a law on its measure d = g . u, with its parameters,
// and the factories that build and check it.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "../base/types.hpp"
#include "laws.hpp"

namespace nvib {
namespace effects {

using Measure = std::vector<std::pair<Index, double>>;

struct Effect {
  Law law = Law::spring;
  std::string name;                     // optional; scenes use it to switch effects off
  std::vector<Index> index;             // DOFs of the measure
  std::vector<double> coef;             // g entries
  std::vector<double> values;           // the declared parameters, in the law's order
  double p0 = 0.0, p1 = 0.0, p2 = 0.0;  // the law's own parameters (LawParams), derived from values
  Signal signal;                        // a_g(t) for ground_acceleration, r(t) for hertz_contact

  // Computed on demand: a stored pointer to `signal` would dangle in a copy.
  LawParams params() const { return {p0, p1, p2, signal.present() ? &signal : nullptr}; }
  bool uses_velocity() const { return dispatch(law, [](auto L) { return decltype(L)::uses_velocity; }); }
  bool is_load() const { return dispatch(law, [](auto L) { return decltype(L)::is_load; }); }
  bool is_dissipative() const { return uses_velocity(); }
  bool uses_time() const { return dispatch(law, [&](auto L) { return decltype(L)::uses_time(params()); }); }
  // Linear in (u, v) for fixed t, so its tangent is constant.
  bool is_linear() const { return dispatch(law, [&](auto L) { return decltype(L)::is_linear(params()); }); }

  template <class V>
  double measure(const V& x) const {
    double d = 0.0;
    for (size_t i = 0; i < index.size(); ++i) d += coef[i] * x[index[i]];
    return d;
  }
  double value(double d, double dd, double t) const {
    return dispatch(law, [&](auto L) { return decltype(L)::value(params(), d, dd, t); });
  }
  double dvalue_dd(double d, double t) const {
    return dispatch(law, [&](auto L) { return decltype(L)::stiffness(params(), d, t); });
  }
  double dvalue_dv(double dd) const {
    return dispatch(law, [&](auto L) { return decltype(L)::damping(params(), dd); });
  }
  double potential(double d, double t) const {
    return dispatch(law, [&](auto L) { return decltype(L)::potential(params(), d, t); });
  }
};

namespace detail_ {
// Checks and builds an effect from its measure and its declared parameters (all of them, in order).
template <class L>
Effect build(Measure g, const double* x, Signal signal) {
  const std::string who = to_string(L::id);
  Effect e;
  e.law = L::id;
  NVIB_CHECK(!g.empty(), "measure", who + " needs at least one DOF in its measure");
  for (auto& [i, c] : g) {
    NVIB_CHECK(i >= 0, "measure", who + ": negative DOF index " + std::to_string(i));
    NVIB_CHECK(std::isfinite(c), "measure", who + ": non-finite coefficient");
    e.index.push_back(i);
    e.coef.push_back(c);
  }
  for (size_t k = 0; k < L::parameters.size(); ++k)
    NVIB_CHECK(std::isfinite(x[k]), L::parameters[k].name,
               who + " needs a finite " + L::parameters[k].name + ", got " + detail::fmt(x[k]));
  L::validate(x);
  e.values.assign(x, x + L::parameters.size());
  const LawParams p = L::prepare(x);
  e.p0 = p.p0;
  e.p1 = p.p1;
  e.p2 = p.p2;
  if constexpr (L::signal != nullptr) {
    if (L::signal_required) NVIB_CHECK(signal.present(), L::signal, "missing (" + who + " needs it)");
    e.signal = std::move(signal);
  } else {
    NVIB_CHECK(!signal.present(), "signal", who + " takes no signal");
  }
  return e;
}
}  // namespace detail_

// An effect from its parameters given by name; optional ones take their defaults.
inline Effect make_effect(Law law, Measure g, const std::vector<std::pair<std::string, double>>& named,
                          Signal signal = {}, std::string name = "") {
  Effect e = dispatch(law, [&](auto L) {
    using Lw = decltype(L);
    const std::string who = to_string(Lw::id);
    std::array<double, Lw::parameters.size() + 1> x{};
    std::array<bool, Lw::parameters.size() + 1> given{};
    for (const auto& [key, value] : named) {
      size_t k = 0;
      while (k < Lw::parameters.size() && key != Lw::parameters[k].name) ++k;
      if (k == Lw::parameters.size()) {
        std::string known;
        for (const auto& q : Lw::parameters) known += (known.empty() ? "" : ", ") + std::string(q.name);
        detail::throw_argument(key, "unknown parameter of " + who + " (expected " + (known.empty() ? "none" : known) +
                                        ")");
      }
      x[k] = value;
      given[k] = true;
    }
    for (size_t k = 0; k < Lw::parameters.size(); ++k) {
      const LawParameter& q = Lw::parameters[k];
      NVIB_CHECK(given[k] || !std::isnan(q.fallback), q.name, "missing parameter of " + who);
      if (!given[k]) x[k] = q.fallback;
    }
    return detail_::build<Lw>(std::move(g), x.data(), std::move(signal));
  });
  e.name = std::move(name);
  return e;
}

// The declared parameters in order (C++ convenience).
inline Effect make_effect_values(Law law, Measure g, std::vector<double> values, Signal signal = {}) {
  return dispatch(law, [&](auto L) {
    using Lw = decltype(L);
    NVIB_CHECK(values.size() == Lw::parameters.size(), to_string(Lw::id),
               "expected " + std::to_string(Lw::parameters.size()) + " parameters, got " + std::to_string(values.size()));
    values.push_back(0.0);  // a valid pointer when there are none
    return detail_::build<Lw>(std::move(g), values.data(), std::move(signal));
  });
}

inline Effect spring(Measure g, double k) { return make_effect_values(Law::spring, std::move(g), {k}); }
inline Effect damper(Measure g, double c) { return make_effect_values(Law::damper, std::move(g), {c}); }
inline Effect hardening_spring(Measure g, double k0, double a) {
  return make_effect_values(Law::hardening_spring, std::move(g), {k0, a});
}
inline Effect cubic_spring(Measure g, double k3) { return make_effect_values(Law::cubic_spring, std::move(g), {k3}); }
inline Effect power_damper(Measure g, double c, double p) { return make_effect_values(Law::power_damper, std::move(g), {c, p}); }
// mgl: the product m g l.
inline Effect pendulum_gravity(Measure g, double mgl) {
  return make_effect_values(Law::pendulum_gravity, std::move(g), {mgl, 1.0, 1.0});
}
// contacts: how many identical contacts act on the measure (2 wheels on a wheelset).
inline Effect hertz_contact(Measure g, double G, double contacts = 1.0, Signal irregularity = {}) {
  return make_effect_values(Law::hertz_contact, std::move(g), {G, contacts}, std::move(irregularity));
}
inline Effect constant_force(Measure g, double value) { return make_effect_values(Law::constant_force, std::move(g), {value}); }
inline Effect harmonic_force(Measure g, double amplitude, double omega, double phase = 0.0) {
  return make_effect_values(Law::harmonic_force, std::move(g), {amplitude, omega, phase});
}
// r: the influence coefficients (1 on every DOF that moves with the ground).
inline Effect ground_acceleration(Measure r, Signal a_g) {
  return make_effect_values(Law::ground_acceleration, std::move(r), {}, std::move(a_g));
}

}  // namespace effects
}  // namespace nvib
