// A model from a mass and the declared effects: springs and dampers assembled
// once into K and C, constant loads into a constant vector, the rest
// evaluated each step; optionally one more force functor (a user's C++ law,
// or Python callables through the binding).
#pragma once

#include <type_traits>
#include <utility>
#include <vector>

#include "../model/model.hpp"
#include "effect_set.hpp"

namespace nvib {
namespace effects {

// The declared effects plus one more force functor (a user's C++ law, or
// Python callables through the binding): f = effects + extra. Flags are
// or-ed (linear only if both are); the tangent is analytic only if both have
// one (the model differentiates the sum otherwise); energy is accounted
// only if both account for it; the states of laws with memory are the
// effects' followed by the extra force's (if it has any).
template <class Extra>
class EffectsPlus {
 public:
  EffectsPlus() = default;
  EffectsPlus(EffectSet effects, Extra extra, Index n)
      : effects_(std::move(effects)), extra_(std::move(extra)), work_(Vector::Zero(n)) {}

  const EffectSet& effects() const { return effects_; }
  EffectSet& effects() { return effects_; }
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
      if (K2_.rows() != K.rows()) {  // made at the first dense tangent: an explicit run never needs its n^2
        K2_.setZero(K.rows(), K.cols());
        C2_.setZero(C.rows(), C.cols());
      }
      extra_.tangent(u, v, t, K2_, C2_);
      K += K2_;
      C += C2_;
    }
  }
  // Entry by entry only if the extra force can too (Python laws on measures; not a vector callable).
  bool has_sparse_tangent() const {
    if constexpr (traits::has_sparse_tangent_method<Extra>::value) return traits::has_sparse_tangent(extra_);
    return false;
  }
  void tangent_entries(std::vector<Entry>& K, std::vector<Entry>& C) const {
    effects_.tangent_entries(K, C);
    ke_ = K.size();
    ce_ = C.size();
    if constexpr (traits::has_sparse_tangent_method<Extra>::value) extra_.tangent_entries(K, C);
  }
  void tangent_values(const CVecRef& u, const CVecRef& v, double t, double* K, double* C) {
    effects_.tangent_values(u, v, t, K, C);
    if constexpr (traits::has_sparse_tangent_method<Extra>::value) extra_.tangent_values(u, v, t, K + ke_, C + ce_);
  }
  double tangent_add(const CVecRef& u, const CVecRef& v, double t, TangentOut& out, std::size_t nk,
                     std::size_t nc) {
    double nonfinite = effects_.tangent_add(u, v, t, out, ke_, ce_);
    if constexpr (traits::has_sparse_tangent_method<Extra>::value) {
      double *K = out.K, *C = out.C;
      extra_.tangent_values(u, v, t, K, C);
      nonfinite += add_listed(out, nk - ke_, nc - ce_);
    }
    (void)nk, (void)nc;
    return nonfinite;
  }
  static constexpr bool magnitude_evaluates_force = true;  // the extra force is evaluated again
  void magnitude(const CVecRef& u, const CVecRef& v, double t, VecRef out) {
    effects_.magnitude(u, v, t, out);
    extra_(u, v, t, work_);
    out += work_.cwiseAbs();
  }
  bool uses_velocity() const { return effects_.uses_velocity() || traits::uses_velocity(extra_); }
  bool uses_time() const { return effects_.uses_time() || traits::uses_time(extra_); }
  bool is_linear() const { return effects_.is_linear() && traits::is_linear(extra_); }

  // ---- memory ----
  bool has_state() const { return effects_.has_state() || extra_state(); }
  Index state_size() const {
    Index n = effects_.state_size();
    if constexpr (traits::has_state_methods<Extra>::value) n += extra_.state_size();
    return n;
  }
  void get_state(double* out) const {
    effects_.get_state(out);
    if constexpr (traits::has_state_methods<Extra>::value) extra_.get_state(out + effects_.state_size());
  }
  void set_state(const double* x) {
    effects_.set_state(x);
    if constexpr (traits::has_state_methods<Extra>::value) extra_.set_state(x + effects_.state_size());
  }
  void reset_state() {
    effects_.reset_state();
    if constexpr (traits::has_state_methods<Extra>::value) extra_.reset_state();
  }
  void commit_last_trial(const double* u, const double* v, double t) {
    if (effects_.has_state()) effects_.commit_last_trial(u, v, t);
    if constexpr (traits::has_state_methods<Extra>::value)
      if (extra_.has_state()) extra_.commit_last_trial(u, v, t);
  }
  void commit_at(const double* u, const double* v, double t) {
    if (effects_.has_state()) effects_.commit_at(u, v, t);
    if constexpr (traits::has_state_methods<Extra>::value)
      if (extra_.has_state()) extra_.commit_at(u, v, t);
  }
  double hysteretic_dissipation() const {
    double e = effects_.hysteretic_dissipation();
    if constexpr (traits::has_hysteresis<Extra>::value) e += extra_.hysteretic_dissipation();
    return e;
  }

  bool accounts_energy() const {
    if constexpr (traits::has_energy<Extra>::value) return effects_.accounts_energy() && traits::accounts_energy(extra_);
    return false;
  }
  double potential(const CVecRef& u, double t) const {
    double e = effects_.potential(u, t);
    if constexpr (traits::has_energy<Extra>::value) e += extra_.potential(u, t);
    return e;
  }
  bool power_jumps() const { return effects_.power_jumps(); }
  double input_power(const CVecRef& u, const CVecRef& v, double t, int side = 0) const {
    double p = effects_.input_power(u, v, t, side);
    if constexpr (traits::has_energy<Extra>::value) p += extra_.input_power(u, v, t);
    return p;
  }
  double dissipated_power(const CVecRef& v) const {
    double p = effects_.dissipated_power(v);
    if constexpr (traits::has_energy<Extra>::value) p += extra_.dissipated_power(v);
    return p;
  }

