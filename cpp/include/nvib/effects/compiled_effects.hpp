// The declared effects, compiled once and never changed after: the linear ones with constant slopes
// (single springs, dampers, P-delta) assembled into K and C (given a LinearParts to assemble into),
// constant loads into a constant vector, the others into groups of one law and one measure storage
// (kernels.hpp), single effects and arrays alike. EffectSet (effect_set.hpp) evaluates them; its
// copies share one CompiledEffects, so a model copied into each stepper costs no memory for its
// effects, only for their states.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "../base/interrupt.hpp"
#include "../model/mass.hpp"
#include "effect.hpp"
#include "kernels.hpp"

namespace nvib {
namespace effects {

// Where linear effects with constant slopes are assembled: their entries (row, column, value),
// summed into sparse K and C by to_matrix() (each empty if nothing went into it).
struct LinearParts {
  std::vector<Eigen::Triplet<double, int>> k, c;

  static SparseMatrix to_matrix(const std::vector<Eigen::Triplet<double, int>>& entries, Index n) {
    if (entries.empty()) return SparseMatrix();
    SparseMatrix A(n, n);
    A.setFromTriplets(entries.begin(), entries.end());  // duplicates summed
    A.prune(0.0);
    A.makeCompressed();
    return A;
  }
};

class CompiledEffects {
 public:
  static constexpr std::size_t npos = std::numeric_limits<std::size_t>::max();
  // Where an evaluated effect sits: its group and its place in it.
  struct Place {
    std::size_t group = npos, k = 0;
  };

  CompiledEffects() = default;  // no effects
  // `mass` turns ground accelerations' influence vectors r into M r. Effects come one by one (list)
  // and as arrays of one law (arrays).
  CompiledEffects(std::vector<Effect> list, const Mass& mass, LinearParts* linear = nullptr,
                  std::vector<EffectArray> arrays = {})
      : all_(std::move(list)), arrays_(std::move(arrays)) {
    const Index n = mass.size();
    f_const_.setZero(n);
    for (const EffectArray& a : arrays_) take_array(a);
    std::vector<std::size_t> active;
    for (size_t i = 0; i < all_.size(); ++i) {
      Effect& e = all_[i];
      for (Index d : e.index)
        NVIB_CHECK(d < n, "effects[" + std::to_string(i) + "].measure",
                   "DOF index " + std::to_string(d) + " is out of range for " + std::to_string(n) +
                       " degrees of freedom");
      if (e.law == law_id<GroundAcceleration>()) to_mass_weighted(e, mass);
      if (e.index.empty()) continue;  // a measure that is zero (a ground motion moving no mass) acts on nothing
      uses_time_ = uses_time_ || e.uses_time();
      linear_ = linear_ && e.is_linear();
      const bool assembled = dispatch(e.law, [](auto L) { return decltype(L)::assembled; });
      if (linear && assembled) {
        assemble(e, *linear);
        continue;
      }
      if (e.law == law_id<ConstantForce>()) {
        for (size_t k = 0; k < e.index.size(); ++k) f_const_[e.index[k]] -= e.coef[k] * e.values[0];
        continue;
      }
      active.push_back(i);
      velocity_ = velocity_ || e.uses_velocity();
    }
    places_.assign(all_.size(), Place{});
    compile(active, n);
  }

  CompiledEffects(const CompiledEffects&) = delete;  // the groups point into this object
  CompiledEffects& operator=(const CompiledEffects&) = delete;

