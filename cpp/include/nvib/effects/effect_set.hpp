// EffectSet: the declared effects as a force functor for Model: a handle on their compiled form
// (compiled_effects.hpp), shared by its copies, and the states of its laws with memory, its own.
//
// Every effect it is given acts: with a LinearParts to assemble into, linear effects with constant
// slopes go into K and C once; without one they are evaluated like the rest. Constant loads go
// into a constant vector; the other effects are evaluated group by group (kernels.hpp).
//
// The force vector is first *written* (constant loads plus the dense loads, which need no state)
// and then accumulated into. Zeroing it first is a memset call whose wide stores the effects'
// narrow read-modify-writes then wait on; measured 30% slower on the building scene.
//
// State (laws with memory): each copy holds the committed internal variables of every effect and
// a trial buffer. An evaluation of the force is a pure trial: it reads the committed states and
// writes the trial states, nothing else; tangents and energies read the committed states only.
// commit() makes a trial the committed state, once per accepted step (StepperBase::advance):
// either the trial of the last force evaluation (a swap), when the scheme's last evaluation was at
// the accepted state, or a new trial at the accepted state. A model without memory has empty
// buffers and commit() does nothing.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <stdexcept>
#include <utility>
#include <vector>

#include "../base/compiler.hpp"
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
      : c_(std::make_shared<const CompiledEffects>(std::move(list), mass, linear, std::move(arrays))),
        committed_(c_->initial_state()),
        trial_(c_->initial_state()),
        load_f_(c_->num_dense_loads(), 0.0) {
    // One dense load whose row has one value everywhere and no constant load under it (a ground motion
    // on a uniform mass): at a time already evaluated, every entry is that value times the kept f.
    const auto& groups = c_->groups();
    if (c_->num_load_groups() == 1) {
      const kernels::Group& g = groups.front();
      one_value_load_ = g.size == 1 && g.writes && g.constant_load == nullptr && g.row_value != nullptr &&
                        !std::isnan(g.row_value[0]);
    }
  }

  const std::vector<Effect>& effects() const { return c_->effects(); }
  const std::vector<EffectArray>& arrays() const { return c_->arrays(); }
  const CompiledEffects& compiled() const { return *c_; }
  size_t num_evaluated() const { return c_->num_evaluated(); }  // single effects and those of arrays
  const Vector& constant_load() const { return c_->constant_load(); }  // -P of the constant loads
  // The entries of the arrays' linear effects with constant slopes (springs, dampers), which are
  // evaluated by their kernels rather than assembled: added to K (stiffness) or C where those are shown.
  void add_linear_array_entries(bool stiffness, std::vector<Eigen::Triplet<double, int>>& out) const {
    for (size_t q = 0; q < arrays().size(); ++q) {
      const std::size_t gi = c_->group_of_array(q);
      if (gi == CompiledEffects::npos) continue;
      const kernels::Group& g = c_->groups()[gi];
      dispatch(g.law, [&](auto L) {
        using Lw = decltype(L);
        if constexpr (Lw::assembled) {
          if (stiffness ? !Lw::uses_displacement : !Lw::uses_velocity) return;
          for (size_t k = 0; k < g.size; ++k) {
            const Slopes s = law::slopes<Lw>(g.params_of<Lw>(k), typename Lw::State{}, 0.0, 0.0, 0.0);
            const double x = stiffness ? s.kd : s.kv;
            g.for_each_entry(k, [&](Index r, double gr) {
              g.for_each_entry(k, [&](Index c, double gc) { out.emplace_back(int(r), int(c), x * (gr * gc)); });
            });
          }
        }
      });
    }
  }

  void operator()(const CVecRef& u, const CVecRef& v, double t, VecRef out) const {
    eval(u.data(), v.data(), t, out.data());
  }
  // The same on contiguous storage of size(): Model calls it with its vectors' data, no Eigen::Ref formed.
  void eval(const double* up, const double* vp, double t, double* op) const {
    const auto& groups = c_->groups();
    const std::size_t nl = c_->num_load_groups();
    if (nl == 1) {  // one group of dense loads (a ground motion): its values, then its rows, all DOFs
      const kernels::Group& g = groups.front();
      double* f = load_f_.data();
      if (!(t == load_t_)) {
        g.load_write(g, t, f, op);
        load_t_ = t;
      } else if (one_value_load_) {  // add_dense_loads' product, inline (a Newton iteration's force)
        const double x = g.row_value[0] * f[0];
        for (Index q = 0, n = g.n; q < n; ++q) op[q] = x;  // (a plain loop keeps eval() small enough to inline)
      } else {
        kernels::add_dense_loads(g, f, op);
      }
    } else {
      write_loads(t, op, 0, c_->constant_load().size());
    }
    const double* committed = committed_.data();
    double* trial = trial_.data();
    for (auto g = groups.begin() + static_cast<std::ptrdiff_t>(nl), e = groups.end(); g != e; ++g)
      g->kernel(*g, up, vp, t, op, committed, trial);
  }

  // ---- the force block by block along the DOFs (Model's streamed explicit step) ----
  // The loads are written first (DOF by DOF), then each group after them adds its forces: the stages
  // of the stream, in order. A group's effect k reaches DOFs within halo of k, so that the stages can
  // run block by block behind the DOFs being prepared: stream_halo(), -1 where some effect reaches
  // anywhere (a dense measure).
  std::int64_t stream_halo() const { return c_->stream_halo(); }
  std::size_t stream_stages() const { return c_->groups().size() - c_->num_load_groups(); }
  std::size_t stage_size(std::size_t s) const { return c_->groups()[c_->num_load_groups() + s].size; }
  // max over the times t0 + (t1 - t0) k / samples (k = 0 .. samples) of |the force at rest|_i, per DOF:
  // the loads, the ground motions and any preload (solve.hpp's load_displacement_scale). Where the one
  // force that changes in time is a single dense load (a ground motion), the force at rest is
  // c + w f(t), so its peak over the samples is at the smallest or the largest f(t) sampled: two
  // evaluations of the force instead of samples + 1 (at 10^6 DOFs, 65 of them took half a second).
  Vector rest_force_peak(double t0, double t1, int samples) const {
    const Index n = c_->constant_load().size();
    const Vector zero = Vector::Zero(n);
    Vector f(n), peak = Vector::Zero(n);
    EffectSet probe = *this;  // the trials it writes are its own
    const auto& groups = c_->groups();
    const std::size_t nl = c_->num_load_groups();
    bool one_load = c_->num_dense_loads() == 1;
    for (std::size_t q = nl; q < groups.size() && one_load; ++q) one_load = !groups[q].uses_time;
    if (samples > 0 && one_load) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int k = 0; k <= samples; ++k) {
        double value;
        groups[0].load_values(groups[0], t0 + (t1 - t0) * static_cast<double>(k) / samples, &value);
        lo = std::min(lo, value);
        hi = std::max(hi, value);
      }
      for (double value : {lo, hi}) {
        if (!std::isfinite(value)) continue;
        kernels::add_dense_loads(groups[0], &value, f.data());  // (it writes, with the constant loads)
        for (std::size_t q = nl; q < groups.size(); ++q)
          groups[q].kernel(groups[q], zero.data(), zero.data(), t0, f.data(), probe.committed_.data(), probe.trial_.data());
        peak = peak.cwiseMax(f.cwiseAbs());
      }
      return peak;
    }
    for (int k = 0; k <= samples; ++k) {
      const double t = samples == 0 ? t0 : t0 + (t1 - t0) * static_cast<double>(k) / samples;
      probe.eval(zero.data(), zero.data(), t, f.data());
      peak = peak.cwiseMax(f.cwiseAbs());
    }
    return peak;
  }

  // out[q0 .. q1): the constant and dense loads at t (eval()'s first writes).
  void stream_loads(double t, double* out, Index q0, Index q1) const { write_loads(t, out, q0, q1); }
  // Stage s: effects k0 .. k1 - 1 of its group add their forces.
  void stream_stage(std::size_t s, const double* u, const double* v, double t, double* out, std::size_t k0,
                    std::size_t k1) const {
    const kernels::Group g = c_->groups()[c_->num_load_groups() + s].range(k0, k1);
    g.kernel(g, u, v, t, out, committed_.data(), trial_.data());
  }
  void tangent(const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) const {
    double *k = K.data(), *c = C.data();
    const Index ld = K.outerStride();
    if (ld == K.rows() && C.outerStride() == ld) {  // contiguous: one fill each
      std::fill_n(k, K.size(), 0.0);
      std::fill_n(c, C.size(), 0.0);
    } else {
      K.setZero();
      C.setZero();
    }
    for (const kernels::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) { kernels::add_tangents<decltype(L)>(g, u.data(), v.data(), t, k, c, ld, committed_.data()); });
  }
  // The tangent entry by entry (sparse models): entries once, values at each state, in the same order.
  void tangent_entries(std::vector<Entry>& K, std::vector<Entry>& C) const {
    for (const kernels::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) { kernels::tangent_entries<decltype(L)>(g, K, C); });
  }
  void tangent_values(const CVecRef& u, const CVecRef& v, double t, double* K, double* C) const {
    for (const kernels::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) {
        kernels::tangent_values<decltype(L)>(g, u.data(), v.data(), t, K, C, committed_.data());
      });
  }
  // tangent_values() with each value also added into an iteration matrix's storage (TangentOut);
  // returns the sum of x - x over the values (0 unless one is not finite).
  // (nk, nc: the numbers of entries, tangent_entries()'s; the kernels know their own.)
  double tangent_add(const CVecRef& u, const CVecRef& v, double t, TangentOut& out, std::size_t nk,
                     std::size_t nc) const {
    (void)nk, (void)nc;
    double nonfinite = 0.0;
    for (const kernels::Group& g : c_->groups()) nonfinite += g.tangent(g, u.data(), v.data(), t, committed_.data(), out);
    return nonfinite;
  }
  // kd += the diagonal of the effects' tangent df/du at (u, v, t).
  void add_tangent_diagonal(const double* u, const double* v, double t, double* kd) const {
    for (const kernels::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) { kernels::add_tangent_diagonal<decltype(L)>(g, u, v, t, kd, committed_.data()); });
  }
  // out_i = |constant loads|_i + sum over effects of |g_i f|: the round-off scale of the force.
  void magnitude(const CVecRef& u, const CVecRef& v, double t, VecRef out) const {
    out = c_->constant_load().cwiseAbs();
    for (const kernels::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) { kernels::add_magnitude<decltype(L)>(g, u.data(), v.data(), t, out.data(), committed_.data()); });
  }
  // Flags of the evaluated part (K and C carry the rest).
  bool uses_velocity() const { return c_->uses_velocity(); }
  bool uses_time() const { return c_->uses_time(); }
  bool is_linear() const { return c_->is_linear(); }
  bool accounts_energy() const { return c_->accounts_energy(); }

  // ---- laws with memory ----
  bool has_state() const { return !committed_.empty(); }
  Index state_size() const { return static_cast<Index>(committed_.size()); }
  const std::vector<double>& state() const { return committed_; }
  void get_state(double* out) const { std::copy(committed_.begin(), committed_.end(), out); }
  // Sets the committed states (as state() gives them).
  void set_state(const double* x) { std::copy(x, x + committed_.size(), committed_.begin()); }
  // The laws' initial states (a new run).
  void reset_state() {
    const std::vector<double>& s0 = c_->initial_state();
    std::copy(s0.begin(), s0.end(), committed_.begin());
  }
  // The trial of the last force evaluation becomes the committed state (its (u, v, t) is the
  // accepted state: the caller knows). With verify_commits() it is checked against a new trial there.
  void commit_last_trial(const double* u, const double* v, double t) {
    if (verify_) verify(u, v, t);
    committed_.swap(trial_);
  }
  // A new trial at the accepted state (u, v, t) becomes the committed state. Out of line: a dispatch
  // over every law, which inlined into the stepper's advance() pushed the step out of the inliner's
  // budget (the building's CEMDTS step 5 % slower).
  NVIB_NOINLINE void commit_at(const double* u, const double* v, double t) {
    for (const kernels::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) { kernels::commit_at<decltype(L)>(g, u, v, t, committed_.data()); });
  }
  // For tests: every commit_last_trial also evaluates the trial at its state and throws
  // std::logic_error unless the two agree bit for bit.
  void verify_commits(bool on) { verify_ = on; }

  // ---- recording effects (solve/observers.hpp) ----
  // The effects a name designates: every single effect of that name, or the array of that name. They
  // must share a law (their internal variables are recorded side by side).
  struct Selection {
    std::string name;
    LawId law = 0;
    std::vector<std::size_t> singles;          // indices of single effects
    std::size_t array = CompiledEffects::npos;  // or an array
    std::size_t count = 0;
    std::size_t width = 0;  // internal variables per effect
  };
  Selection select(const std::string& name) const {
    Selection sel;
    sel.name = name;
    for (size_t i = 0; i < effects().size(); ++i)
      if (effects()[i].name == name) sel.singles.push_back(i);
    for (size_t q = 0; q < arrays().size(); ++q)
      if (arrays()[q].name == name) {
        NVIB_CHECK(sel.singles.empty() && sel.array == CompiledEffects::npos, "record",
                   "the name '" + name + "' is given to an effect array and to other effects: name them apart to record them");
        sel.array = q;
      }
    NVIB_CHECK(!sel.singles.empty() || sel.array != CompiledEffects::npos, "record",
               "no effect named '" + name + "'" + known_names());
    sel.law = sel.array != CompiledEffects::npos ? arrays()[sel.array].law : effects()[sel.singles[0]].law;
    for (size_t i : sel.singles)
      NVIB_CHECK(effects()[i].law == sel.law, "record",
                 "the effects named '" + name + "' have different laws (" + key_of(sel.law) + ", " +
                     effects()[i].key() + "): give them names of their own to record them");
    sel.count = sel.array != CompiledEffects::npos ? arrays()[sel.array].size() : sel.singles.size();
    sel.width = dispatch(sel.law, [](auto L) { return law::state_width<decltype(L)>(); });
    return sel;
  }
  // Each selected effect at (u, v, t) with its committed state: measure d, rate d', force f and
  // internal variables (width each), written to d[k], dd[k], f[k], state[k * width ..].
  void sample(const Selection& sel, const double* u, const double* v, double t, double* d, double* dd, double* f,
              double* state) const {
    dispatch(sel.law, [&](auto L) {
      using Lw = decltype(L);
      constexpr std::size_t W = law::state_width<Lw>();
      auto one = [&](std::size_t k, double dk, double ddk, const typename Lw::Params& p, const typename Lw::State& st) {
        d[k] = dk;
        dd[k] = ddk;
        f[k] = law::force<Lw>(p, st, Lw::uses_displacement ? dk : 0.0, Lw::uses_velocity ? ddk : 0.0, t);
        if constexpr (W > 0) std::memcpy(state + k * W, &st, sizeof st);
      };
      if (sel.array != CompiledEffects::npos) {
        const EffectArray& a = arrays()[sel.array];
        const std::size_t gi = c_->group_of_array(sel.array);
        const Signal* sig = a.signal.present() ? &a.signal : nullptr;
        for (std::size_t k = 0; k < a.size(); ++k) {
          const double dk = u[a.i[k]] - (a.j[k] >= 0 ? u[a.j[k]] : 0.0), ddk = v[a.i[k]] - (a.j[k] >= 0 ? v[a.j[k]] : 0.0);
          if (gi == CompiledEffects::npos) {  // (constant loads: not evaluated)
            const auto p = a.template params<Lw>(k, sig);
            one(k, dk, ddk, p, law::initial<Lw>(p));
          } else {
            const kernels::Group& g = c_->groups()[gi];
            one(k, dk, ddk, g.params_of<Lw>(k), g.state_of<Lw>(committed_.data(), k));
          }
        }
        return;
      }
      for (std::size_t k = 0; k < sel.singles.size(); ++k) {
        const Effect& e = effects()[sel.singles[k]];
        const auto& place = c_->place_of_effect(sel.singles[k]);
        const double dk = e.measure(u), ddk = e.measure(v);
        if (place.group == CompiledEffects::npos) {  // assembled into K and C, or a constant load
          const auto p = e.template params<Lw>();
          one(k, dk, ddk, p, law::initial<Lw>(p));
        } else {
          const kernels::Group& g = c_->groups()[place.group];
          one(k, dk, ddk, g.params_of<Lw>(place.k), g.state_of<Lw>(committed_.data(), place.k));
        }
      }
    });
  }

  // ---- collapse ----
  // Some law can fail (lose its strength for good).
  bool can_fail() const {
    for (const kernels::Group& g : c_->groups())
      if (dispatch(g.law, [](auto L) { return law::can_fail<decltype(L)>::value; })) return true;
    return false;
  }
  // The first effect whose law has failed, by its committed state: true and its description in `who`.
  bool failed(std::string& who) const {
    const auto& groups = c_->groups();
    for (std::size_t gi = 0; gi < groups.size(); ++gi) {
      const kernels::Group& g = groups[gi];
      const std::size_t k = dispatch(g.law, [&](auto L) -> std::size_t {
        using Lw = decltype(L);
        if constexpr (law::can_fail<Lw>::value) {
          for (std::size_t q = 0; q < g.size; ++q)
            if (Lw::failed(g.params_of<Lw>(q), g.state_of<Lw>(committed_.data(), q))) return q;
        }
        return CompiledEffects::npos;
      });
      if (k != CompiledEffects::npos) {
        who = c_->describe(gi, k);
        return true;
      }
    }
    return false;
  }
  // The first effect with memory whose |d| exceeds `limit` at u: true, its description and d.
  bool beyond(const double* u, double limit, std::string& who, double& d) const {
    const auto& groups = c_->groups();
    for (std::size_t gi = 0; gi < groups.size(); ++gi) {
      const kernels::Group& g = groups[gi];
      if (!dispatch(g.law, [](auto L) { return law::has_state<decltype(L)>; })) continue;
      for (std::size_t k = 0; k < g.size; ++k) {
        const double x = g.measure(k, u);
        if (!(std::abs(x) <= limit)) {
          who = c_->describe(gi, k);
          d = x;
          return true;
        }
      }
    }
    return false;
  }

  // The effects whose laws declare where their force is not smooth (law::has_event), and their event
  // values at (u, v, t) from the committed states in `committed` (a buffer of state_size() doubles), in
  // the order of the groups.
  Index num_events() const {
    Index count = 0;
    for (const kernels::Group& g : c_->groups())
      if (dispatch(g.law, [](auto L) { return law::has_event<decltype(L)>::value; })) count += static_cast<Index>(g.size);
    return count;
  }
  void events(const double* u, const double* v, double t, const double* committed, double* out) const {
    Index q = 0;
    for (const kernels::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) {
        using Lw = decltype(L);
        if constexpr (law::has_event<Lw>::value) {
          for (std::size_t k = 0; k < g.size; ++k) {
            const double d = Lw::uses_displacement ? g.measure(k, u) : 0.0;
            const double dd = Lw::uses_velocity ? g.measure(k, v) : 0.0;
            out[q++] = Lw::event(g.template params_of<Lw>(k), g.template state_of<Lw>(committed, k), d, dd, t);
          }
        }
      });
  }
  // The description of event k (num_events() order): its law, name and index.
  std::string describe_event(Index which) const {
    Index q = 0;
    const auto& groups = c_->groups();
    for (std::size_t gi = 0; gi < groups.size(); ++gi) {
      const kernels::Group& g = groups[gi];
      if (!dispatch(g.law, [](auto L) { return law::has_event<decltype(L)>::value; })) continue;
      if (which < q + static_cast<Index>(g.size)) return c_->describe(gi, static_cast<std::size_t>(which - q));
      q += static_cast<Index>(g.size);
    }
    return "?";
  }

  // Energy accounting over the effects evaluated each step and the constant loads; the model adds
  // what K and C carry. With memory: the stored (recoverable) energy at the committed state.
  double potential(const CVecRef& u, double t) const {
    double e = 0.0;
    for (const kernels::Group& g : c_->groups())
      e += dispatch(g.law, [&](auto L) {
        using Lw = decltype(L);
        return kernels::sum<Lw>(g, u.data(), nullptr, committed_.data(),
                                [&](const auto& p, const auto& s, double d, double) { return law::stored<Lw>(p, s, d, t); });
      });
    return e;
  }
  // The energy the laws with memory have dissipated (their committed states say).
  double hysteretic_dissipation() const {
    double e = 0.0;
    for (const kernels::Group& g : c_->groups())
      e += dispatch(g.law, [&](auto L) {
        using Lw = decltype(L);
        if constexpr (law::has_state<Lw>) {
          return kernels::sum<Lw>(g, nullptr, nullptr, committed_.data(),
                                  [&](const auto& p, const auto& s, double, double) { return law::dissipated<Lw>(p, s); });
        } else {
          return 0.0;
        }
      });
    return e;
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
    double w = -c_->constant_load().dot(v);
    for (const kernels::Group& g : c_->groups())
      w += dispatch(g.law, [&](auto L) {
        using Lw = decltype(L);
        return kernels::sum<Lw>(g, u.data(), v.data(), committed_.data(), [&](const auto& p, const auto&, double d, double dd) {
          return law::input_power<Lw>(p, d, dd, t, side);
        });
      });
    return w;
  }
  double dissipated_power(const CVecRef& v) const {
    double w = 0.0;
    for (const kernels::Group& g : c_->groups())
      w += dispatch(g.law, [&](auto L) {
        using Lw = decltype(L);
        if constexpr (law::is_viscous<Lw>()) {
          return kernels::sum<Lw>(g, nullptr, v.data(), committed_.data(),
                                  [&](const auto& p, const auto&, double, double dd) { return law::dissipated_power<Lw>(p, dd); });
        } else {
          return 0.0;
        }
      });
    return w;
  }

 private:
  // out[q0 .. q1) = the constant loads plus the dense loads at t, their values kept while t does not
  // change (a step's Newton iterations evaluate the force several times at one time).
  void write_loads(double t, double* op, Index q0, Index q1) const {
    const auto& groups = c_->groups();
    const std::size_t nl = c_->num_load_groups();
    if (nl > 0) {
      if (!(t == load_t_)) {
        for (std::size_t q = 0; q < nl; ++q) groups[q].load_values(groups[q], t, load_f_.data() + groups[q].load);
        load_t_ = t;
      }
      for (std::size_t q = 0; q < nl; ++q)
        kernels::add_dense_loads(groups[q], load_f_.data() + groups[q].load, op, q0, q1);  // the first writes
    } else {
      // A stored zero the compiler cannot see through keeps this a plain loop, not memcpy.
      const double* base = c_->constant_load().data();
      const double z = opaque_zero_;
      for (Index i = q0; i < q1; ++i) op[i] = base[i] + z;
    }
  }
  std::string known_names() const {
    std::string names;
    for (const Effect& e : effects())
      if (!e.name.empty() && names.find("'" + e.name + "'") == std::string::npos) names += (names.empty() ? "" : ", ") + ("'" + e.name + "'");
    for (const EffectArray& a : arrays())
      if (!a.name.empty()) names += (names.empty() ? "" : ", ") + ("'" + a.name + "'");
    return names.empty() ? " (no effect has a name)" : " (named: " + names + ")";
  }
  void verify(const double* u, const double* v, double t) {
    std::vector<double> fresh = committed_;
    for (const kernels::Group& g : c_->groups())
      dispatch(g.law, [&](auto L) { kernels::commit_at<decltype(L)>(g, u, v, t, fresh.data()); });
    for (size_t k = 0; k < fresh.size(); ++k)
      if (!(fresh[k] == trial_[k]) && !(std::isnan(fresh[k]) && std::isnan(trial_[k])))
        throw std::logic_error("commit: the last trial's state differs from a trial at the accepted state at entry " +
                               std::to_string(k) + " (" + detail::fmt(trial_[k]) + " != " + detail::fmt(fresh[k]) + ")");
  }

  std::shared_ptr<const CompiledEffects> c_ = std::make_shared<const CompiledEffects>();
  std::vector<double> committed_;
  mutable std::vector<double> trial_;  // written by every force evaluation (a pure trial)
  mutable std::vector<double> load_f_;  // the dense loads' values at load_t_ (a pure function of t)
  mutable double load_t_ = std::numeric_limits<double>::quiet_NaN();
  bool one_value_load_ = false;  // see the constructor
  bool verify_ = false;
  double opaque_zero_ = 0.0;  // see eval()
};

}  // namespace effects
}  // namespace nvib
