// The contract of a law: a scalar force f on a measure d = g . u (loads:
// -P(t) along g), written once as one struct (one header under laws/) that
// declares
//   key, doc, source                        its name in scenes and Python, one line, where it comes from
//   parameters                              name, default (or required), meaning: the declared parameters
//   validate(const double* x)               checks them (x in the declared order); names the parameter
//   struct Params, prepare(x, signal)       what it evaluates with, derived once from the declared values
//   uses_displacement, uses_velocity, is_load, is_linear(p), uses_time(p)   flags the schemes exploit
//   assembled                               linear with constant slopes: single effects go into K and C
// and either, without memory (State = NoState),
//   value(p, d, d', t) -> f                 the force
//   slopes(p, d, d', t) -> {df/dd, df/dd'}  both slopes, always
//   potential(p, d, t)                      its stored energy (0 where it stores none)
// or, with memory (a State of doubles: the internal variables, named in state_names),
//   trial(p, committed, d, d', t) -> {f, df/dd, df/dd', trial state}   a pure trial: it changes nothing;
//                                           the slopes are the consistent (algorithmic) tangent of the update
//   initial(p) -> State                     the virgin state (default: all zero)
//   recoverable(p, state, d)                the energy it stores and can give back
//   dissipated(p, state)                    the energy it has dissipated (an internal variable)
// plus, where they are not zero, input_power(p, d, d', t, side) (loads, a moving rail) and
// dissipated_power(p, d') (viscous laws). The kernels (kernels.hpp) read laws only through the
// functions below, so that a law with memory and one without are handled alike.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <tuple>
#include <type_traits>
#include <utility>

#include "../base/errors.hpp"
#include "signal.hpp"

