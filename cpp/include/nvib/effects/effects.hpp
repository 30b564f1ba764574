// Built-in effects: each a scalar law f(d, d', t) on a measure d = g . u
// (g a sparse row over DOFs); its force enters the equation of motion as g^T f.
// Loads are effects too: their law is -P(t) along g.
//
// EffectSet is a force functor for Model: linear effects (springs, dampers)
// are assembled once into constant K and C by make_effect_model; only the
// others are evaluated each step.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "../core/model.hpp"

namespace nvib {
namespace effects {

enum class Law {
  spring,            // f = k d
  damper,            // f = c d'
  hardening_spring,  // f = k0 (1 + a d^2) d
  cubic_spring,      // f = k3 d^3
  pendulum_gravity,  // f = m g l sin(d)
  constant_force,    // load P = value along g (f = -value)
  harmonic_force,    // load P = amplitude sin(omega t + phase) along g
};

inline const char* to_string(Law l) {
  switch (l) {
    case Law::spring: return "spring";
    case Law::damper: return "damper";
    case Law::hardening_spring: return "hardening_spring";
    case Law::cubic_spring: return "cubic_spring";
    case Law::pendulum_gravity: return "pendulum_gravity";
    case Law::constant_force: return "constant_force";
    case Law::harmonic_force: return "harmonic_force";
  }
  return "?";
}

struct Effect {
  Law law = Law::spring;
  std::vector<Index> index;  // DOFs of the measure
  std::vector<double> coef;  // g entries
  double p0 = 0.0, p1 = 0.0, p2 = 0.0;  // law parameters (see the factories)

  bool uses_velocity() const { return law == Law::damper; }
  bool uses_time() const { return law == Law::harmonic_force; }
  bool is_linear() const { return law != Law::hardening_spring && law != Law::cubic_spring && law != Law::pendulum_gravity; }
  bool is_load() const { return law == Law::constant_force || law == Law::harmonic_force; }

  template <class V>
  double measure(const V& x) const {
    double d = 0.0;
    for (size_t i = 0; i < index.size(); ++i) d += coef[i] * x[index[i]];
    return d;
  }

