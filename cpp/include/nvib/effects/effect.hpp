// Declared effects: one law on one measure d = g . u (Effect), or many effects of one law at once,
// d_k = u_{i_k} - u_{j_k} with j_k < 0 the ground (EffectArray: about 8 bytes per effect plus its
// own parameter values; 10^6 springs build in well under a second, where one Effect each would
// not). Both are checked by one parser of the law's declared parameters (parse_parameters), each
// parameter one value, or for an array one value or one per effect.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "../base/types.hpp"
#include "laws/all.hpp"

namespace nvib {
namespace effects {

using Measure = std::vector<std::pair<Index, double>>;

template <class Fn>
decltype(auto) dispatch(LawId law, Fn&& fn) {
  return AllLaws::dispatch(law, std::forward<Fn>(fn));
}
inline const char* key_of(LawId law) { return AllLaws::key(law); }
// The tag of the law with this key; an ArgumentError naming `argument` if there is none.
inline LawId law_of(const std::string& key, const std::string& argument = "type") {
  const LawId id = AllLaws::find(key);
  if (id < 0) {
    std::string known;
    AllLaws::for_each([&](auto L) { known += (known.empty() ? "" : ", ") + std::string(decltype(L)::key); });
    detail::throw_argument(argument, "unknown effect type '" + key + "' (known: " + known + ")");
  }
  return id;
}
template <class L>
constexpr LawId law_id() {
  return AllLaws::id<L>();
}

struct Effect {
  LawId law = 0;
  std::string name;              // optional; scenes use it to switch effects off and to record them
  std::vector<Index> index;      // DOFs of the measure
  std::vector<double> coef;      // g entries
  std::vector<double> values;    // the declared parameters, in the law's order (NaN: left unset)
  Signal signal;                 // a_g(t) for ground_acceleration, r(t) for hertz_contact

  const char* key() const { return key_of(law); }
  bool uses_displacement() const { return dispatch(law, [](auto L) { return decltype(L)::uses_displacement; }); }
  bool uses_velocity() const { return dispatch(law, [](auto L) { return decltype(L)::uses_velocity; }); }
  bool is_load() const { return dispatch(law, [](auto L) { return decltype(L)::is_load; }); }
  bool has_state() const { return dispatch(law, [](auto L) { return law::has_state<decltype(L)>; }); }
  bool uses_time() const {
    return dispatch(law, [&](auto L) { return decltype(L)::uses_time(params<decltype(L)>()); });
  }
  // Linear in (u, v) for fixed t, so its tangent is constant (a law with memory never is).
  bool is_linear() const {
    return dispatch(law, [&](auto L) {
      using Lw = decltype(L);
      return !law::has_state<Lw> && Lw::is_linear(params<Lw>());
    });
  }

  template <class V>
  double measure(const V& x) const {
    double d = 0.0;
    for (size_t i = 0; i < index.size(); ++i) d += coef[i] * x[index[i]];
    return d;
  }
  // The law at (d, d', t), from its initial state for a law with memory.
  double value(double d, double dd, double t) const {
    return dispatch(law, [&](auto L) {
      using Lw = decltype(L);
      const auto p = params<Lw>();
      return law::force<Lw>(p, law::initial<Lw>(p), d, dd, t);
    });
  }
  Slopes slopes(double d, double dd, double t) const {
    return dispatch(law, [&](auto L) {
      using Lw = decltype(L);
      const auto p = params<Lw>();
      return law::slopes<Lw>(p, law::initial<Lw>(p), d, dd, t);
    });
  }

  // The law's own parameters, pointing to this effect's signal (computed on demand: a stored pointer
  // would dangle in a copy).
  template <class L>
  typename L::Params params() const {
    return L::prepare(values.data(), signal.present() ? &signal : nullptr);
  }
};

struct EffectArray {
  LawId law = 0;
  std::string name;
  std::vector<std::int32_t> i, j;           // the measures' DOFs (j < 0: the ground)
  std::vector<std::vector<double>> values;  // per declared parameter: one value, or one per effect
  Signal signal;                            // shared by every effect (hertz_contact's irregularity)