namespace nvib {
namespace effects {

// A declared parameter: its name, its default (kRequired: must be given; unset(): may be left out,
// then NaN reaches validate(), which decides) and its meaning. A choice (choice()) takes one of the
// words "a|b|c" (in scenes and Python), passed to the law as 0, 1, 2; its default is the first.
struct Parameter {
  const char* name;
  double fallback;
  const char* doc = "";
  bool may_be_unset = false;
  const char* choices = nullptr;
};
constexpr double kRequired = std::numeric_limits<double>::quiet_NaN();
constexpr Parameter unset(const char* name, const char* doc) { return {name, kRequired, doc, true}; }
constexpr Parameter choice(const char* name, const char* doc, const char* words) { return {name, 0.0, doc, false, words}; }
inline bool is_unset(double x) { return std::isnan(x); }

// The state of a law without memory: no storage, no calls.
struct NoState {};

struct Slopes {
  double kd = 0.0;  // df/dd
  double kv = 0.0;  // df/dd'
};

// What a law with memory answers to a trial.
template <class State>
struct Trial {
  double f = 0.0, kd = 0.0, kv = 0.0;
  State state{};
};

// What a law does not declare: it acts on the displacement, has no memory, no signal, no
// stored energy; linear, independent of time, every finite parameter valid.
struct LawBase {
  static constexpr bool uses_displacement = true, uses_velocity = false, is_load = false;
  static constexpr bool assembled = false;
  static constexpr bool knows_energy = true;  // false: its stored energy is not known (a compiled law)
  static constexpr const char* signal = nullptr;  // name of its signal parameter
  static constexpr bool signal_required = false;
  static constexpr const char* source = "";
  using State = NoState;
  static constexpr std::array<const char*, 0> state_names{};
  static void validate(const double*) {}
  template <class P>
  static bool is_linear(const P&) {
    return true;
  }
  template <class P>
  static bool uses_time(const P&) {
    return false;
  }
  template <class P>
  static double potential(const P&, double, double) {
    return 0.0;
  }
};

namespace law {

template <class L>
constexpr bool has_state = !std::is_empty_v<typename L::State>;

// Doubles per effect of its state (0 without memory).
template <class L>
constexpr std::size_t state_width() {
  if constexpr (has_state<L>) {
    static_assert(std::is_trivially_copyable_v<typename L::State> && std::is_standard_layout_v<typename L::State> &&
                      sizeof(typename L::State) % sizeof(double) == 0 && alignof(typename L::State) == alignof(double),
                  "a law's State is a struct of doubles");
    static_assert(L::state_names.size() == sizeof(typename L::State) / sizeof(double),
                  "state_names names every internal variable");
    return sizeof(typename L::State) / sizeof(double);
  } else {
    return 0;
  }
}

template <class L>
using params_t = typename L::Params;
template <class L>
using state_t = typename L::State;

template <class L, class = void>
struct has_initial : std::false_type {};
template <class L>
struct has_initial<L, std::void_t<decltype(L::initial(std::declval<const params_t<L>&>()))>> : std::true_type {};
template <class L>
state_t<L> initial(const params_t<L>& p) {
  if constexpr (has_initial<L>::value) return L::initial(p);
  (void)p;
  return state_t<L>{};
}

template <class L>
double force(const params_t<L>& p, const state_t<L>& s, double d, double dd, double t) {
  if constexpr (has_state<L>) {
    return L::trial(p, s, d, dd, t).f;
  } else {
    (void)s;
    return L::value(p, d, dd, t);
  }
}

template <class L>
Slopes slopes(const params_t<L>& p, const state_t<L>& s, double d, double dd, double t) {
  if constexpr (has_state<L>) {
    const auto r = L::trial(p, s, d, dd, t);
    return {r.kd, r.kv};
  } else {
    (void)s;
    return L::slopes(p, d, dd, t);
  }
}

// The energy it stores at d (with memory: the recoverable part, given its state).
template <class L>
double stored(const params_t<L>& p, const state_t<L>& s, double d, double t) {
  if constexpr (has_state<L>) {
    (void)t;
    return L::recoverable(p, s, d);
  } else {
    (void)s;
    return L::potential(p, d, t);
  }
}

// The energy its state says it has dissipated (laws with memory that track it; 0 otherwise).
template <class L, class = void>
struct tracks_dissipation : std::false_type {};
template <class L>
struct tracks_dissipation<L, std::void_t<decltype(L::dissipated(std::declval<const params_t<L>&>(),
                                                                   std::declval<const state_t<L>&>()))>>
    : std::true_type {};
template <class L>
double dissipated(const params_t<L>& p, const state_t<L>& s) {
  if constexpr (tracks_dissipation<L>::value) return L::dissipated(p, s);
  (void)p, (void)s;
  return 0.0;
}

// Whether a law with memory has failed (lost its strength for good: a collapse).
template <class L, class = void>
struct can_fail : std::false_type {};
template <class L>
struct can_fail<L, std::void_t<decltype(L::failed(std::declval<const params_t<L>&>(), std::declval<const state_t<L>&>()))>>
    : std::true_type {};
template <class L>
bool failed(const params_t<L>& p, const state_t<L>& s) {
  if constexpr (can_fail<L>::value) return L::failed(p, s);
  (void)p, (void)s;
  return false;
}

// Power put in from outside: loads (P . v) and whatever the law declares (a moving rail).
template <class L, class = void>
struct has_input_power : std::false_type {};
template <class L>
struct has_input_power<L, std::void_t<decltype(L::input_power(std::declval<const params_t<L>&>(), 0.0, 0.0, 0.0, 0))>>
    : std::true_type {};
template <class L>
double input_power(const params_t<L>& p, double d, double dd, double t, int side) {
  if constexpr (has_input_power<L>::value) return L::input_power(p, d, dd, t, side);
  if constexpr (L::is_load) return -L::value(p, d, dd, t) * dd;
  (void)p, (void)d, (void)dd, (void)t, (void)side;
  return 0.0;
}

// Power dissipated by a viscous law (one that acts on the velocity alone): f d'.
template <class L>
constexpr bool is_viscous() {
  return L::uses_velocity && !L::uses_displacement && !L::is_load;
}
template <class L>
double dissipated_power(const params_t<L>& p, double dd) {
  if constexpr (is_viscous<L>()) return L::value(p, 0.0, dd, 0.0) * dd;
  (void)p, (void)dd;
  return 0.0;
}

// Where the force is not smooth (a contact opening or closing, a gap closing, a yield point): a law
// may declare event(p, committed, d, d', t), a value whose sign changes there (from the committed
// state of the step's start). Adaptive runs land their steps on such points instead of straddling them.
template <class L, class = void>
struct has_event : std::false_type {};
template <class L>
struct has_event<L, std::void_t<decltype(L::event(std::declval<const params_t<L>&>(), std::declval<const state_t<L>&>(),
                                                   0.0, 0.0, 0.0))>> : std::true_type {};

}  // namespace law

// The registry of laws: the runtime tag of a law is its position in the list.
using LawId = int;

template <class... L>
struct LawList {
  static constexpr std::size_t size = sizeof...(L);
  template <class Fn>
  static void for_each(Fn&& fn) {
    (fn(L{}), ...);
  }
  // The tag of law X.
  template <class X>
  static constexpr LawId id() {
    LawId k = 0, found = -1;
    ((std::is_same_v<X, L> ? (found = k, ++k) : ++k), ...);
    return found;
  }
  // fn(L{}) for the law tagged `law`: the one runtime switch over laws.
  template <class Fn>
  static decltype(auto) dispatch(LawId law, Fn&& fn) {
    using First = std::tuple_element_t<0, std::tuple<L...>>;
    using R = decltype(fn(First{}));
    LawId k = 0;
    if constexpr (std::is_void_v<R>) {
      (void)((law == k++ ? (fn(L{}), true) : false) || ...);
    } else {
      R r{};
      (void)((law == k++ ? (r = fn(L{}), true) : false) || ...);
      return r;
    }
  }
  // The tag of the law whose key is `key`, -1 if none.
  static LawId find(const std::string& key) {
    LawId k = 0, found = -1;
    ((key == L::key ? (found = k, ++k) : ++k), ...);
    return found;
  }
  static const char* key(LawId law) {
    const char* out = "?";
    dispatch(law, [&](auto x) { out = decltype(x)::key; });
    return out;
  }
};

}  // namespace effects
}  // namespace nvib
