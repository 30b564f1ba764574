// Built-in effects: each a scalar law f(d, d', t) on a measure d = g . u
// (g a sparse row over DOFs); its force enters the equation of motion as g^T f.
// Loads are effects too: their law is -P(t) along g.
//
// EffectSet is a force functor for Model. make_effect_model assembles the
// linear effects once (springs into K, dampers into C, constant loads into a
// constant vector); only the remaining effects are evaluated each step, and
// the model's flags (uses_velocity, uses_time, is_linear) come from the
// declared effects alone.
#pragma once

#include <algorithm>
#include <cstdint>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "../core/model.hpp"

namespace nvib {
namespace effects {

enum class Law {
  spring,               // f = k d
  damper,               // f = c d'
  hardening_spring,     // f = k0 (1 + a d^2) d
  cubic_spring,         // f = k3 d^3
  power_damper,         // f = c |d'|^p sign(d')
  pendulum_gravity,     // f = m g l sin(d)
  hertz_contact,        // f = n (max(d - r(t), 0) / G)^{3/2}, unilateral
  constant_force,       // load P = value along g
  harmonic_force,       // load P = amplitude sin(omega t + phase) along g
  ground_acceleration,  // load P = -M r a_g(t), r = g
};

inline const char* to_string(Law l) {
  switch (l) {
    case Law::spring: return "spring";
    case Law::damper: return "damper";
    case Law::hardening_spring: return "hardening_spring";
    case Law::cubic_spring: return "cubic_spring";
    case Law::power_damper: return "power_damper";
    case Law::pendulum_gravity: return "pendulum_gravity";
    case Law::hertz_contact: return "hertz_contact";
    case Law::constant_force: return "constant_force";
    case Law::harmonic_force: return "harmonic_force";
    case Law::ground_acceleration: return "ground_acceleration";
  }
  return "?";
}
inline const std::vector<Law>& all_laws() {
  static const std::vector<Law> laws = {Law::spring,        Law::damper,           Law::hardening_spring,
                                        Law::cubic_spring,  Law::power_damper,     Law::pendulum_gravity,
                                        Law::hertz_contact, Law::constant_force,   Law::harmonic_force,
                                        Law::ground_acceleration};
  return laws;
}

// A time signal: absent (0), a sine, or a table interpolated linearly (0 outside its range).
struct Signal {
  enum class Kind { none, sine, table };
  Kind kind = Kind::none;
  double amplitude = 0.0, omega = 0.0, phase = 0.0;
  std::vector<double> t, y;

  static Signal sine(double amplitude, double omega, double phase = 0.0) {
    nvib::detail::require(std::isfinite(amplitude) && std::isfinite(omega) && std::isfinite(phase),
                          "signal: amplitude, omega and phase must be finite");
    Signal s;
    s.kind = Kind::sine;
    s.amplitude = amplitude;
    s.omega = omega;
    s.phase = phase;
    return s;
  }
  static Signal table(std::vector<double> times, std::vector<double> values) {
    nvib::detail::require(times.size() == values.size(), "signal: t and values must have the same length");
    nvib::detail::require(times.size() >= 2, "signal: a table needs at least two points");
    for (size_t i = 0; i < times.size(); ++i) {
      nvib::detail::require(std::isfinite(times[i]) && std::isfinite(values[i]), "signal: non-finite table entry");
      if (i > 0) nvib::detail::require(times[i] > times[i - 1], "signal: table times must increase strictly");
    }
    Signal s;
    s.kind = Kind::table;
    s.t = std::move(times);
    s.y = std::move(values);
    return s;
  }

  bool present() const { return kind != Kind::none; }

  double value(double time) const {
    switch (kind) {
      case Kind::none: return 0.0;
      case Kind::sine: return amplitude * std::sin(omega * time + phase);
      case Kind::table: {
        if (time < t.front() || time > t.back()) return 0.0;
        const size_t i = segment(time);
        const double w = (time - t[i]) / (t[i + 1] - t[i]);
        return (1.0 - w) * y[i] + w * y[i + 1];
      }
    }
    return 0.0;
  }
  double derivative(double time) const {
    switch (kind) {
      case Kind::none: return 0.0;
      case Kind::sine: return amplitude * omega * std::cos(omega * time + phase);
      case Kind::table: {
        if (time < t.front() || time > t.back()) return 0.0;
        const size_t i = segment(time);
        return (y[i + 1] - y[i]) / (t[i + 1] - t[i]);
      }
    }
    return 0.0;
  }