  const char* key() const { return key_of(law); }
  size_t size() const { return i.size(); }
  double value(size_t parameter, size_t k) const {
    const std::vector<double>& v = values[parameter];
    return v.size() == 1 ? v[0] : v[k];
  }
  bool varying() const {
    for (const auto& v : values)
      if (v.size() > 1) return true;
    return false;
  }
  // The law's own parameters of effect k, pointing to `s` (the caller's copy of the signal, or nullptr).
  template <class L>
  typename L::Params params(size_t k, const Signal* s) const {
    std::array<double, L::parameters.size() + 1> x{};
    for (size_t p = 0; p < L::parameters.size(); ++p) x[p] = value(p, k);
    return L::prepare(x.data(), s);
  }
  bool is_load() const { return dispatch(law, [](auto L) { return decltype(L)::is_load; }); }
  bool uses_displacement() const { return dispatch(law, [](auto L) { return decltype(L)::uses_displacement; }); }
  bool uses_velocity() const { return dispatch(law, [](auto L) { return decltype(L)::uses_velocity; }); }
  bool has_state() const { return dispatch(law, [](auto L) { return law::has_state<decltype(L)>; }); }
  // The same for every effect: the flags depend on the law and on whether a signal is given.
  bool uses_time() const {
    return size() > 0 && dispatch(law, [&](auto L) {
             using Lw = decltype(L);
             return Lw::uses_time(params<Lw>(0, signal.present() ? &signal : nullptr));
           });
  }
  bool is_linear() const {
    return size() == 0 || dispatch(law, [&](auto L) {
             using Lw = decltype(L);
             return !law::has_state<Lw> && Lw::is_linear(params<Lw>(0, signal.present() ? &signal : nullptr));
           });
  }
};

namespace detail_ {

// The declared parameters of law L given by name, for m effects: per parameter one value or m
// (one per effect); defaults for those left out, NaN for those left unset; every value finite
// (or unset where the law allows it) and checked by the law. Errors name the parameter, and the
// entry where values vary ("k0[17]").
template <class L>
std::vector<std::vector<double>> parse_parameters(const std::vector<std::pair<std::string, std::vector<double>>>& named,
                                                  size_t m, const std::string& who) {
  constexpr size_t np = L::parameters.size();
  std::vector<std::vector<double>> values(np);
  std::array<bool, np + 1> given{};
  for (const auto& [key, v] : named) {
    size_t p = 0;
    while (p < np && key != L::parameters[p].name) ++p;
    if (p == np) {
      std::string known;
      for (const auto& q : L::parameters) known += (known.empty() ? "" : ", ") + std::string(q.name);
      detail::throw_argument(key, "unknown parameter of " + who + " (expected " + (known.empty() ? "none" : known) + ")");
    }
    NVIB_CHECK(!given[p], key, "given twice");
    NVIB_CHECK(v.size() == 1 || v.size() == m, key,
               m == 1 ? "expected one value, got " + std::to_string(v.size())
                      : "expected one value or " + std::to_string(m) + " (one per effect), got " + std::to_string(v.size()));
    values[p] = v;
    given[p] = true;
  }
  for (size_t p = 0; p < np; ++p) {
    const Parameter& q = L::parameters[p];
    NVIB_CHECK(given[p] || !std::isnan(q.fallback) || q.may_be_unset, q.name, "missing parameter of " + who);
    if (!given[p]) values[p] = {q.fallback};
  }
  bool varying = false;
  for (const auto& v : values) varying = varying || v.size() > 1;
  std::array<double, np + 1> x{};
  for (size_t k = 0; k < (varying ? m : 1); ++k) {
    for (size_t p = 0; p < np; ++p) {
      x[p] = values[p].size() == 1 ? values[p][0] : values[p][k];
      const bool ok = std::isfinite(x[p]) || (L::parameters[p].may_be_unset && std::isnan(x[p]));
      if (!ok) {
        const std::string where = std::string(L::parameters[p].name) + (values[p].size() > 1 ? "[" + std::to_string(k) + "]" : "");
        detail::throw_argument(where, who + " needs a finite " + L::parameters[p].name + ", got " + detail::fmt(x[p]));
      }
    }
    try {
      L::validate(x.data());
    } catch (const ArgumentError& e) {
      if (!varying) throw;
      detail::throw_argument(e.argument() + "[" + std::to_string(k) + "]",
                             std::string(e.what()).substr(e.argument().size() + 2));
    }
  }
  return values;
}

template <class L>
Signal check_signal(Signal signal, const std::string& who) {
  if constexpr (L::signal != nullptr) {
    if (L::signal_required) NVIB_CHECK(signal.present(), L::signal, "missing (" + who + " needs it)");
    return signal;
  } else {
    NVIB_CHECK(!signal.present(), "signal", who + " takes no signal");
    return {};
  }
}

}  // namespace detail_

// An effect of law `law` on its measure, its parameters given by name; optional ones take their defaults.
inline Effect make_effect(LawId law, Measure g, const std::vector<std::pair<std::string, double>>& named,
                          Signal signal = {}, std::string name = "") {
  Effect e;
  e.law = law;
  e.name = std::move(name);
  const std::string who = key_of(law);
  NVIB_CHECK(!g.empty(), "measure", who + " needs at least one DOF in its measure");
  for (auto& [i, c] : g) {
    NVIB_CHECK(i >= 0, "measure", who + ": negative DOF index " + std::to_string(i));
    NVIB_CHECK(std::isfinite(c), "measure", who + ": non-finite coefficient");
    e.index.push_back(i);
    e.coef.push_back(c);
  }
  std::vector<std::pair<std::string, std::vector<double>>> vectors;
  for (const auto& [key, v] : named) vectors.emplace_back(key, std::vector<double>{v});
  dispatch(law, [&](auto L) {
    using Lw = decltype(L);
    for (const auto& v : detail_::parse_parameters<Lw>(vectors, 1, who)) e.values.push_back(v[0]);
    e.signal = detail_::check_signal<Lw>(std::move(signal), who);
  });
  return e;
}
inline Effect make_effect(const std::string& key, Measure g, const std::vector<std::pair<std::string, double>>& named,
                          Signal signal = {}, std::string name = "") {
  return make_effect(law_of(key), std::move(g), named, std::move(signal), std::move(name));
}

// The declared parameters in order (C++ convenience).
inline Effect make_effect_values(LawId law, Measure g, const std::vector<double>& values, Signal signal = {}) {
  std::vector<std::pair<std::string, double>> named;
  dispatch(law, [&](auto L) {
    using Lw = decltype(L);
    NVIB_CHECK(values.size() == Lw::parameters.size(), Lw::key,
               "expected " + std::to_string(Lw::parameters.size()) + " parameters, got " + std::to_string(values.size()));
    for (size_t p = 0; p < values.size(); ++p) named.emplace_back(Lw::parameters[p].name, values[p]);
  });
  return make_effect(law, std::move(g), named, std::move(signal));
}

// Checks and builds an array: n is the model's number of DOFs; parameters by name, each one value
// or one per effect (optional ones take their defaults). Errors name the parameter and the entry,
// "k0[17]", "j[3]".
inline EffectArray make_effect_array(LawId law, std::vector<std::int32_t> i, std::vector<std::int32_t> j,
                                     const std::vector<std::pair<std::string, std::vector<double>>>& named, Index n,
                                     Signal signal = {}, std::string name = "") {
  EffectArray a;
  a.law = law;
  a.name = std::move(name);
  const std::string who = key_of(law);
  NVIB_CHECK(law != law_id<GroundAcceleration>(), "type", "a ground acceleration acts on the whole model: declare it once");
  const size_t m = i.size();
  NVIB_CHECK(m > 0, "i", who + ": an effect array needs at least one effect");
  if (j.empty()) j.assign(m, -1);
  NVIB_CHECK(j.size() == m, "j", "expected " + std::to_string(m) + " entries (as many as i), got " + std::to_string(j.size()));
  for (size_t k = 0; k < m; ++k) {
    NVIB_CHECK(i[k] >= 0 && i[k] < n, "i[" + std::to_string(k) + "]",
               "DOF index " + std::to_string(i[k]) + " is out of range for " + std::to_string(n) + " degrees of freedom");
    NVIB_CHECK(j[k] < n, "j[" + std::to_string(k) + "]",
               "DOF index " + std::to_string(j[k]) + " is out of range for " + std::to_string(n) + " degrees of freedom");
    NVIB_CHECK(j[k] != i[k], "j[" + std::to_string(k) + "]", "equals i[" + std::to_string(k) + "]: the measure is zero");
    if (j[k] < 0) j[k] = -1;
  }
  dispatch(law, [&](auto L) {
    using Lw = decltype(L);
    a.values = detail_::parse_parameters<Lw>(named, m, who);
    a.signal = detail_::check_signal<Lw>(std::move(signal), who);
  });
  a.i = std::move(i);
  a.j = std::move(j);
  return a;
}
inline EffectArray make_effect_array(const std::string& key, std::vector<std::int32_t> i, std::vector<std::int32_t> j,
                                     const std::vector<std::pair<std::string, std::vector<double>>>& named, Index n,
                                     Signal signal = {}, std::string name = "") {
  return make_effect_array(law_of(key), std::move(i), std::move(j), named, n, std::move(signal), std::move(name));
}

inline Effect spring(Measure g, double k) { return make_effect_values(law_id<Spring>(), std::move(g), {k}); }
inline Effect damper(Measure g, double c) { return make_effect_values(law_id<Damper>(), std::move(g), {c}); }
inline Effect hardening_spring(Measure g, double k0, double a) {
  return make_effect_values(law_id<HardeningSpring>(), std::move(g), {k0, a});
}
inline Effect cubic_spring(Measure g, double k3) { return make_effect_values(law_id<CubicSpring>(), std::move(g), {k3}); }
inline Effect power_damper(Measure g, double c, double p) {
  return make_effect_values(law_id<PowerDamper>(), std::move(g), {c, p});
}
// mgl: the product m g l.
inline Effect pendulum_gravity(Measure g, double mgl) {
  return make_effect_values(law_id<PendulumGravity>(), std::move(g), {mgl, 1.0, 1.0});
}
// contacts: how many identical contacts act on the measure (2 wheels on a wheelset).
inline Effect hertz_contact(Measure g, double G, double contacts = 1.0, Signal irregularity = {}) {
  return make_effect_values(law_id<HertzContact>(), std::move(g), {G, contacts}, std::move(irregularity));
}
inline Effect constant_force(Measure g, double value) {
  return make_effect_values(law_id<ConstantForce>(), std::move(g), {value});
}
inline Effect harmonic_force(Measure g, double amplitude, double omega, double phase = 0.0) {
  return make_effect_values(law_id<HarmonicForce>(), std::move(g), {amplitude, omega, phase});
}
// r: the influence coefficients (1 on every DOF that moves with the ground).
inline Effect ground_acceleration(Measure r, Signal a_g) {
  return make_effect_values(law_id<GroundAcceleration>(), std::move(r), {}, std::move(a_g));
}

}  // namespace effects
}  // namespace nvib
