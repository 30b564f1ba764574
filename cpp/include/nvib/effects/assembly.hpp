// A model from a mass and the declared effects: springs and dampers assembled
// once into K and C, constant loads into a constant vector, the rest
// evaluated each step; optionally one more force functor (a user's C++ law,
// or Python callables through the binding).
#pragma once

#include <utility>
#include <vector>

#include "../core/model.hpp"
#include "effect_set.hpp"

namespace nvib {
namespace effects {

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
  void magnitude(const CVecRef& u, const CVecRef& v, double t, VecRef out) {
    effects_.magnitude(u, v, t, out);
    extra_(u, v, t, work_);
    out += work_.cwiseAbs();
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
// K_extra, C_extra plus the springs and dampers of the list; the rest in the EffectSet.
inline std::pair<LinearParts, EffectSet> assemble(const Mass& mass, std::vector<Effect> list, const Matrix& K_extra,
                                                  const Matrix& C_extra) {
  const Index n = mass.size();
  LinearParts lin;
  if (K_extra.size() > 0) {
    NVIB_CHECK(K_extra.rows() == n && K_extra.cols() == n, "K", "wrong shape");
    lin.K = K_extra;
  }
  if (C_extra.size() > 0) {
    NVIB_CHECK(C_extra.rows() == n && C_extra.cols() == n, "C", "wrong shape");
    lin.C = C_extra;
  }
  EffectSet set(std::move(list), mass, &lin);
  return {std::move(lin), std::move(set)};
}
}  // namespace detail_

inline Model<EffectSet> make_effect_model(Mass mass, std::vector<Effect> list, Matrix K_extra = Matrix(),
                                          Matrix C_extra = Matrix()) {
  auto [lin, set] = detail_::assemble(mass, std::move(list), K_extra, C_extra);
  return Model<EffectSet>(std::move(mass), std::move(lin.K), std::move(lin.C), std::move(set));
}

template <class Extra>
Model<EffectsPlus<Extra>> make_effect_model(Mass mass, std::vector<Effect> list, Extra extra,
                                            Matrix K_extra = Matrix(), Matrix C_extra = Matrix()) {
  const Index n = mass.size();
  auto [lin, set] = detail_::assemble(mass, std::move(list), K_extra, C_extra);
  return Model<EffectsPlus<Extra>>(std::move(mass), std::move(lin.K), std::move(lin.C),
                                   EffectsPlus<Extra>(std::move(set), std::move(extra), n));
}

}  // namespace effects
}  // namespace nvib