 private:
  size_t segment(double time) const {
    const auto it = std::upper_bound(t.begin(), t.end(), time);
    size_t i = static_cast<size_t>(it - t.begin());
    i = i == 0 ? 0 : i - 1;
    return std::min(i, t.size() - 2);
  }
};

// Parameters of one law: p0, p1, p2 (see the factories below) and its signal.
struct LawParams {
  double p0 = 0.0, p1 = 0.0, p2 = 0.0;
  const Signal* signal = nullptr;  // a_g(t) for ground_acceleration, r(t) for hertz_contact (may be absent)
};

// What a law reads, known at compile time so the evaluation loops drop the rest.
constexpr bool law_uses_velocity(Law l) { return l == Law::damper || l == Law::power_damper; }
constexpr bool law_is_load(Law l) {
  return l == Law::constant_force || l == Law::harmonic_force || l == Law::ground_acceleration;
}
constexpr bool law_uses_displacement(Law l) { return !law_uses_velocity(l) && !law_is_load(l); }
constexpr bool law_is_dissipative(Law l) { return law_uses_velocity(l); }

// The scalar laws f(d, d', t) (loads: -P), written once; Effect and EffectSet both call these.
template <Law L>
inline double law_value(const LawParams& p, double d, double dd, double t) {
  if constexpr (L == Law::spring) return p.p0 * d;
  if constexpr (L == Law::damper) return p.p0 * dd;
  if constexpr (L == Law::hardening_spring) return p.p0 * (1.0 + p.p1 * d * d) * d;
  if constexpr (L == Law::cubic_spring) return p.p0 * d * d * d;
  if constexpr (L == Law::power_damper) return dd == 0.0 ? 0.0 : std::copysign(p.p0 * std::pow(std::abs(dd), p.p1), dd);
  if constexpr (L == Law::pendulum_gravity) return p.p0 * std::sin(d);
  if constexpr (L == Law::hertz_contact) {
    const double delta = p.signal ? d - p.signal->value(t) : d;
    return delta > 0.0 ? p.p1 * std::pow(delta / p.p0, 1.5) : 0.0;
  }
  if constexpr (L == Law::constant_force) return -p.p0;
  if constexpr (L == Law::harmonic_force) return -p.p0 * std::sin(p.p1 * t + p.p2);
  if constexpr (L == Law::ground_acceleration) return p.signal->value(t);  // g = M r, so g^T f = -P
  (void)p, (void)d, (void)dd, (void)t;
  return 0.0;
}
// df/dd
template <Law L>
inline double law_dvalue_dd(const LawParams& p, double d, double t) {
  if constexpr (L == Law::spring) return p.p0;
  if constexpr (L == Law::hardening_spring) return p.p0 * (1.0 + 3.0 * p.p1 * d * d);
  if constexpr (L == Law::cubic_spring) return 3.0 * p.p0 * d * d;
  if constexpr (L == Law::pendulum_gravity) return p.p0 * std::cos(d);
  if constexpr (L == Law::hertz_contact) {
    const double delta = p.signal ? d - p.signal->value(t) : d;
    return delta > 0.0 ? 1.5 * p.p1 / p.p0 * std::sqrt(delta / p.p0) : 0.0;
  }
  (void)p, (void)d, (void)t;
  return 0.0;
}
// df/dd'
template <Law L>
inline double law_dvalue_dv(const LawParams& p, double dd) {
  if constexpr (L == Law::damper) return p.p0;
  if constexpr (L == Law::power_damper) {
    // At d' = 0 the slope of c |d'|^p sign(d') is unbounded for p < 1 and 0
    // for p > 1; Newton then uses the linear damper's c (p <= 1) or 0.
    const double s = std::abs(dd);
    if (s == 0.0) return p.p1 > 1.0 ? 0.0 : p.p0;
    return p.p0 * p.p1 * std::pow(s, p.p1 - 1.0);
  }
  (void)p, (void)dd;
  return 0.0;
}
// Potential energy of a conservative law at t (0 for dampers and loads).
template <Law L>
inline double law_potential(const LawParams& p, double d, double t) {
  if constexpr (L == Law::spring) return 0.5 * p.p0 * d * d;
  if constexpr (L == Law::hardening_spring) return p.p0 * (0.5 * d * d + 0.25 * p.p1 * d * d * d * d);
  if constexpr (L == Law::cubic_spring) return 0.25 * p.p0 * d * d * d * d;
  if constexpr (L == Law::pendulum_gravity) return p.p0 * (1.0 - std::cos(d));
  if constexpr (L == Law::hertz_contact) {
    const double delta = p.signal ? d - p.signal->value(t) : d;
    return delta > 0.0 ? p.p1 * p.p0 * std::pow(delta / p.p0, 2.5) / 2.5 : 0.0;
  }
  (void)p, (void)d, (void)t;
  return 0.0;
}
// Power put into the system from outside: loads (P . v) and a moving rail
// (the contact potential V(d - r(t)) changes at the rate -f r'(t)).
template <Law L>
inline double law_input_power(const LawParams& p, double d, double dd, double t) {
  if constexpr (law_is_load(L)) return -law_value<L>(p, d, dd, t) * dd;
  if constexpr (L == Law::hertz_contact)
    return p.signal ? -law_value<L>(p, d, dd, t) * p.signal->derivative(t) : 0.0;
  (void)p, (void)d, (void)dd, (void)t;
  return 0.0;
}
template <Law L>
inline double law_dissipated_power(const LawParams& p, double dd) {
  if constexpr (law_is_dissipative(L)) return law_value<L>(p, 0.0, dd, 0.0) * dd;
  (void)p, (void)dd;
  return 0.0;
}

// Calls fn(std::integral_constant<Law, L>{}) for the runtime law l: the one switch over laws.
template <class Fn>
decltype(auto) dispatch(Law l, Fn&& fn) {
  switch (l) {
    case Law::spring: return fn(std::integral_constant<Law, Law::spring>{});
    case Law::damper: return fn(std::integral_constant<Law, Law::damper>{});
    case Law::hardening_spring: return fn(std::integral_constant<Law, Law::hardening_spring>{});
    case Law::cubic_spring: return fn(std::integral_constant<Law, Law::cubic_spring>{});
    case Law::power_damper: return fn(std::integral_constant<Law, Law::power_damper>{});
    case Law::pendulum_gravity: return fn(std::integral_constant<Law, Law::pendulum_gravity>{});
    case Law::hertz_contact: return fn(std::integral_constant<Law, Law::hertz_contact>{});
    case Law::constant_force: return fn(std::integral_constant<Law, Law::constant_force>{});
    case Law::harmonic_force: return fn(std::integral_constant<Law, Law::harmonic_force>{});
    case Law::ground_acceleration: break;
  }
  return fn(std::integral_constant<Law, Law::ground_acceleration>{});
}

// One declared effect: a law on its measure d = g . u.
struct Effect {
  Law law = Law::spring;
  std::string name;          // optional; scenes use it to switch effects off
  std::vector<Index> index;  // DOFs of the measure
  std::vector<double> coef;  // g entries
  double p0 = 0.0, p1 = 0.0, p2 = 0.0;  // law parameters (see the factories)
  Signal signal;             // a_g(t) for ground_acceleration, r(t) for hertz_contact