  const std::vector<Effect>& effects() const { return all_; }
  const std::vector<EffectArray>& arrays() const { return arrays_; }
  // Effects evaluated each step, single ones and those of arrays.
  size_t num_evaluated() const {
    size_t k = 0;
    for (const kernels::Group& g : groups_) k += g.size;
    return k;
  }
  const Vector& constant_load() const { return f_const_; }  // -P of the constant loads
  const std::vector<kernels::Group>& groups() const { return groups_; }
  // Effects in the dense_first groups (their values are kept per time by EffectSet), and those groups
  // (the first ones).
  std::size_t num_dense_loads() const { return dense_loads_; }
  std::size_t num_load_groups() const { return load_groups_; }
  // The largest halo of the groups after the loads (kernels::Group::halo), -1 if one has none.
  std::int64_t stream_halo() const {
    std::int64_t h = 0;
    for (std::size_t q = num_load_groups(); q < groups_.size(); ++q) {
      if (groups_[q].halo < 0) return -1;
      h = std::max(h, groups_[q].halo);
    }
    return h;
  }
  bool uses_velocity() const { return velocity_; }
  bool uses_time() const { return uses_time_; }
  bool is_linear() const { return linear_; }
  // Every evaluated law knows its stored energy (a compiled law does not: no energy account).
  bool accounts_energy() const {
    for (const kernels::Group& g : groups_)
      if (!dispatch(g.law, [](auto L) { return decltype(L)::knows_energy; })) return false;
    return true;
  }
  // The internal variables of the laws with memory, all effects' one after the other, as the laws
  // start (the committed states of each model copy begin as this).
  bool has_state() const { return !initial_state_.empty(); }
  const std::vector<double>& initial_state() const { return initial_state_; }
  // Where single effect i and array q are evaluated (group npos: assembled, a constant load, or nothing).
  const Place& place_of_effect(size_t i) const { return places_[i]; }
  std::size_t group_of_array(size_t q) const { return array_groups_[q]; }
  // Who the members of group g are: single effects (their indices), or the effects of one array.
  const std::vector<std::uint32_t>& members(size_t g) const { return members_[g]; }
  std::size_t array_of_group(size_t g) const { return group_arrays_[g]; }
  // "storey1" (its name), or "effects[3] (bilinear)"; of an array, "name[k]" or "arrays[q][k]".
  std::string describe(size_t g, size_t k) const {
    const std::size_t q = group_arrays_[g];
    if (q != npos) {
      const EffectArray& a = arrays_[q];
      return (a.name.empty() ? "arrays[" + std::to_string(q) + "]" : a.name) + "[" + std::to_string(k) + "] (" + a.key() + ")";
    }
    const std::size_t i = members_[g][k];
    const Effect& e = all_[i];
    return e.name.empty() ? "effects[" + std::to_string(i) + "] (" + e.key() + ")" : e.name + " (" + e.key() + ")";
  }

 private:
  // The storage of one group's measures and parameters (arrays keep their own index arrays).
  struct Store {
    std::vector<std::int32_t> i, j, first;
    std::vector<Index> idx;
    std::vector<double> c, coef, rows;
    std::vector<double> row_value;  // dense loads: the value every entry of row k has, or NaN
    std::unique_ptr<unsigned char[]> params;
  };

  // An array's constant loads go into the constant vector; the rest is evaluated each step.
  void take_array(const EffectArray& a) {
    if (a.size() == 0) return;
    uses_time_ = uses_time_ || a.uses_time();
    linear_ = linear_ && a.is_linear();
    if (a.law == law_id<ConstantForce>()) {
      for (size_t k = 0; k < a.size(); ++k) {
        f_const_[a.i[k]] -= a.value(0, k);
        if (a.j[k] >= 0) f_const_[a.j[k]] += a.value(0, k);
      }
      return;
    }
    velocity_ = velocity_ || a.uses_velocity();
  }