 private:
  bool extra_state() const {
    if constexpr (traits::has_state_methods<Extra>::value) return extra_.has_state();
    return false;
  }
  EffectSet effects_;
  Extra extra_;
  Vector work_;     // the extra force
  Matrix K2_, C2_;  // the extra tangent (dense)
  mutable size_t ke_ = 0, ce_ = 0;  // where the extra force's tangent entries start
};

namespace detail_ {
// K_extra + C_extra (dense or sparse) plus the springs and dampers of the list, summed into sparse K
// and C; the rest in the EffectSet.
inline SparseMatrix to_sparse(const SparseMatrix& A) { return A; }
inline SparseMatrix to_sparse(const Matrix& A) {
  NVIB_CHECK(A.allFinite(), "K, C", "the matrix has non-finite entries");
  return A.sparseView(1.0, 0.0);
}

struct Assembled {
  SparseMatrix K, C;
  EffectSet set;
};

template <class MatK, class MatC>
Assembled assemble(const Mass& mass, std::vector<Effect> list, const MatK& K_extra, const MatC& C_extra,
                   std::vector<EffectArray> arrays = {}) {
  const Index n = mass.size();
  LinearParts lin;
  auto add = [&](const auto& A, const char* name, std::vector<Eigen::Triplet<double, int>>& out) {
    if (A.size() == 0) return;
    NVIB_CHECK(A.rows() == n && A.cols() == n, name,
               "expected shape (" + std::to_string(n) + ", " + std::to_string(n) + "), got (" +
                   std::to_string(A.rows()) + ", " + std::to_string(A.cols()) + ")");
    const SparseMatrix S = to_sparse(A);
    refuse_one_triangle(S, name);  // the matrix given, before the springs and dampers join it
    for (Index j = 0; j < S.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(S, j); it; ++it) out.emplace_back(it.row(), static_cast<int>(j), it.value());
  };
  add(K_extra, "K", lin.k);
  add(C_extra, "C", lin.c);
  EffectSet set(std::move(list), mass, &lin, std::move(arrays));
  return {LinearParts::to_matrix(lin.k, n), LinearParts::to_matrix(lin.c, n), std::move(set)};
}
}  // namespace detail_

template <class MatK = Matrix, class MatC = Matrix,
          class = std::enable_if_t<std::is_base_of_v<Eigen::EigenBase<MatK>, MatK>>>
Model<EffectSet> make_effect_model(Mass mass, std::vector<Effect> list, const MatK& K_extra = MatK(),
                                   const MatC& C_extra = MatC()) {
  auto a = detail_::assemble(mass, std::move(list), K_extra, C_extra);
  return Model<EffectSet>(std::move(mass), std::move(a.K), std::move(a.C), std::move(a.set),
                          LinearPartsSummed{true});
}

template <class Extra, class MatK = Matrix, class MatC = Matrix,
          class = std::enable_if_t<!std::is_base_of_v<Eigen::EigenBase<Extra>, Extra> &&
                                   !std::is_same_v<Extra, std::vector<EffectArray>>>>
Model<EffectsPlus<Extra>> make_effect_model(Mass mass, std::vector<Effect> list, Extra extra,
                                            const MatK& K_extra = MatK(), const MatC& C_extra = MatC()) {
  const Index n = mass.size();
  auto a = detail_::assemble(mass, std::move(list), K_extra, C_extra);
  return Model<EffectsPlus<Extra>>(std::move(mass), std::move(a.K), std::move(a.C),
                                   EffectsPlus<Extra>(std::move(a.set), std::move(extra), n), LinearPartsSummed{true});
}

}  // namespace effects
}  // namespace nvib

namespace nvib {
namespace effects {
// A model of effects declared one by one and as arrays (and an optional extra force functor).
template <class MatK = Matrix, class MatC = Matrix>
Model<EffectSet> make_effect_model(Mass mass, std::vector<Effect> list, std::vector<EffectArray> arrays,
                                   const MatK& K_extra = MatK(), const MatC& C_extra = MatC()) {
  auto a = detail_::assemble(mass, std::move(list), K_extra, C_extra, std::move(arrays));
  return Model<EffectSet>(std::move(mass), std::move(a.K), std::move(a.C), std::move(a.set),
                          LinearPartsSummed{true});
}
template <class Extra, class MatK = Matrix, class MatC = Matrix>
Model<EffectsPlus<Extra>> make_effect_model_plus(Mass mass, std::vector<Effect> list, std::vector<EffectArray> arrays,
                                                 Extra extra, const MatK& K_extra = MatK(), const MatC& C_extra = MatC()) {
  const Index n = mass.size();
  auto a = detail_::assemble(mass, std::move(list), K_extra, C_extra, std::move(arrays));
  return Model<EffectsPlus<Extra>>(std::move(mass), std::move(a.K), std::move(a.C),
                                   EffectsPlus<Extra>(std::move(a.set), std::move(extra), n), LinearPartsSummed{true});
}
}  // namespace effects
}  // namespace nvib