  bool uses_velocity() const { return law_uses_velocity(law); }
  bool uses_time() const {
    return law == Law::harmonic_force || law == Law::ground_acceleration ||
           (law == Law::hertz_contact && signal.present());
  }
  // Linear in (u, v) for fixed t, so its tangent is constant.
  bool is_linear() const {
    switch (law) {
      case Law::hardening_spring:
      case Law::cubic_spring:
      case Law::pendulum_gravity:
      case Law::hertz_contact: return false;
      case Law::power_damper: return p1 == 1.0;
      default: return true;
    }
  }
  bool is_load() const { return law_is_load(law); }
  bool is_dissipative() const { return law_is_dissipative(law); }
  LawParams params() const { return {p0, p1, p2, signal.present() ? &signal : nullptr}; }

  template <class V>
  double measure(const V& x) const {
    double d = 0.0;
    for (size_t i = 0; i < index.size(); ++i) d += coef[i] * x[index[i]];
    return d;
  }

  double value(double d, double dd, double t) const {
    return dispatch(law, [&](auto L) { return law_value<L()>(params(), d, dd, t); });
  }
  double dvalue_dd(double d, double t) const {
    return dispatch(law, [&](auto L) { return law_dvalue_dd<L()>(params(), d, t); });
  }
  double dvalue_dv(double dd) const {
    return dispatch(law, [&](auto L) { return law_dvalue_dv<L()>(params(), dd); });
  }
  double potential(double d, double t) const {
    return dispatch(law, [&](auto L) { return law_potential<L()>(params(), d, t); });
  }
  double input_power(double d, double dd, double t) const {
    return dispatch(law, [&](auto L) { return law_input_power<L()>(params(), d, dd, t); });
  }
  double dissipated_power(double dd) const {
    return dispatch(law, [&](auto L) { return law_dissipated_power<L()>(params(), dd); });
  }
};

namespace detail_ {
inline Effect make(Law law, std::vector<std::pair<Index, double>> g, double p0, double p1 = 0.0, double p2 = 0.0,
                   Signal signal = {}) {
  const std::string who = to_string(law);
  Effect e;
  e.law = law;
  nvib::detail::require(!g.empty(), who + ".measure: an effect needs at least one DOF in its measure");
  for (auto& [i, c] : g) {
    nvib::detail::require(i >= 0, who + ".measure: negative DOF index " + std::to_string(i));
    nvib::detail::require(std::isfinite(c), who + ".measure: non-finite coefficient");
    e.index.push_back(i);
    e.coef.push_back(c);
  }
  nvib::detail::require(std::isfinite(p0) && std::isfinite(p1) && std::isfinite(p2), who + ": parameters must be finite");
  e.p0 = p0;
  e.p1 = p1;
  e.p2 = p2;
  e.signal = std::move(signal);
  switch (law) {
    case Law::power_damper:
      nvib::detail::require(p1 > 0.0, "power_damper.p: the exponent must be > 0, got " + nvib::detail::fmt(p1));
      break;
    case Law::hertz_contact:
      nvib::detail::require(p0 > 0.0, "hertz_contact.G: must be > 0, got " + nvib::detail::fmt(p0));
      nvib::detail::require(p1 > 0.0, "hertz_contact.contacts: must be > 0, got " + nvib::detail::fmt(p1));
      break;
    case Law::ground_acceleration:
      nvib::detail::require(e.signal.present(), "ground_acceleration.signal: missing");
      break;
    default: break;
  }
  return e;
}
}  // namespace detail_

using Measure = std::vector<std::pair<Index, double>>;
inline Effect spring(Measure g, double k) { return detail_::make(Law::spring, std::move(g), k); }
inline Effect damper(Measure g, double c) { return detail_::make(Law::damper, std::move(g), c); }
inline Effect hardening_spring(Measure g, double k0, double a) {
  return detail_::make(Law::hardening_spring, std::move(g), k0, a);
}
inline Effect cubic_spring(Measure g, double k3) { return detail_::make(Law::cubic_spring, std::move(g), k3); }
inline Effect power_damper(Measure g, double c, double p) { return detail_::make(Law::power_damper, std::move(g), c, p); }
inline Effect pendulum_gravity(Measure g, double mgl) { return detail_::make(Law::pendulum_gravity, std::move(g), mgl); }
// contacts: how many identical contacts act on the measure (2 wheels on a wheelset).
inline Effect hertz_contact(Measure g, double G, double contacts = 1.0, Signal irregularity = {}) {
  return detail_::make(Law::hertz_contact, std::move(g), G, contacts, 0.0, std::move(irregularity));
}
inline Effect constant_force(Measure g, double value) { return detail_::make(Law::constant_force, std::move(g), value); }
inline Effect harmonic_force(Measure g, double amplitude, double omega, double phase = 0.0) {
  return detail_::make(Law::harmonic_force, std::move(g), amplitude, omega, phase);
}
// r: the influence coefficients (1 on every DOF that moves with the ground).
inline Effect ground_acceleration(Measure r, Signal a_g) {
  return detail_::make(Law::ground_acceleration, std::move(r), 0.0, 0.0, 0.0, std::move(a_g));
}

// The effects evaluated each step, plus a constant load vector.
//
// The evaluated effects are compiled once into flat arrays grouped by law and
// by how their measures are stored: one or two entries inline (with special
// cases for d = u_i and d = u_i - u_j, the usual spring to the ground or
// between two DOFs), a sparse list, or a dense row (a ground acceleration's M r). Each group runs one loop instantiated for its law and
// storage, reached through one function pointer chosen at build time: one
// indirect call per group, never per effect, and no switch in the loop. A
// load reads no measure, a spring no velocity.
//
// The force vector is first *written* (constant loads plus the dense loads,
// which need no state) and then accumulated into. Zeroing it first is a
// memset call whose wide stores the effects' narrow read-modify-writes then
// wait on; measured 30% slower on the building scene.
class EffectSet {
 public:
  EffectSet() = default;
  // `mass` turns ground accelerations' influence vectors r into M r.
  EffectSet(std::vector<Effect> list, const Mass& mass) : all_(std::move(list)) {
    const Index n = mass.size();
    f_const_.setZero(n);
    for (size_t i = 0; i < all_.size(); ++i) {
      Effect& e = all_[i];
      for (Index d : e.index)
        nvib::detail::require(d < n, "effects[" + std::to_string(i) + "].measure: DOF index " + std::to_string(d) +
                                         " is out of range for " + std::to_string(n) + " degrees of freedom");
      if (e.law == Law::ground_acceleration) {
        Vector r = Vector::Zero(n), w(n);
        for (size_t k = 0; k < e.index.size(); ++k) r[e.index[k]] += e.coef[k];
        mass.apply(r, w);
        e.index.clear();
        e.coef.clear();
        for (Index d = 0; d < n; ++d)
          if (w[d] != 0.0) {
            e.index.push_back(d);
            e.coef.push_back(w[d]);
          }
      }
      uses_time_ = uses_time_ || e.uses_time();
      linear_ = linear_ && e.is_linear();
      if (e.law == Law::spring || e.law == Law::damper) continue;  // assembled into K, C
      if (e.law == Law::constant_force) {
        for (size_t k = 0; k < e.index.size(); ++k) f_const_[e.index[k]] -= e.coef[k] * e.p0;
        continue;
      }
      active_.push_back(e);
      active_velocity_ = active_velocity_ || e.uses_velocity();
    }
    compile();
  }