  // A ground acceleration acts as g^T a_g(t) with g = M r.
  static void to_mass_weighted(Effect& e, const Mass& mass) {
    const Index n = mass.size();
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
  // K += df/dd g g^T, C += df/dd' g g^T (constant slopes).
  static void assemble(const Effect& e, LinearParts& lin) {
    const Slopes s = e.slopes(0.0, 0.0, 0.0);
    const bool disp = e.uses_displacement(), vel = e.uses_velocity();
    for (size_t i = 0; i < e.index.size(); ++i)
      for (size_t j = 0; j < e.index.size(); ++j) {
        const int r = static_cast<int>(e.index[i]), c = static_cast<int>(e.index[j]);
        if (disp) lin.k.emplace_back(r, c, s.kd * e.coef[i] * e.coef[j]);
        if (vel) lin.c.emplace_back(r, c, s.kv * e.coef[i] * e.coef[j]);
      }
  }

  static kernels::Storage single_storage(const Effect& e, Index n) {
    using namespace kernels;
    const Index m = static_cast<Index>(e.index.size());
    if (m == 1 && e.coef[0] == 1.0) return ground;
    if (m == 2 && e.coef[0] == 1.0 && e.coef[1] == -1.0 && e.index[0] != e.index[1]) return pair;
    if (m <= 2) return two;
    if (2 * m < n) return sparse;
    return e.is_load() ? dense_first : dense;  // a load's force needs no measure
  }

  // Groups of the evaluated single effects (dense loads first, then by law and storage, in the
  // order declared within each), then one group per evaluated array, in order.
  void compile(const std::vector<std::size_t>& active, Index n) {
    using namespace kernels;
    struct Source {
      std::size_t effect;
      LawId law;
      Storage storage;
    };
    std::vector<Source> sources;
    sources.reserve(active.size());
    for (std::size_t i : active) sources.push_back({i, all_[i].law, single_storage(all_[i], n)});
    std::stable_sort(sources.begin(), sources.end(), [](const Source& a, const Source& b) {
      const bool fa = a.storage == dense_first, fb = b.storage == dense_first;
      if (fa != fb) return fa;
      return a.law != b.law ? a.law < b.law : a.storage < b.storage;
    });
    // Effects on one DOF and on a difference of two, of one law, share a group (mixed storage, the
    // ground ones first): one kernel call fewer, and the same operations in the same order.
    auto kind = [](Storage s) { return s == ground || s == pair ? mixed : s; };
    std::size_t state_size = 0;
    for (std::size_t b = 0; b < sources.size();) {
      std::size_t e = b;
      while (e < sources.size() && sources[e].law == sources[b].law && kind(sources[e].storage) == kind(sources[b].storage))
        ++e;
      dispatch(sources[b].law, [&](auto L) {
        using Lw = decltype(L);
        Store& st = stores_.emplace_back();
        Group g;
        g.law = sources[b].law;
        g.storage = sources[b].storage == sources[e - 1].storage ? sources[b].storage : mixed;
        g.size = e - b;
        g.n = n;
        auto* P = new_params<Lw>(st, g.size);
        std::vector<std::uint32_t> members;
        if (g.storage == sparse || g.storage == dense || g.storage == dense_first) st.first.push_back(0);
        for (std::size_t q = b; q < e; ++q) {
          if (((q - b) & 0xFFFF) == 0) poll_interrupt();  // large models: every 65536 effects
          const Effect& ef = all_[sources[q].effect];
          places_[sources[q].effect] = Place{groups_.size(), q - b};
          members.push_back(static_cast<std::uint32_t>(sources[q].effect));
          new (P + (q - b)) typename Lw::Params(ef.template params<Lw>());
          switch (g.storage) {
            case ground: st.i.push_back(static_cast<std::int32_t>(ef.index[0])); break;
            case pair:
            case mixed:
              st.i.push_back(static_cast<std::int32_t>(ef.index[0]));
              st.j.push_back(static_cast<std::int32_t>(ef.index.size() > 1 ? ef.index[1] : -1));
              break;
            case two:  // always two entries: a zero second one for a single DOF
              st.i.push_back(static_cast<std::int32_t>(ef.index[0]));
              st.j.push_back(static_cast<std::int32_t>(ef.index.size() > 1 ? ef.index[1] : ef.index[0]));
              st.c.push_back(ef.coef[0]);
              st.c.push_back(ef.index.size() > 1 ? ef.coef[1] : 0.0);
              break;
            default:
              st.idx.insert(st.idx.end(), ef.index.begin(), ef.index.end());
              st.coef.insert(st.coef.end(), ef.coef.begin(), ef.coef.end());
              st.first.push_back(static_cast<std::int32_t>(st.idx.size()));
              if (g.storage != sparse) {
                const std::size_t at = st.rows.size();
                st.rows.resize(at + static_cast<std::size_t>(n), 0.0);
                for (size_t k = 0; k < ef.index.size(); ++k) st.rows[at + static_cast<std::size_t>(ef.index[k])] += ef.coef[k];
              }
          }
        }
        // One set of parameters for all where they are all the same (a uniform storey spring).
        if (g.storage == ground || g.storage == pair || g.storage == mixed) {
          g.uniform = true;
          for (std::size_t q = 1; q < g.size && g.uniform; ++q)
            g.uniform = std::memcmp(P + q, P, sizeof(typename Lw::Params)) == 0;
        }
        members_.push_back(std::move(members));
        group_arrays_.push_back(npos);
        finish_group<Lw>(g, st, state_size);
      });
      b = e;
    }
    if (!groups_.empty() && groups_.front().storage == dense_first) {
      groups_.front().writes = true;
      const bool none = f_const_.size() == 0 || f_const_.cwiseAbs().maxCoeff() == 0.0;
      groups_.front().constant_load = none ? nullptr : f_const_.data();
    }
    // The arrays: their own index arrays, parameters uniform or one set per effect.
    array_groups_.assign(arrays_.size(), npos);
    for (size_t q = 0; q < arrays_.size(); ++q) {
      const EffectArray& a = arrays_[q];
      if (a.size() == 0 || a.law == law_id<ConstantForce>()) continue;
      dispatch(a.law, [&](auto L) {
        using Lw = decltype(L);
        Store& st = stores_.emplace_back();
        Group g;
        g.law = a.law;
        g.storage = mixed;
        g.size = a.size();
        g.n = n;
        g.i = a.i.data();
        g.j = a.j.data();
        g.uniform = !a.varying();
        const Signal* s = a.signal.present() ? &a.signal : nullptr;
        auto* P = new_params<Lw>(st, g.uniform ? 1 : g.size);
        for (size_t k = 0; k < (g.uniform ? 1 : g.size); ++k) new (P + k) typename Lw::Params(a.template params<Lw>(k, s));
        array_groups_[q] = groups_.size();
        members_.emplace_back();
        group_arrays_.push_back(q);
        finish_group<Lw>(g, st, state_size);
      });
    }
    while (load_groups_ < groups_.size() && groups_[load_groups_].storage == kernels::dense_first) ++load_groups_;
    for (std::size_t q = 0; q < groups_.size(); ++q) {
      kernels::Group& g = groups_[q];
      if (group_arrays_[q] != npos)
        g.uses_time = arrays_[group_arrays_[q]].uses_time();
      else
        for (std::uint32_t e : members_[q]) g.uses_time = g.uses_time || all_[e].uses_time();
    }
  }

  // How far the DOFs of effect k lie from k (kernels::Group::halo): -1 for a dense row (it reaches every
  // DOF), 0 for the dense loads (their rows go DOF by DOF).
  static std::int64_t halo_of(const kernels::Group& g) {
    using namespace kernels;
    if (g.storage == dense_first) return 0;
    if (g.storage == dense) return -1;
    std::int64_t h = 0;
    auto reach = [&](std::int64_t d, std::size_t k) { h = std::max<std::int64_t>(h, std::abs(d - std::int64_t(k))); };
    for (std::size_t k = 0; k < g.size; ++k) {
      if (g.storage == sparse) {
        for (std::int32_t e = g.first[k]; e < g.first[k + 1]; ++e) reach(g.idx[e], k);
      } else {
        reach(g.i[k], k);
        if (g.j && g.j[k] >= 0) reach(g.j[k], k);
      }
    }
    return h;
  }

  template <class L>
  static typename L::Params* new_params(Store& st, std::size_t count) {
    static_assert(std::is_trivially_copyable_v<typename L::Params> && std::is_trivially_destructible_v<typename L::Params>,
                  "a law's Params is plain data");
    static_assert(alignof(typename L::Params) <= alignof(std::max_align_t), "over-aligned Params");
    st.params.reset(new unsigned char[sizeof(typename L::Params) * std::max<std::size_t>(count, 1)]);
    return reinterpret_cast<typename L::Params*>(st.params.get());
  }

  // Points the group at its store, gives it its kernel and its place in the state buffers.
  template <class L>
  void finish_group(kernels::Group& g, Store& st, std::size_t& state_size) {
    using namespace kernels;
    if (!st.i.empty()) g.i = st.i.data();  // (an array's group points to the array's own)
    if (!st.j.empty()) g.j = st.j.data();
    g.c = st.c.empty() ? nullptr : st.c.data();
    g.first = st.first.empty() ? nullptr : st.first.data();
    g.idx = st.idx.empty() ? nullptr : st.idx.data();
    g.coef = st.coef.empty() ? nullptr : st.coef.data();
    g.rows = st.rows.empty() ? nullptr : st.rows.data();
    if (g.storage == dense_first) {  // a row of one value everywhere (a ground motion of a uniform mass)
      st.row_value.assign(g.size, std::numeric_limits<double>::quiet_NaN());
      for (std::size_t k = 0; k < g.size; ++k) {
        const double* w = g.rows + static_cast<Index>(k) * g.n;
        if (std::all_of(w, w + g.n, [&](double x) { return x == w[0] && std::signbit(x) == std::signbit(w[0]); }))
          st.row_value[k] = w[0];
      }
      g.row_value = st.row_value.data();
    }
    g.params = st.params.get();
    g.kernel = force_kernel<L>(g);
    g.tangent = &tangent_add<L>;
    g.params_bytes = g.uniform ? 0 : sizeof(typename L::Params);
    g.state_width = law::state_width<L>();
    g.halo = halo_of(g);
    if constexpr (L::is_load) {
      if (g.storage == dense_first) {
        g.load_values = &dense_load_values<L>;
        g.load_write = &dense_load_write<L>;
        g.load = dense_loads_;
        dense_loads_ += g.size;
      }
    }
    if constexpr (law::has_state<L>) {
      g.state = state_size;
      state_size += g.size * law::state_width<L>();
      initial_state_.resize(state_size);
      for (std::size_t k = 0; k < g.size; ++k) g.store_state<L>(initial_state_.data(), k, law::initial<L>(g.params_of<L>(k)));
    }
    groups_.push_back(g);
  }

  std::vector<Effect> all_;
  std::vector<EffectArray> arrays_;
  Vector f_const_;  // -P of the constant loads
  bool uses_time_ = false, linear_ = true, velocity_ = false;
  std::vector<Store> stores_;
  std::vector<kernels::Group> groups_;
  std::vector<Place> places_;
  std::vector<std::size_t> array_groups_;
  std::vector<std::vector<std::uint32_t>> members_;  // per group: its single effects (empty for an array's)
  std::vector<std::size_t> group_arrays_;           // per group: its array, or npos
  std::vector<double> initial_state_;
  std::size_t dense_loads_ = 0;
  std::size_t load_groups_ = 0;  // the dense_first groups, the first ones
};

}  // namespace effects
}  // namespace nvib
