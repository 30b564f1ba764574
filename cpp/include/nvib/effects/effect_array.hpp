// Many effects of one law at once: d_k = u_{i_k} - u_{j_k} (j_k < 0: the
// ground, d_k = u_{i_k}), each parameter one value for all or one per effect.
// Stored as flat arrays (about 12 bytes per effect plus its own parameter
// values), checked in one pass, compiled straight into the EffectSet's terms:
// 10^6 springs build in well under a second, where one Effect each would not.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "laws.hpp"

namespace nvib {
namespace effects {

struct EffectArray {
  Law law = Law::spring;
  std::string name;
  std::vector<std::int32_t> i, j;           // the measures' DOFs (j < 0: the ground)
  std::vector<std::vector<double>> values;  // per declared parameter: one value, or one per effect
  Signal signal;                            // shared by every effect (hertz_contact's irregularity)

  size_t size() const { return i.size(); }
  double value(size_t parameter, size_t k) const {
    const std::vector<double>& v = values[parameter];
    return v.size() == 1 ? v[0] : v[k];
  }
  // The law's own parameters of effect k (the signal pointer is the caller's to set).
  LawParams params(size_t k) const {
    return dispatch(law, [&](auto L) {
      using Lw = decltype(L);
      std::array<double, Lw::parameters.size() + 1> x{};
      for (size_t p = 0; p < Lw::parameters.size(); ++p) x[p] = value(p, k);
      LawParams out = Lw::prepare(x.data());
      out.signal = signal.present() ? &signal : nullptr;
      return out;
    });
  }
  bool is_load() const { return dispatch(law, [](auto L) { return decltype(L)::is_load; }); }
  bool uses_velocity() const { return dispatch(law, [](auto L) { return decltype(L)::uses_velocity; }); }
  // The same for every effect: the flags depend on the law and on whether a signal is given.
  bool uses_time() const { return size() > 0 && dispatch(law, [&](auto L) { return decltype(L)::uses_time(params(0)); }); }
  bool is_linear() const { return size() == 0 || dispatch(law, [&](auto L) { return decltype(L)::is_linear(params(0)); }); }
};

// Checks and builds an array: n is the model's number of DOFs; parameters by name, each one value
// or one per effect (optional ones take their defaults). Errors name the parameter and the entry,
// "k0[17]", "j[3]".
inline EffectArray make_effect_array(Law law, std::vector<std::int32_t> i, std::vector<std::int32_t> j,
                                     const std::vector<std::pair<std::string, std::vector<double>>>& named,
                                     Index n, Signal signal = {}, std::string name = "") {
  EffectArray a;
  a.law = law;
  a.name = std::move(name);
  const std::string who = to_string(law);
  NVIB_CHECK(law != Law::ground_acceleration, "type", "a ground acceleration acts on the whole model: declare it once");
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
    a.values.assign(Lw::parameters.size(), {});
    std::array<bool, Lw::parameters.size() + 1> given{};
    for (const auto& [key, v] : named) {
      size_t p = 0;
      while (p < Lw::parameters.size() && key != Lw::parameters[p].name) ++p;
      if (p == Lw::parameters.size()) {
        std::string known;
        for (const auto& q : Lw::parameters) known += (known.empty() ? "" : ", ") + std::string(q.name);
        detail::throw_argument(key, "unknown parameter of " + who + " (expected " + (known.empty() ? "none" : known) + ")");
      }
      NVIB_CHECK(v.size() == 1 || v.size() == m, key,
                 "expected one value or " + std::to_string(m) + " (one per effect), got " + std::to_string(v.size()));
      a.values[p] = v;
      given[p] = true;
    }
    for (size_t p = 0; p < Lw::parameters.size(); ++p) {
      NVIB_CHECK(given[p] || !std::isnan(Lw::parameters[p].fallback), Lw::parameters[p].name,
                 "missing parameter of " + who);
      if (!given[p]) a.values[p] = {Lw::parameters[p].fallback};
    }
    // Every effect's parameters, as one effect's would be checked.
    std::array<double, Lw::parameters.size() + 1> x{};
    bool varying = false;
    for (const auto& v : a.values) varying = varying || v.size() > 1;
    for (size_t k = 0; k < (varying ? m : 1); ++k) {
      for (size_t p = 0; p < Lw::parameters.size(); ++p) {
        x[p] = a.value(p, k);
        if (!std::isfinite(x[p])) {
          const std::string where = std::string(Lw::parameters[p].name) + (a.values[p].size() > 1 ? "[" + std::to_string(k) + "]" : "");
          detail::throw_argument(where, who + " needs a finite value, got " + detail::fmt(x[p]));
        }
      }
      try {
        Lw::validate(x.data());
      } catch (const ArgumentError& e) {
        if (!varying) throw;
        detail::throw_argument(e.argument() + "[" + std::to_string(k) + "]",
                               std::string(e.what()).substr(e.argument().size() + 2));
      }
    }
    if constexpr (Lw::signal != nullptr) {
      if (Lw::signal_required) NVIB_CHECK(signal.present(), Lw::signal, "missing (" + who + " needs it)");
      a.signal = std::move(signal);
    } else {
      NVIB_CHECK(!signal.present(), "signal", who + " takes no signal");
    }
  });
  a.i = std::move(i);
  a.j = std::move(j);
  return a;
}

}  // namespace effects
}  // namespace nvib