  // Copies re-point the compiled terms at their own signals.
  EffectSet(const EffectSet& o) { *this = o; }
  EffectSet& operator=(const EffectSet& o) {
    if (this == &o) return *this;
    all_ = o.all_;
    active_ = o.active_;
    f_const_ = o.f_const_;
    uses_time_ = o.uses_time_;
    linear_ = o.linear_;
    active_velocity_ = o.active_velocity_;
    compile();
    return *this;
  }
  // Moving the vectors keeps their buffers, so the compiled pointers stay valid.
  EffectSet(EffectSet&&) noexcept = default;
  EffectSet& operator=(EffectSet&&) noexcept = default;

  const std::vector<Effect>& effects() const { return all_; }
  const std::vector<Effect>& evaluated() const { return active_; }
  const Vector& constant_load() const { return f_const_; }  // -P of the constant loads

  void operator()(const CVecRef& u, const CVecRef& v, double t, VecRef out) const {
    const double* up = u.data();
    const double* vp = v.data();
    double* op = out.data();
    auto g = groups_.begin();
    if (g != groups_.end() && g->writes) {
      g->kernel(*this, *g, up, vp, t, op);  // writes constant loads + its loads
      ++g;
    } else {
      // A stored zero the compiler cannot see through keeps this a plain loop, not memcpy.
      const double* base = f_const_.data();
      const double z = opaque_zero_;
      for (Index i = 0; i < n_; ++i) op[i] = base[i] + z;
    }
    for (; g != groups_.end(); ++g) g->kernel(*this, *g, up, vp, t, op);
  }
  void tangent(const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) const {
    K.setZero();
    C.setZero();
    for (const Group& g : groups_)
      dispatch(g.law, [&](auto L) { add_tangents<L()>(g, u, v, t, K, C); });
  }
  // Flags of the evaluated part (K and C carry the rest).
  bool uses_velocity() const { return active_velocity_; }
  bool uses_time() const { return uses_time_; }
  bool is_linear() const { return linear_; }