  // Scalar law f(d, d', t) and its derivatives.
  double value(double d, double dd, double t) const {
    switch (law) {
      case Law::spring: return p0 * d;
      case Law::damper: return p0 * dd;
      case Law::hardening_spring: return p0 * (1.0 + p1 * d * d) * d;
      case Law::cubic_spring: return p0 * d * d * d;
      case Law::pendulum_gravity: return p0 * std::sin(d);
      case Law::constant_force: return -p0;
      case Law::harmonic_force: return -p0 * std::sin(p1 * t + p2);
    }
    return 0.0;
  }
  double dvalue_dd(double d) const {
    switch (law) {
      case Law::spring: return p0;
      case Law::hardening_spring: return p0 * (1.0 + 3.0 * p1 * d * d);
      case Law::cubic_spring: return 3.0 * p0 * d * d;
      case Law::pendulum_gravity: return p0 * std::cos(d);
      default: return 0.0;
    }
  }
  double dvalue_dv() const { return law == Law::damper ? p0 : 0.0; }
  // Potential energy of a conservative law (0 for dampers and loads).
  double potential(double d) const {
    switch (law) {
      case Law::spring: return 0.5 * p0 * d * d;
      case Law::hardening_spring: return p0 * (0.5 * d * d + 0.25 * p1 * d * d * d * d);
      case Law::cubic_spring: return 0.25 * p0 * d * d * d * d;
      case Law::pendulum_gravity: return p0 * (1.0 - std::cos(d));
      default: return 0.0;
    }
  }
};

namespace detail_ {
inline Effect make(Law law, std::vector<std::pair<Index, double>> g, double p0, double p1 = 0.0, double p2 = 0.0) {
  Effect e;
  e.law = law;
  nvib::detail::require(!g.empty(), "measure: an effect needs at least one DOF in its measure");
  for (auto& [i, c] : g) {
    nvib::detail::require(i >= 0, "measure: negative DOF index " + std::to_string(i));
    nvib::detail::require(std::isfinite(c), "measure: non-finite coefficient");
    e.index.push_back(i);
    e.coef.push_back(c);
  }
  nvib::detail::require(std::isfinite(p0) && std::isfinite(p1) && std::isfinite(p2),
                        std::string(to_string(law)) + ": parameters must be finite");
  e.p0 = p0;
  e.p1 = p1;
  e.p2 = p2;
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
inline Effect pendulum_gravity(Measure g, double mgl) { return detail_::make(Law::pendulum_gravity, std::move(g), mgl); }
inline Effect constant_force(Measure g, double value) { return detail_::make(Law::constant_force, std::move(g), value); }
inline Effect harmonic_force(Measure g, double amplitude, double omega, double phase = 0.0) {
  return detail_::make(Law::harmonic_force, std::move(g), amplitude, omega, phase);
}

// The effects evaluated each step (everything except springs and dampers).
class EffectSet {
 public:
  EffectSet() = default;
  EffectSet(std::vector<Effect> list, Index ndofs) : all_(std::move(list)) {
    for (size_t i = 0; i < all_.size(); ++i)
      for (Index d : all_[i].index)
        nvib::detail::require(d < ndofs, "effects[" + std::to_string(i) + "].measure: DOF index " +
                                             std::to_string(d) + " is out of range for " +
                                             std::to_string(ndofs) + " degrees of freedom");
    for (const auto& e : all_) {
      const bool assembled = e.law == Law::spring || e.law == Law::damper;
      if (!assembled) active_.push_back(e);
      uses_velocity_ = uses_velocity_ || e.uses_velocity();
      uses_time_ = uses_time_ || e.uses_time();
      linear_ = linear_ && e.is_linear();
    }
    // Springs and dampers are in K and C; active effects that use velocity:
    active_velocity_ = false;
    for (const auto& e : active_) active_velocity_ = active_velocity_ || e.uses_velocity();
  }

  const std::vector<Effect>& effects() const { return all_; }
  const std::vector<Effect>& evaluated() const { return active_; }

  void operator()(const CVecRef& u, const CVecRef& v, double t, VecRef out) const {
    out.setZero();
    for (const auto& e : active_) {
      const double f = e.value(e.measure(u), e.uses_velocity() ? e.measure(v) : 0.0, t);
      for (size_t i = 0; i < e.index.size(); ++i) out[e.index[i]] += e.coef[i] * f;
    }
  }
  void tangent(const CVecRef& u, const CVecRef&, double, MatRef K, MatRef C) const {
    K.setZero();
    C.setZero();
    for (const auto& e : active_) {
      const double kd = e.dvalue_dd(e.measure(u));
      const double cd = e.dvalue_dv();
      for (size_t i = 0; i < e.index.size(); ++i)
        for (size_t j = 0; j < e.index.size(); ++j) {
          K(e.index[i], e.index[j]) += kd * e.coef[i] * e.coef[j];
          if (cd != 0.0) C(e.index[i], e.index[j]) += cd * e.coef[i] * e.coef[j];
        }
    }
  }
  // Flags of the evaluated part (K and C carry the rest).
  bool uses_velocity() const { return active_velocity_; }
  bool uses_time() const { return uses_time_; }
  bool is_linear() const { return linear_; }

  // Potential energy of all conservative effects (springs included).
  double potential(const CVecRef& u) const {
    double e = 0.0;
    for (const auto& x : all_) e += x.potential(x.measure(u));
    return e;
  }

 private:
  std::vector<Effect> all_, active_;
  bool uses_velocity_ = false, uses_time_ = false, linear_ = true, active_velocity_ = false;
};

// Model from a mass and declared effects: springs and dampers assembled once
// into K and C (added to the optional K_extra, C_extra), the rest evaluated.
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
  EffectSet set(std::move(list), n);
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
