// EffectSet: the declared effects as a force functor for Model, a handle on
// their compiled form (compiled_effects.hpp) shared by its copies.
//
// Every effect it is given acts: with a LinearParts to assemble into, linear
// springs and dampers go into K and C once; without one they are evaluated
// like the rest. Constant loads go into a constant vector; the other effects
// are compiled once into flat terms grouped by law and by how their measures
// are stored (compiled_terms.hpp): one indirect call per group, never per
// effect, and no switch in the loop. A load reads no measure, a spring no velocity.
//
// The force vector is first *written* (constant loads plus the dense loads,
// which need no state) and then accumulated into. Zeroing it first is a
// memset call whose wide stores the effects' narrow read-modify-writes then
// wait on; measured 30% slower on the building scene.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <utility>
#include <vector>

#include "compiled_effects.hpp"

namespace nvib {
namespace effects {

class EffectSet {
 public:
  EffectSet() = default;
  // `mass` turns ground accelerations' influence vectors r into M r. Effects come one by one (list)
  // and as arrays of one law (arrays).
  EffectSet(std::vector<Effect> list, const Mass& mass, LinearParts* linear = nullptr,
            std::vector<EffectArray> arrays = {})
      : c_(std::make_shared<const CompiledEffects>(std::move(list), mass, linear, std::move(arrays))) {}

  const std::vector<Effect>& effects() const { return c_->effects(); }
  const std::vector<EffectArray>& arrays() const { return c_->arrays(); }
  size_t num_evaluated() const { return c_->num_evaluated(); }  // single effects and those of arrays
  const Vector& constant_load() const { return c_->constant_load(); }  // -P of the constant loads
  // The entries of the linear springs (law spring) or dampers (law damper) of the arrays, which are
  // evaluated by their kernels rather than assembled: added to K or C where those are shown.
  void add_linear_array_entries(Law law, std::vector<Eigen::Triplet<double, int>>& out) const {
    for (const arrays::ArrayGroup& g : c_->array_groups())
      if (g.law == law)
        for (size_t k = 0; k < g.size; ++k)
          arrays::for_each_pair(g, k, [&](int r, int col, double gg) { out.emplace_back(r, col, gg * g.params(k).p0); });
  }