  // Energy accounting over the effects evaluated each step and the constant
  // loads; the model adds what K and C carry.
  double potential(const CVecRef& u, double t) const {
    double e = 0.0;
    for (const Group& g : groups_)
      e += dispatch(g.law, [&](auto L) {
        double s = 0.0;
        for (const Term* c = g.begin; c != g.end; ++c) s += law_potential<L()>(c->p, measure(*c, u), t);
        return s;
      });
    return e;
  }
  double input_power(const CVecRef& u, const CVecRef& v, double t) const {
    double p = -f_const_.dot(v);
    for (const Group& g : groups_)
      p += dispatch(g.law, [&](auto L) {
        double s = 0.0;
        for (const Term* c = g.begin; c != g.end; ++c)
          s += law_input_power<L()>(c->p, measure(*c, u), measure(*c, v), t);
        return s;
      });
    return p;
  }
  double dissipated_power(const CVecRef& v) const {
    double p = 0.0;
    for (const Group& g : groups_)
      p += dispatch(g.law, [&](auto L) {
        double s = 0.0;
        if constexpr (law_is_dissipative(L()))
          for (const Term* c = g.begin; c != g.end; ++c) s += law_dissipated_power<L()>(c->p, measure(*c, v));
        return s;
      });
    return p;
  }

