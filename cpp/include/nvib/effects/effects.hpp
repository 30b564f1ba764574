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
#include <string>
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

struct Effect {
  Law law = Law::spring;
  std::string name;          // optional; scenes use it to switch effects off
  std::vector<Index> index;  // DOFs of the measure
  std::vector<double> coef;  // g entries
  double p0 = 0.0, p1 = 0.0, p2 = 0.0;  // law parameters (see the factories)
  Signal signal;             // a_g(t) for ground_acceleration, r(t) for hertz_contact

  bool uses_velocity() const { return law == Law::damper || law == Law::power_damper; }
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
  bool is_load() const {
    return law == Law::constant_force || law == Law::harmonic_force || law == Law::ground_acceleration;
  }
  bool is_dissipative() const { return law == Law::damper || law == Law::power_damper; }

  template <class V>
  double measure(const V& x) const {
    double d = 0.0;
    for (size_t i = 0; i < index.size(); ++i) d += coef[i] * x[index[i]];
    return d;
  }

  // Scalar law f(d, d', t) (loads: -P) and its derivatives.
  double value(double d, double dd, double t) const {
    switch (law) {
      case Law::spring: return p0 * d;
      case Law::damper: return p0 * dd;
      case Law::hardening_spring: return p0 * (1.0 + p1 * d * d) * d;
      case Law::cubic_spring: return p0 * d * d * d;
      case Law::power_damper: return dd == 0.0 ? 0.0 : std::copysign(p0 * std::pow(std::abs(dd), p1), dd);
      case Law::pendulum_gravity: return p0 * std::sin(d);
      case Law::hertz_contact: {
        const double delta = d - signal.value(t);
        return delta > 0.0 ? p1 * std::pow(delta / p0, 1.5) : 0.0;
      }
      case Law::constant_force: return -p0;
      case Law::harmonic_force: return -p0 * std::sin(p1 * t + p2);
      case Law::ground_acceleration: return signal.value(t);  // g = M r, so g^T f = -P
    }
    return 0.0;
  }
  double dvalue_dd(double d, double t) const {
    switch (law) {
      case Law::spring: return p0;
      case Law::hardening_spring: return p0 * (1.0 + 3.0 * p1 * d * d);
      case Law::cubic_spring: return 3.0 * p0 * d * d;
      case Law::pendulum_gravity: return p0 * std::cos(d);
      case Law::hertz_contact: {
        const double delta = d - signal.value(t);
        return delta > 0.0 ? 1.5 * p1 / p0 * std::sqrt(delta / p0) : 0.0;
      }
      default: return 0.0;
    }
  }
  double dvalue_dv(double dd) const {
    switch (law) {
      case Law::damper: return p0;
      case Law::power_damper: {
        // d/dd' of c |d'|^p sign(d'); at d' = 0 with p < 1 the slope is
        // unbounded, and the linear damper's c is used instead.
        const double s = std::abs(dd);
        if (s == 0.0) return p1 == 1.0 ? p0 : (p1 > 1.0 ? 0.0 : p0);
        return p0 * p1 * std::pow(s, p1 - 1.0);
      }
      default: return 0.0;
    }
  }
  // Potential energy of a conservative law at t (0 for dampers and loads).
  double potential(double d, double t) const {
    switch (law) {
      case Law::spring: return 0.5 * p0 * d * d;
      case Law::hardening_spring: return p0 * (0.5 * d * d + 0.25 * p1 * d * d * d * d);
      case Law::cubic_spring: return 0.25 * p0 * d * d * d * d;
      case Law::pendulum_gravity: return p0 * (1.0 - std::cos(d));
      case Law::hertz_contact: {
        const double delta = d - signal.value(t);
        return delta > 0.0 ? p1 * p0 * std::pow(delta / p0, 2.5) / 2.5 : 0.0;
      }
      default: return 0.0;
    }
  }
  // Power put into the system from outside: loads (P . v) and a moving rail
  // (the contact potential V(d - r(t)) changes at the rate -f r'(t)).
  double input_power(double d, double dd, double t) const {
    if (is_load()) return -value(d, dd, t) * dd;
    if (law == Law::hertz_contact && signal.present()) return -value(d, dd, t) * signal.derivative(t);
    return 0.0;
  }
  double dissipated_power(double dd) const { return is_dissipative() ? value(0.0, dd, 0.0) * dd : 0.0; }
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
      uses_velocity_ = uses_velocity_ || e.uses_velocity();
      uses_time_ = uses_time_ || e.uses_time();
      linear_ = linear_ && e.is_linear();
      if (e.law == Law::spring || e.law == Law::damper) continue;  // assembled into K, C
      if (e.law == Law::constant_force) {
        for (size_t k = 0; k < e.index.size(); ++k) f_const_[e.index[k]] -= e.coef[k] * e.p0;
        has_const_ = true;
        continue;
      }
      active_.push_back(e);
      active_velocity_ = active_velocity_ || e.uses_velocity();
    }
  }

  const std::vector<Effect>& effects() const { return all_; }
  const std::vector<Effect>& evaluated() const { return active_; }
  const Vector& constant_load() const { return f_const_; }  // -P of the constant loads

  void operator()(const CVecRef& u, const CVecRef& v, double t, VecRef out) const {
    if (has_const_)
      out = f_const_;
    else
      out.setZero();
    for (const auto& e : active_) {
      const double f = e.value(e.measure(u), e.uses_velocity() ? e.measure(v) : 0.0, t);
      if (f == 0.0) continue;
      for (size_t i = 0; i < e.index.size(); ++i) out[e.index[i]] += e.coef[i] * f;
    }
  }
  void tangent(const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) const {
    K.setZero();
    C.setZero();
    for (const auto& e : active_) {
      const double kd = e.dvalue_dd(e.measure(u), t);
      const double cd = e.uses_velocity() ? e.dvalue_dv(e.measure(v)) : 0.0;
      if (kd == 0.0 && cd == 0.0) continue;
      for (size_t i = 0; i < e.index.size(); ++i)
        for (size_t j = 0; j < e.index.size(); ++j) {
          K(e.index[i], e.index[j]) += kd * e.coef[i] * e.coef[j];
          C(e.index[i], e.index[j]) += cd * e.coef[i] * e.coef[j];
        }
    }
  }
  // Flags of the evaluated part (K and C carry the rest).
  bool uses_velocity() const { return active_velocity_; }
  bool uses_time() const { return uses_time_; }
  bool is_linear() const { return linear_; }

  // Energy accounting over the effects evaluated each step and the constant
  // loads; the model adds what K and C carry.
  double potential(const CVecRef& u, double t) const {
    double e = 0.0;
    for (const auto& x : active_) e += x.potential(x.measure(u), t);
    return e;
  }
  double input_power(const CVecRef& u, const CVecRef& v, double t) const {
    double p = has_const_ ? -f_const_.dot(v) : 0.0;
    for (const auto& x : active_) p += x.input_power(x.measure(u), x.measure(v), t);
    return p;
  }
  double dissipated_power(const CVecRef& v) const {
    double p = 0.0;
    for (const auto& x : active_)
      if (x.is_dissipative()) p += x.dissipated_power(x.measure(v));
    return p;
  }

 private:
  std::vector<Effect> all_, active_;
  Vector f_const_;
  bool has_const_ = false;
  bool uses_velocity_ = false, uses_time_ = false, linear_ = true, active_velocity_ = false;
};

// Model from a mass and the declared effects: springs and dampers assembled
// once into K and C (added to the optional K_extra, C_extra), constant loads
// into a constant vector, the rest evaluated each step.
inline Model<EffectSet> make_effect_model(Mass mass, std::vector<Effect> list, Matrix K_extra = Matrix(),
                                          Matrix C_extra = Matrix()) {
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
  return Model<EffectSet>(std::move(mass), anyK ? K : Matrix(), anyC ? C : Matrix(), std::move(set));
}

}  // namespace effects
}  // namespace nvib
