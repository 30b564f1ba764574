// A law compiled elsewhere and handed over as a C function pointer (a Numba cfunc, a function of a
// shared library, a scipy.LowLevelCallable's): called from the kernels like any built-in law, with no
// Python in the loop, so a run keeps the GIL released. The signature:
//
//   int law(const double* params, const double* state, double d, double dd, double t,
//           double* out, double* trial_state)
//
// params: the effect's parameters (up to kCompiledParams); state: its committed internal variables
// (nullptr for a law without memory); out[0] = f, out[1] = df/dd, out[2] = df/dd' (the consistent
// tangent of a law with memory); trial_state: where it writes the internal variables after (d, d', t)
// (nullptr without memory). It must be a pure trial (change nothing else) and return 0; any other
// value stops the run with an error naming the law, its code and the point. The function's address
// travels as a declared parameter: a double holds a user-space address (below 2^47) exactly.
//
// Two laws share this: `compiled` (no memory) and `compiled_state` (up to kCompiledState internal
// variables, their initial values declared). Neither knows its stored energy, so a model with one
// refuses an energy account, as one with a Python callable does.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>

#include "../law.hpp"

namespace nvib {
namespace effects {

constexpr int kCompiledParams = 8;
constexpr int kCompiledState = 8;

using CompiledLawFn = int (*)(const double* params, const double* state, double d, double dd, double t, double* out,
                              double* trial_state);

namespace detail_compiled {

inline void check_address(double a) {
  NVIB_CHECK(a > 0.0 && a < 9007199254740992.0 && a == static_cast<double>(static_cast<std::uint64_t>(a)), "address",
             "expected the address of a compiled function (a positive whole number), got " + detail::fmt(a));
}
inline CompiledLawFn function_at(double a) {
  return reinterpret_cast<CompiledLawFn>(static_cast<std::uintptr_t>(a));
}
[[noreturn]] inline void fail(int code, double d, double dd, double t) {
  throw std::runtime_error("a compiled law returned " + std::to_string(code) + " (not 0) at d = " + detail::fmt(d) +
                           ", d' = " + detail::fmt(dd) + ", t = " + detail::fmt(t));
}
// One call: out = {f, df/dd, df/dd'} (and the trial state, with memory); a code other than 0 stops the run.
inline void call(CompiledLawFn fn, const double* p, const double* state, double d, double dd, double t, double* out,
                 double* trial) {
  const int code = fn(p, state, d, dd, t, out, trial);
  if (code != 0) fail(code, d, dd, t);
}

}  // namespace detail_compiled

struct CompiledLawBase : LawBase {
  static constexpr bool uses_velocity = true;  // not known: d' is always measured
  static constexpr bool knows_energy = false;
  template <class P>
  static bool is_linear(const P&) {
    return false;
  }
  template <class P>
  static bool uses_time(const P& p) {
    return p.time;
  }
};

struct Compiled : CompiledLawBase {
  static constexpr const char* key = "compiled";
  static constexpr const char* doc =
      "a compiled law without memory: a C function int law(params, state, d, d', t, out, trial_state)";
  static constexpr std::array<Parameter, 2 + kCompiledParams> parameters{
      {{"address", kRequired, "the function's address"},
       {"uses_time", 1.0, "1 if the force depends on t, 0 if not"},
       {"p0", 0.0, "parameter 0"}, {"p1", 0.0, "parameter 1"}, {"p2", 0.0, "parameter 2"}, {"p3", 0.0, "parameter 3"},
       {"p4", 0.0, "parameter 4"}, {"p5", 0.0, "parameter 5"}, {"p6", 0.0, "parameter 6"}, {"p7", 0.0, "parameter 7"}}};
  struct Params {
    CompiledLawFn fn;
    double p[kCompiledParams];
    bool time;
  };
  static void validate(const double* x) { detail_compiled::check_address(x[0]); }
  static Params prepare(const double* x, const Signal*) {
    Params p{detail_compiled::function_at(x[0]), {}, x[1] != 0.0};
    for (int k = 0; k < kCompiledParams; ++k) p.p[k] = x[2 + k];
    return p;
  }
  static Slopes slopes(const Params& p, double d, double dd, double t) {
    double out[3] = {0.0, 0.0, 0.0};
    detail_compiled::call(p.fn, p.p, nullptr, d, dd, t, out, nullptr);
    return {out[1], out[2]};
  }
  static double value(const Params& p, double d, double dd, double t) {
    double out[3] = {0.0, 0.0, 0.0};
    detail_compiled::call(p.fn, p.p, nullptr, d, dd, t, out, nullptr);
    return out[0];
  }
};

struct CompiledState : CompiledLawBase {
  static constexpr const char* key = "compiled_state";
  static constexpr const char* doc =
      "a compiled law with memory: a C function int law(params, state, d, d', t, out, trial_state)";
  static constexpr std::array<Parameter, 3 + kCompiledParams + kCompiledState> parameters{
      {{"address", kRequired, "the function's address"},
       {"uses_time", 1.0, "1 if the force depends on t, 0 if not"},
       {"state_size", kRequired, "its internal variables (1 to 8)"},
       {"p0", 0.0, "parameter 0"}, {"p1", 0.0, "parameter 1"}, {"p2", 0.0, "parameter 2"}, {"p3", 0.0, "parameter 3"},
       {"p4", 0.0, "parameter 4"}, {"p5", 0.0, "parameter 5"}, {"p6", 0.0, "parameter 6"}, {"p7", 0.0, "parameter 7"},
       {"s0", 0.0, "initial internal variable 0"}, {"s1", 0.0, "initial internal variable 1"},
       {"s2", 0.0, "initial internal variable 2"}, {"s3", 0.0, "initial internal variable 3"},
       {"s4", 0.0, "initial internal variable 4"}, {"s5", 0.0, "initial internal variable 5"},
       {"s6", 0.0, "initial internal variable 6"}, {"s7", 0.0, "initial internal variable 7"}}};
  struct Params {
    CompiledLawFn fn;
    double p[kCompiledParams];
    double s0[kCompiledState];
    bool time;
  };
  struct State {
    double s[kCompiledState];
  };
  static constexpr std::array<const char*, kCompiledState> state_names{
      {"s0", "s1", "s2", "s3", "s4", "s5", "s6", "s7"}};
  static void validate(const double* x) {
    detail_compiled::check_address(x[0]);
    NVIB_CHECK(x[2] >= 1.0 && x[2] <= kCompiledState && x[2] == static_cast<double>(static_cast<int>(x[2])),
               "state_size", "expected 1 to " + std::to_string(kCompiledState) + " internal variables, got " +
                                 detail::fmt(x[2]));
  }
  static Params prepare(const double* x, const Signal*) {
    Params p{detail_compiled::function_at(x[0]), {}, {}, x[1] != 0.0};
    for (int k = 0; k < kCompiledParams; ++k) p.p[k] = x[3 + k];
    for (int k = 0; k < kCompiledState; ++k) p.s0[k] = x[3 + kCompiledParams + k];
    return p;
  }
  static State initial(const Params& p) {
    State s{};
    for (int k = 0; k < kCompiledState; ++k) s.s[k] = p.s0[k];
    return s;
  }
  // The trial state starts as the committed one, so variables past the law's own count stay as they were.
  static Trial<State> trial(const Params& p, const State& c, double d, double dd, double t) {
    Trial<State> r{0.0, 0.0, 0.0, c};
    double out[3] = {0.0, 0.0, 0.0};
    detail_compiled::call(p.fn, p.p, c.s, d, dd, t, out, r.state.s);
    r.f = out[0];
    r.kd = out[1];
    r.kv = out[2];
    return r;
  }
  static double recoverable(const Params&, const State&, double) { return 0.0; }
};

}  // namespace effects
}  // namespace nvib