 private:
  // One evaluated effect. Its measure is idx_/coef_[first, last); one of one
  // or two entries is also kept inline in i0, i1, c0, c1 (c1 = 0 for one),
  // and one covering at least half the DOFs densely in dense_[offset, offset + n).
  struct Term {
    std::int32_t first = 0, last = 0;
    Index i0 = 0, i1 = 0;
    double c0 = 0.0, c1 = 0.0;
    Index offset = 0;
    LawParams p;
  };
  // dense_first: dense loads, evaluated first, whose first term writes the force vector;
  // unit: d = u_i0 (coefficient 1); difference: d = u_i0 - u_i1 (the common
  // spring or damper between two DOFs); two: any two coefficients.
  enum Storage { dense_first = 0, unit = 1, difference = 2, two = 3, sparse = 4, dense = 5 };
  struct Group;
  using Kernel = void (*)(const EffectSet&, const Group&, const double*, const double*, double, double*);
  // Consecutive terms with the same law and storage; kernel is add_forces<law, storage>.
  // writes: the first group, dense_first: its first term writes the force vector.
  struct Group {
    Law law;
    Storage storage;
    Kernel kernel;
    const Term *begin, *end;
    bool writes;
  };

  template <class V>
  double measure(const Term& c, const V& x) const {
    double d = 0.0;
    for (std::int32_t k = c.first; k < c.last; ++k) d += coef_[k] * x[idx_[k]];
    return d;
  }

  // g . x for storage S.
  template <Storage S>
  double measure_of(const Term& c, const double* x) const {
    if constexpr (S == unit) return x[c.i0];
    if constexpr (S == difference) return x[c.i0] - x[c.i1];
    if constexpr (S == two) return c.c0 * x[c.i0] + c.c1 * x[c.i1];
    if constexpr (S == dense || S == dense_first) {
      const double* w = dense_.data() + c.offset;
      double d = 0.0;
      for (Index i = 0; i < n_; ++i) d += w[i] * x[i];
      return d;
    }
    double d = 0.0;
    for (std::int32_t k = c.first; k < c.last; ++k) d += coef_[k] * x[idx_[k]];
    return d;
  }

  template <Law L, Storage S>
  static void add_forces(const EffectSet& set, const Group& g, const double* u, const double* v, double t,
                         double* out) {
    for (const Term* c = g.begin; c != g.end; ++c) {
      const double d = law_uses_displacement(L) ? set.measure_of<S>(*c, u) : 0.0;
      const double dd = law_uses_velocity(L) ? set.measure_of<S>(*c, v) : 0.0;
      const double f = law_value<L>(c->p, d, dd, t);
      if constexpr (S == unit) {
        out[c->i0] += f;
      } else if constexpr (S == difference) {
        out[c->i0] += f;
        out[c->i1] -= f;
      } else if constexpr (S == two) {
        if constexpr (L == Law::hertz_contact)
          if (f == 0.0) continue;  // an open contact adds nothing
        out[c->i0] += c->c0 * f;
        out[c->i1] += c->c1 * f;
      } else if constexpr (S == dense || S == dense_first) {
        const double* w = set.dense_.data() + c->offset;
        if (S == dense_first && g.writes && c == g.begin) {
          const double* base = set.f_const_.data();
          for (Index i = 0; i < set.n_; ++i) out[i] = base[i] + w[i] * f;
        } else {
          for (Index i = 0; i < set.n_; ++i) out[i] += w[i] * f;
        }
      } else {
        const Index* idx = set.idx_.data();
        const double* coef = set.coef_.data();
        for (std::int32_t k = c->first; k < c->last; ++k) out[idx[k]] += coef[k] * f;
      }
    }
  }
  static Kernel kernel_for(Law law, Storage s) {
    return dispatch(law, [&](auto L) -> Kernel {
      switch (s) {
        case dense_first: return &add_forces<L(), dense_first>;
        case unit: return &add_forces<L(), unit>;
        case difference: return &add_forces<L(), difference>;
        case two: return &add_forces<L(), two>;
        case dense: return &add_forces<L(), dense>;
        case sparse: break;
      }
      return &add_forces<L(), sparse>;
    });
  }