  void operator()(const CVecRef& u, const CVecRef& v, double t, VecRef out) const {
    eval(u.data(), v.data(), t, out.data());
  }
  // The same on contiguous storage of size(): Model calls it with its vectors' data, no Eigen::Ref formed.
  void eval(const double* up, const double* vp, double t, double* op) const {
    const compiled::Arrays& a = c_->arrays_of_terms();
    auto g = c_->groups().begin();
    if (g != c_->groups().end() && g->writes) {
      g->kernel(a, *g, up, vp, t, op);  // writes constant loads + its loads
      ++g;
    } else {
      // A stored zero the compiler cannot see through keeps this a plain loop, not memcpy.
      const double* base = a.f_const.data();
      const double z = opaque_zero_;
      for (Index i = 0; i < a.n; ++i) op[i] = base[i] + z;
    }
    for (; g != c_->groups().end(); ++g) g->kernel(a, *g, up, vp, t, op);
    for (const arrays::ArrayGroup& ag : c_->array_groups()) ag.kernel(ag, up, vp, t, op);
  }
  void tangent(const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) const {
    const compiled::Arrays& a = c_->arrays_of_terms();
    double *k = K.data(), *c = C.data();
    const Index ld = K.outerStride();
    if (ld == K.rows() && C.outerStride() == ld) {  // contiguous: one fill each
      std::fill_n(k, K.size(), 0.0);
      std::fill_n(c, C.size(), 0.0);
    } else {
      K.setZero();
      C.setZero();
    }
    for (const compiled::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) { compiled::add_tangents<decltype(L)>(a, g, u.data(), v.data(), t, k, c, ld); });
    for (const arrays::ArrayGroup& ag : c_->array_groups())
      dispatch(ag.law, [&](auto L) { arrays::add_tangents<decltype(L)>(ag, u.data(), v.data(), t, k, c, ld); });
  }
  // The tangent entry by entry (sparse models): entries once, values at each state, in the same order.
  void tangent_entries(std::vector<Entry>& K, std::vector<Entry>& C) const {
    const compiled::Arrays& a = c_->arrays_of_terms();
    for (const compiled::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) { compiled::tangent_entries<decltype(L)>(a, g, K, C); });
    for (const arrays::ArrayGroup& ag : c_->array_groups())
      dispatch(ag.law, [&](auto L) { arrays::tangent_entries<decltype(L)>(ag, K, C); });
  }
  void tangent_values(const CVecRef& u, const CVecRef& v, double t, double* K, double* C) const {
    const compiled::Arrays& a = c_->arrays_of_terms();
    for (const compiled::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) { compiled::tangent_values<decltype(L)>(a, g, u.data(), v.data(), t, K, C); });
    for (const arrays::ArrayGroup& ag : c_->array_groups())
      dispatch(ag.law, [&](auto L) { arrays::tangent_values<decltype(L)>(ag, u.data(), v.data(), t, K, C); });
  }
  // out_i = |constant loads|_i + sum over terms of |g_i f|: the round-off scale of the force.
  void magnitude(const CVecRef& u, const CVecRef& v, double t, VecRef out) const {
    const compiled::Arrays& a = c_->arrays_of_terms();
    out = a.f_const.cwiseAbs();
    for (const compiled::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) {
        for (const compiled::Term* c = g.begin; c != g.end; ++c) {
          const double f = std::abs(decltype(L)::value(c->p, a.measure(g.storage, *c, u), a.measure(g.storage, *c, v), t));
          a.for_each_entry(g.storage, *c, [&](Index i, double gi) { out[i] += std::abs(gi) * f; });
        }
      });
    for (const arrays::ArrayGroup& ag : c_->array_groups())
      dispatch(ag.law, [&](auto L) {
        for (size_t k = 0; k < ag.size; ++k) {
          const double f = std::abs(decltype(L)::value(ag.params(k), ag.measure(k, u), ag.measure(k, v), t));
          out[ag.i[k]] += f;
          if (ag.j[k] >= 0) out[ag.j[k]] += f;
        }
      });
  }
  // Flags of the evaluated part (K and C carry the rest).
  bool uses_velocity() const { return c_->uses_velocity(); }
  bool uses_time() const { return c_->uses_time(); }
  bool is_linear() const { return c_->is_linear(); }

  // Energy accounting over the effects evaluated each step and the constant
  // loads; the model adds what K and C carry.
  double potential(const CVecRef& u, double t) const {
    const compiled::Arrays& a = c_->arrays_of_terms();
    const double e = sum_terms(0.0, [&](auto L, compiled::Storage s, const compiled::Term& c) {
      return decltype(L)::potential(c.p, a.measure(s, c, u), t);
    });
    return sum_arrays(e, u.data(), nullptr, [&](auto L, const LawParams& p, double d, double) {
      return decltype(L)::potential(p, d, t);
    });
  }
  // Whether the input power can jump in time (a signal whose rate jumps): only then does it matter which
  // side of a step point input_power() takes.
  bool power_jumps() const {
    for (const Effect& e : effects())
      if (e.signal.rate_jumps()) return true;
    for (const EffectArray& a : arrays())
      if (a.signal.rate_jumps()) return true;
    return false;
  }
  double input_power(const CVecRef& u, const CVecRef& v, double t, int side = 0) const {
    const compiled::Arrays& a = c_->arrays_of_terms();
    const double w = sum_terms(-a.f_const.dot(v), [&](auto L, compiled::Storage s, const compiled::Term& c) {
      return effects::input_power<decltype(L)>(c.p, a.measure(s, c, u), a.measure(s, c, v), t, side);
    });
    return sum_arrays(w, u.data(), v.data(), [&](auto L, const LawParams& p, double d, double dd) {
      return effects::input_power<decltype(L)>(p, d, dd, t, side);
    });
  }
  double dissipated_power(const CVecRef& v) const {
    const compiled::Arrays& a = c_->arrays_of_terms();
    const double w = sum_terms(0.0, [&](auto L, compiled::Storage s, const compiled::Term& c) {
      using Lw = decltype(L);
      if constexpr (is_dissipative<Lw>()) {
        return effects::dissipated_power<Lw>(c.p, a.measure(s, c, v));
      } else {
        (void)c;
        return 0.0;
      }
    });
    return sum_arrays(w, nullptr, v.data(), [&](auto L, const LawParams& p, double, double dd) {
      using Lw = decltype(L);
      if constexpr (is_dissipative<Lw>()) {
        return effects::dissipated_power<Lw>(p, dd);
      } else {
        (void)p;
        (void)dd;
        return 0.0;
      }
    });
  }

 private:
  // init + sum over groups of the sum over their terms of fn(L, storage, term)
  template <class Fn>
  double sum_terms(double init, Fn&& fn) const {
    double e = init;
    for (const compiled::Group& g : c_->groups())
      e += dispatch(g.law, [&](auto L) {
        double s = 0.0;
        for (const compiled::Term* c = g.begin; c != g.end; ++c) s += fn(L, g.storage, *c);
        return s;
      });
    return e;
  }
  // init + sum over the arrays' effects of fn(L, params, measure of u, measure of v) (u, v may be null).
  template <class Fn>
  double sum_arrays(double init, const double* u, const double* v, Fn&& fn) const {
    double e = init;
    for (const arrays::ArrayGroup& g : c_->array_groups())
      e += dispatch(g.law, [&](auto L) {
        return arrays::sum(g, u, v, [&](const LawParams& p, double d, double dd) { return fn(L, p, d, dd); });
      });
    return e;
  }

  std::shared_ptr<const CompiledEffects> c_ = std::make_shared<const CompiledEffects>();
  double opaque_zero_ = 0.0;  // see operator()
};

}  // namespace effects
}  // namespace nvib
