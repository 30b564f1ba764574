// A C++ law of one's own, outside nvib's headers: a struct with the contract of the built-in laws
// (law.hpp: parameters, validate, Params and prepare, flags, and value/slopes or State/trial/initial)
// becomes an effect through the compiled-law entry (laws/compiled.hpp):
//
//   Effect e = make_user_effect<MyLaw>({{0, 1.0}}, {k, fy});   // its declared parameters, in order
//
// user_law<L> is the C function the compiled law calls: it prepares L's Params from the parameters it is
// given and answers with L's value and slopes, or with L's trial from the committed State, so a user law
// runs in every scheme, alone or among built-in effects, with the same trial/commit contract. It is one
// call through a pointer per effect and evaluation (the compiled laws' price: measured 1.3-1.4x a
// built-in law on the building, benchmarks/results/law_cost.md), at most kCompiledParams parameters and
// kCompiledState internal variables. Its stored energy is not known (no energy account).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "effect.hpp"
#include "laws/compiled.hpp"

namespace nvib {
namespace effects {

template <class L>
int user_law(const double* p, const double* state, double d, double dd, double t, double* out, double* trial) {
  const typename L::Params params = L::prepare(p, nullptr);
  if constexpr (law::has_state<L>) {
    typename L::State committed;
    std::memcpy(&committed, state, sizeof committed);
    const Trial<typename L::State> r = L::trial(params, committed, d, dd, t);
    out[0] = r.f;
    out[1] = r.kd;
    out[2] = r.kv;
    std::memcpy(trial, &r.state, sizeof r.state);
  } else {
    (void)state, (void)trial;
    out[0] = L::value(params, d, dd, t);
    const Slopes s = L::slopes(params, d, dd, t);
    out[1] = s.kd;
    out[2] = s.kv;
  }
  return 0;
}

// An effect of the user law L on the measure g, with L's declared parameters in their order; optional
// `name`. Checked as a built-in law is (L::validate names the parameter).
template <class L>
Effect make_user_effect(Measure g, const std::vector<double>& values, std::string name = "") {
  static_assert(L::parameters.size() <= static_cast<std::size_t>(kCompiledParams),
                "a user law takes at most kCompiledParams parameters");
  static_assert(law::state_width<L>() <= static_cast<std::size_t>(kCompiledState),
                "a user law keeps at most kCompiledState internal variables");
  static_assert(!L::is_load, "a load is a built-in effect (constant_force, harmonic_force, ground_acceleration)");
  NVIB_CHECK(values.size() == L::parameters.size(), L::key,
             "expected " + std::to_string(L::parameters.size()) + " parameters, got " + std::to_string(values.size()));
  L::validate(values.data());
  double padded[kCompiledParams] = {};
  std::copy(values.begin(), values.end(), padded);
  const typename L::Params params = L::prepare(padded, nullptr);
  const CompiledLawFn fn = &user_law<L>;
  std::vector<std::pair<std::string, double>> named{
      {"address", static_cast<double>(reinterpret_cast<std::uintptr_t>(fn))},
      {"uses_time", L::uses_time(params) ? 1.0 : 0.0}};
  for (std::size_t k = 0; k < values.size(); ++k) named.emplace_back("p" + std::to_string(k), values[k]);
  if constexpr (law::has_state<L>) {
    const typename L::State s0 = law::initial<L>(params);
    double initial[kCompiledState] = {};
    std::memcpy(initial, &s0, sizeof s0);
    named.emplace_back("state_size", static_cast<double>(law::state_width<L>()));
    for (std::size_t k = 0; k < law::state_width<L>(); ++k) named.emplace_back("s" + std::to_string(k), initial[k]);
    return make_effect(law_id<CompiledState>(), std::move(g), named, {}, std::move(name));
  } else {
    return make_effect(law_id<Compiled>(), std::move(g), named, {}, std::move(name));
  }
}

}  // namespace effects
}  // namespace nvib