  template <Law L>
  void add_tangents(const Group& g, const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) const {
    if constexpr (law_is_load(L)) return;  // loads do not depend on the state
    for (const Term* c = g.begin; c != g.end; ++c) {
      const double kd = law_uses_displacement(L) ? law_dvalue_dd<L>(c->p, measure(*c, u), t) : 0.0;
      const double cd = law_uses_velocity(L) ? law_dvalue_dv<L>(c->p, measure(*c, v)) : 0.0;
      if (kd == 0.0 && cd == 0.0) continue;
      MatRef& A = law_uses_velocity(L) ? C : K;
      const double s = law_uses_velocity(L) ? cd : kd;
      for (std::int32_t i = c->first; i < c->last; ++i)
        for (std::int32_t j = c->first; j < c->last; ++j) A(idx_[i], idx_[j]) += s * coef_[i] * coef_[j];
    }
  }

  // Flat, grouped form of active_ (rebuilt on copy: terms point at active_'s signals).
  void compile() {
    n_ = f_const_.size();
    auto storage = [&](size_t i) {
      const Effect& e = active_[i];
      const Index m = static_cast<Index>(e.index.size());
      if (m == 1 && e.coef[0] == 1.0) return unit;
      if (m == 2 && e.coef[0] == 1.0 && e.coef[1] == -1.0 && e.index[0] != e.index[1]) return difference;
      if (m <= 2) return two;
      if (2 * m < n_) return sparse;
      return law_is_load(e.law) ? dense_first : dense;  // a load's force needs no measure
    };
    std::vector<size_t> order(active_.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    // Dense loads first, then by law and storage: each group is one instantiated loop.
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) {
      const bool fa = storage(a) == dense_first, fb = storage(b) == dense_first;
      if (fa != fb) return fa;
      return active_[a].law != active_[b].law ? active_[a].law < active_[b].law : storage(a) < storage(b);
    });
    idx_.clear();
    coef_.clear();
    dense_.clear();
    terms_.clear();
    terms_.reserve(active_.size());
    for (size_t i : order) {
      const Effect& e = active_[i];
      Term c;
      c.first = static_cast<std::int32_t>(idx_.size());
      idx_.insert(idx_.end(), e.index.begin(), e.index.end());
      coef_.insert(coef_.end(), e.coef.begin(), e.coef.end());
      c.last = static_cast<std::int32_t>(idx_.size());
      if (!e.index.empty()) {
        c.i0 = c.i1 = e.index[0];
        c.c0 = e.coef[0];
      }
      if (e.index.size() > 1) {
        c.i1 = e.index[1];
        c.c1 = e.coef[1];
      }
      const Storage st = storage(i);
      if (st == dense || st == dense_first) {
        c.offset = static_cast<Index>(dense_.size());
        dense_.resize(dense_.size() + static_cast<size_t>(n_), 0.0);
        for (size_t k = 0; k < e.index.size(); ++k) dense_[static_cast<size_t>(c.offset + e.index[k])] += e.coef[k];
      }
      c.p = e.params();
      terms_.push_back(c);
    }
    groups_.clear();
    for (size_t i = 0; i < terms_.size(); ++i) {
      const Law law = active_[order[i]].law;
      const Storage st = storage(order[i]);
      if (groups_.empty() || groups_.back().law != law || groups_.back().storage != st)
        groups_.push_back({law, st, kernel_for(law, st), &terms_[i], &terms_[i], false});
      groups_.back().end = &terms_[i] + 1;
    }
    if (!groups_.empty() && groups_.front().storage == dense_first) groups_.front().writes = true;
  }

  std::vector<Effect> all_, active_;
  Vector f_const_;
  bool uses_time_ = false, linear_ = true, active_velocity_ = false;
  Index n_ = 0;
  double opaque_zero_ = 0.0;  // see operator()
  std::vector<Index> idx_;
  std::vector<double> coef_, dense_;
  std::vector<Term> terms_;
  std::vector<Group> groups_;
};

// The declared effects plus one more force functor (a user's C++ law, or
// Python callables through the binding): f = effects + extra. Flags are
// or-ed (linear only if both are); the tangent is analytic only if both have
// one (the model differentiates the sum otherwise); energy is accounted
// only if both account for it.
template <class Extra>
class EffectsPlus {
 public:
  EffectsPlus() = default;
  EffectsPlus(EffectSet effects, Extra extra, Index n)
      : effects_(std::move(effects)), extra_(std::move(extra)), work_(Vector::Zero(n)), K2_(Matrix::Zero(n, n)),
        C2_(Matrix::Zero(n, n)) {}

  const EffectSet& effects() const { return effects_; }
  Extra& extra() { return extra_; }
  const Extra& extra() const { return extra_; }

  void operator()(const CVecRef& u, const CVecRef& v, double t, VecRef out) {
    effects_(u, v, t, out);
    extra_(u, v, t, work_);
    out += work_;
  }
  bool has_tangent() const { return traits::has_tangent(extra_); }
  void tangent(const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) {
    effects_.tangent(u, v, t, K, C);
    if constexpr (traits::has_tangent_method<Extra>::value) {
      extra_.tangent(u, v, t, K2_, C2_);
      K += K2_;
      C += C2_;
    }
  }
  bool uses_velocity() const { return effects_.uses_velocity() || traits::uses_velocity(extra_); }
  bool uses_time() const { return effects_.uses_time() || traits::uses_time(extra_); }
  bool is_linear() const { return effects_.is_linear() && traits::is_linear(extra_); }

  bool accounts_energy() const {
    if constexpr (traits::has_energy<Extra>::value) return traits::accounts_energy(extra_);
    return false;
  }
  double potential(const CVecRef& u, double t) const {
    double e = effects_.potential(u, t);
    if constexpr (traits::has_energy<Extra>::value) e += extra_.potential(u, t);
    return e;
  }
  double input_power(const CVecRef& u, const CVecRef& v, double t) const {
    double p = effects_.input_power(u, v, t);
    if constexpr (traits::has_energy<Extra>::value) p += extra_.input_power(u, v, t);
    return p;
  }
  double dissipated_power(const CVecRef& v) const {
    double p = effects_.dissipated_power(v);
    if constexpr (traits::has_energy<Extra>::value) p += extra_.dissipated_power(v);
    return p;
  }

 private:
  EffectSet effects_;
  Extra extra_;
  Vector work_;     // the extra force
  Matrix K2_, C2_;  // the extra tangent
};

namespace detail_ {
// Springs and dampers assembled once into K and C (added to the optional
// K_extra, C_extra); constant loads and the rest go to the EffectSet.
struct Assembled {
  Matrix K, C;  // empty when nothing contributes
  EffectSet set;
};
inline Assembled assemble(const Mass& mass, std::vector<Effect> list, const Matrix& K_extra, const Matrix& C_extra) {
  const Index n = mass.size();
  Matrix K = Matrix::Zero(n, n), C = Matrix::Zero(n, n);
  bool anyK = K_extra.size() > 0, anyC = C_extra.size() > 0;
  if (anyK) {
    nvib::detail::require(K_extra.rows() == n && K_extra.cols() == n, "K: wrong shape");
    K += K_extra;
  }
  if (anyC) {
    nvib::detail::require(C_extra.rows() == n && C_extra.cols() == n, "C: wrong shape");
    C += C_extra;
  }
  EffectSet set(std::move(list), mass);
  for (const auto& e : set.effects()) {
    if (e.law != Law::spring && e.law != Law::damper) continue;
    Matrix& A = e.law == Law::spring ? K : C;
    (e.law == Law::spring ? anyK : anyC) = true;
    for (size_t i = 0; i < e.index.size(); ++i)
      for (size_t j = 0; j < e.index.size(); ++j) A(e.index[i], e.index[j]) += e.p0 * e.coef[i] * e.coef[j];
  }
  return {anyK ? K : Matrix(), anyC ? C : Matrix(), std::move(set)};
}
}  // namespace detail_

// Model from a mass and the declared effects: springs and dampers assembled
// once into K and C (added to the optional K_extra, C_extra), constant loads
// into a constant vector, the rest evaluated each step.
inline Model<EffectSet> make_effect_model(Mass mass, std::vector<Effect> list, Matrix K_extra = Matrix(),
                                          Matrix C_extra = Matrix()) {
  auto a = detail_::assemble(mass, std::move(list), K_extra, C_extra);
  return Model<EffectSet>(std::move(mass), std::move(a.K), std::move(a.C), std::move(a.set));
}

// The same plus one more force functor evaluated with the effects.
template <class Extra>
Model<EffectsPlus<Extra>> make_effect_model(Mass mass, std::vector<Effect> list, Extra extra,
                                            Matrix K_extra = Matrix(), Matrix C_extra = Matrix()) {
  const Index n = mass.size();
  auto a = detail_::assemble(mass, std::move(list), K_extra, C_extra);
  return Model<EffectsPlus<Extra>>(std::move(mass), std::move(a.K), std::move(a.C),
                                   EffectsPlus<Extra>(std::move(a.set), std::move(extra), n));
}

}  // namespace effects
}  // namespace nvib
