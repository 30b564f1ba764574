// Model: M a + K u + C v + f(u, v, t) = 0, where f is the user's (or the
// effects') nonlinear force with the loads included as -P(t).
//
// The force is a template parameter: any callable f(u, v, t, out) with
// Eigen::Ref arguments, called directly (inlined), never through a virtual
// call or std::function. Optional members detected at compile time:
//   tangent(u, v, t, K, C)   K = df/du, C = df/dv (overwrite both)
//   has_tangent()            runtime switch (a Python model may or may not have one)
//   uses_velocity(), uses_time(), is_linear()   flags the schemes exploit
//   has_state(), state_size(), get_state(double*), set_state(const double*), reset_state(),
//   commit_last_trial(u, v, t), commit_at(u, v, t)   a force with memory (laws with internal
//                            variables): evaluations are pure trials, commits happen once per
//                            accepted step (see commit() below)
// Without a tangent the model differentiates f by central differences and
// counts the extra evaluations in Stats::num_fd_force_evals.
#pragma once

#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "../base/types.hpp"
#include "linear_product.hpp"
#include "mass.hpp"

namespace nvib {

// The empty force: a linear model M a + K u + C v = 0.
struct NoForce {
  void operator()(const CVecRef&, const CVecRef&, double, VecRef out) const { out.setZero(); }
  void tangent(const CVecRef&, const CVecRef&, double, MatRef K, MatRef C) const {
    K.setZero();
    C.setZero();
  }
  void tangent_entries(std::vector<Entry>&, std::vector<Entry>&) const {}
  void tangent_values(const CVecRef&, const CVecRef&, double, double*, double*) const {}
  bool uses_velocity() const { return false; }
  bool uses_time() const { return false; }
  bool is_linear() const { return true; }
  double potential(const CVecRef&, double) const { return 0.0; }
  double input_power(const CVecRef&, const CVecRef&, double) const { return 0.0; }
  double dissipated_power(const CVecRef&) const { return 0.0; }
};

namespace traits {
template <class F, class = void>
struct has_tangent_method : std::false_type {};
template <class F>
struct has_tangent_method<F, std::void_t<decltype(std::declval<F&>().tangent(
                          std::declval<const CVecRef&>(), std::declval<const CVecRef&>(), 0.0,
                          std::declval<MatRef>(), std::declval<MatRef>()))>> : std::true_type {};

#define NVIB_OPTIONAL_FLAG(name, fallback)                                                     \
  template <class F, class = void>                                                             \
  struct name##_t {                                                                            \
    static bool get(const F&) { return fallback; }                                             \
  };                                                                                           \
  template <class F>                                                                           \
  struct name##_t<F, std::void_t<decltype(std::declval<const F&>().name())>> {                 \
    static bool get(const F& f) { return static_cast<bool>(f.name()); }                        \
  };                                                                                           \
  template <class F>                                                                           \
  bool name(const F& f) {                                                                      \
    return name##_t<F>::get(f);                                                                \
  }
// Unknown forces are assumed to use velocity and time and to be nonlinear:
// that is always correct, only sometimes slower.
NVIB_OPTIONAL_FLAG(uses_velocity, true)
NVIB_OPTIONAL_FLAG(uses_time, true)
NVIB_OPTIONAL_FLAG(is_linear, false)
NVIB_OPTIONAL_FLAG(has_tangent, has_tangent_method<F>::value)
NVIB_OPTIONAL_FLAG(accounts_energy, true)
template <class F, class = void>
struct has_sparse_tangent_method : std::false_type {};
template <class F>
struct has_sparse_tangent_method<
    F, std::void_t<decltype(std::declval<const F&>().tangent_entries(std::declval<std::vector<Entry>&>(),
                                                                     std::declval<std::vector<Entry>&>())),
                   decltype(std::declval<F&>().tangent_values(std::declval<const CVecRef&>(),
                                                              std::declval<const CVecRef&>(), 0.0,
                                                              std::declval<double*>(), std::declval<double*>()))>>
    : std::true_type {};
// ... and that adds them into an iteration matrix's storage as it evaluates them (EffectSet).
template <class F, class = void>
struct has_tangent_add_method : std::false_type {};
template <class F>
struct has_tangent_add_method<
    F, std::void_t<decltype(std::declval<F&>().tangent_add(std::declval<const CVecRef&>(), std::declval<const CVecRef&>(),
                                                           0.0, std::declval<TangentOut&>(),
                                                           std::size_t(0), std::size_t(0)))>> : std::true_type {};
// A force with the entry-by-entry tangent may still switch it off at run time.
NVIB_OPTIONAL_FLAG(has_sparse_tangent, has_sparse_tangent_method<F>::value)
#undef NVIB_OPTIONAL_FLAG

// A force with memory: its internal variables, committed once per accepted step.
template <class F, class = void>
struct has_state_methods : std::false_type {};
template <class F>
struct has_state_methods<
    F, std::void_t<decltype(std::declval<const F&>().has_state()), decltype(std::declval<const F&>().state_size()),
                   decltype(std::declval<const F&>().get_state(std::declval<double*>())),
                   decltype(std::declval<F&>().set_state(std::declval<const double*>())),
                   decltype(std::declval<F&>().reset_state()),
                   decltype(std::declval<F&>().commit_last_trial(std::declval<const double*>(),
                                                                 std::declval<const double*>(), 0.0)),
                   decltype(std::declval<F&>().commit_at(std::declval<const double*>(), std::declval<const double*>(),
                                                         0.0))>> : std::true_type {};
// hysteretic_dissipation(): the energy its laws with memory have dissipated.
template <class F, class = void>
struct has_hysteresis : std::false_type {};
template <class F>
struct has_hysteresis<F, std::void_t<decltype(std::declval<const F&>().hysteretic_dissipation())>> : std::true_type {};

// eval(const double* u, const double* v, double t, double* out): the force on contiguous arrays.
template <class F, class = void>
struct has_pointer_eval : std::false_type {};
template <class F>
struct has_pointer_eval<F, std::void_t<decltype(std::declval<const F&>().eval(
                               std::declval<const double*>(), std::declval<const double*>(), 0.0,
                               std::declval<double*>()))>> : std::true_type {};

// Energy accounting of a force: potential(u, t), input_power(u, v, t), dissipated_power(v).
template <class F, class = void>
struct has_energy : std::false_type {};
template <class F>
struct has_energy<F, std::void_t<decltype(std::declval<const F&>().potential(std::declval<const CVecRef&>(), 0.0)),
                                 decltype(std::declval<const F&>().input_power(std::declval<const CVecRef&>(),
                                                                               std::declval<const CVecRef&>(), 0.0)),
                                 decltype(std::declval<const F&>().dissipated_power(std::declval<const CVecRef&>()))>>
    : std::true_type {};
// input_power(u, v, t, side) and power_jumps(): the power with the limit of a kinked signal chosen (the effects).
template <class F, class = void>
struct has_sided_power : std::false_type {};
template <class F>
struct has_sided_power<F, std::void_t<decltype(std::declval<const F&>().input_power(
                              std::declval<const CVecRef&>(), std::declval<const CVecRef&>(), 0.0, 0))>>
    : std::true_type {};
// magnitude(u, v, t, out): out_i = the sum of |contributions| to the force on DOF i.
template <class F, class = void>
struct has_magnitude : std::false_type {};
template <class F>
struct has_magnitude<F, std::void_t<decltype(std::declval<F&>().magnitude(
                            std::declval<const CVecRef&>(), std::declval<const CVecRef&>(), 0.0,
                            std::declval<VecRef>()))>> : std::true_type {};
// A force that can be evaluated block by block along the DOFs (EffectSet: stream_halo(), stream_stages(),
// stage_size(), stream_loads(), stream_stage()).
template <class F, class = void>
struct has_stream : std::false_type {};
template <class F>
struct has_stream<F, std::void_t<decltype(std::declval<const F&>().stream_halo()),
                                 decltype(std::declval<const F&>().stream_stage(0, nullptr, nullptr, 0.0, nullptr, 0, 0))>>
    : std::true_type {};
// A force whose magnitude() evaluates the force again (a Python callable inside) says so.
template <class F, class = void>
struct magnitude_evaluates_force : std::false_type {};
template <class F>
struct magnitude_evaluates_force<F, std::void_t<decltype(F::magnitude_evaluates_force)>>
    : std::bool_constant<F::magnitude_evaluates_force> {};
}  // namespace traits

// K and C handed to Model: given as they are (checked for being one triangle), or sums of parts
// checked one by one (summed = true).
struct LinearPartsSummed {
  bool summed = false;
};

// One triangle of a symmetric matrix with its diagonal (as some programs store it) would be solved as a
// very different matrix: refused, naming it. A non-symmetric K or C is legitimate (follower forces,
// gyroscopic terms), and so is a strictly triangular one without a diagonal (a one-sided coupling); a
// triangle with its diagonal is half of a symmetric matrix.
inline void refuse_one_triangle(const SparseMatrix& A, const char* name) {
  Index above = 0, below = 0, diagonal = 0;
  for (Index j = 0; j < A.outerSize(); ++j)
    for (SparseMatrix::InnerIterator it(A, j); it; ++it)
      if (it.value() != 0.0) {
        above += it.row() < it.col();
        below += it.row() > it.col();
        diagonal += it.row() == it.col();
      }
  if (diagonal == 0) return;
  const std::string held = " and on its diagonal only (one triangle of a symmetric matrix, as some programs store "
                           "it): it would be solved as that triangle; give the whole matrix (for a symmetric one, "
                           "the triangle plus its transpose minus the diagonal)";
  NVIB_CHECK(above == 0 || below > 0, name, "the matrix has entries above its diagonal" + held);
  NVIB_CHECK(below == 0 || above > 0, name, "the matrix has entries below its diagonal" + held);
}

template <class Force = NoForce>
class Model {
 public:
  using force_type = Force;

  Model() = default;

  // K and C may be empty (0x0) when absent; they are kept sparse (compressed columns). With
  // LinearParts{true} they are sums of parts each checked on its own (the K given plus the springs of
  // the effects): a one-sided K given plus grounded springs is not one triangle of a symmetric matrix.
  Model(Mass mass, SparseMatrix K, SparseMatrix C, Force force = Force{}, LinearPartsSummed parts = {})
      : mass_(std::move(mass)), f_(std::move(force)) {
    const Index n = mass_.size();
    NVIB_CHECK(n > 0, "mass", "the model has no degree of freedom");
    auto lin = std::make_shared<Linear>();
    if (!mass_.warning().empty()) lin->warnings.push_back("mass: " + mass_.warning());
    has_K_ = check_linear_part(K, "K", n, lin->warnings, !parts.summed);
    has_C_ = check_linear_part(C, "C", n, lin->warnings, !parts.summed);
    lin->K = std::move(K);
    lin->C = std::move(C);
    lin->product = LinearProduct(has_K_ ? lin->K : SparseMatrix(n, n), has_C_ ? lin->C : SparseMatrix(n, n),
                                 mass_.is_diagonal() ? &mass_.diagonal_entries() : nullptr);
    lin_ = std::move(lin);
    uses_velocity_ = has_C_ || traits::uses_velocity(f_);
    uses_time_ = traits::uses_time(f_);
    is_linear_ = traits::is_linear(f_) && !has_state();
  }
  // Dense K and C (small models, tests): stored sparse, exact zeros dropped.
  Model(Mass mass, const Matrix& K, const Matrix& C, Force force = Force{})
      : Model(std::move(mass), to_sparse(K, "K"), to_sparse(C, "C"), std::move(force)) {}

  Model(Mass mass, Force force) : Model(std::move(mass), SparseMatrix(), SparseMatrix(), std::move(force)) {}

  Index size() const { return mass_.size(); }
  const Mass& mass() const { return mass_; }
  bool has_K() const { return has_K_; }
  bool has_C() const { return has_C_; }
  const SparseMatrix& K() const { return lin_->K; }
  const SparseMatrix& C() const { return lin_->C; }
  // How K u + C v is taken (band, rayleigh, shared or rows: linear_product.hpp).
  const LinearProduct& linear_product() const { return lin_->product; }
  // What an accepted model still wants said ("mass: nearly singular ...", "K: nearly symmetric ..."), each
  // prefixed by the argument it is about.
  const std::vector<std::string>& warnings() const { return lin_->warnings; }
  Force& nonlinear_force() { return f_; }
  const Force& nonlinear_force() const { return f_; }

  // Flags the schemes read: what is absent is not computed.
  bool uses_velocity() const { return uses_velocity_; }
  bool uses_time() const { return uses_time_; }
  bool is_linear() const { return is_linear_; }
  bool has_analytic_tangent() const { return traits::has_tangent_method<Force>::value && traits::has_tangent(f_); }
  // The force gives its tangent entry by entry (effects, laws on measures): sparse linear solvers apply.
  bool has_sparse_tangent() const {
    if constexpr (traits::has_sparse_tangent_method<Force>::value) return traits::has_sparse_tangent(f_);
    return false;
  }

  // ---- memory (laws with internal variables) ----
  // A model with memory is never linear; without it the calls below do nothing (no storage, and for
  // a force type without state methods no code at all).
  bool has_state() const {
    if constexpr (traits::has_state_methods<Force>::value) return f_.has_state();
    return false;
  }
  Index state_size() const {
    if constexpr (traits::has_state_methods<Force>::value) return f_.state_size();
    return 0;
  }
  void get_state(double* out) const {
    if constexpr (traits::has_state_methods<Force>::value) f_.get_state(out);
    (void)out;
  }
  void set_state(const double* x) {
    if constexpr (traits::has_state_methods<Force>::value) f_.set_state(x);
    (void)x;
  }
  // The laws' initial states (a new run).
  void reset_state() {
    if constexpr (traits::has_state_methods<Force>::value) f_.reset_state();
  }
  // Once per accepted step, at its state (u, v, t): the trial there becomes the committed state.
  // last_evaluation: the last force evaluation was at (u, v, t), so its trial is taken as it is;
  // otherwise (a step whose equation holds elsewhere, such as generalized-alpha's alpha-point) a new
  // trial is made there.
  void commit(const Vector& u, const Vector& v, double t, bool last_evaluation) {
    if constexpr (traits::has_state_methods<Force>::value) {
      if (!f_.has_state()) return;
      if (last_evaluation)
        f_.commit_last_trial(u.data(), v.data(), t);
      else
        f_.commit_at(u.data(), v.data(), t);
    }
    (void)u, (void)v, (void)t, (void)last_evaluation;
  }

  // out = K u + C v + f(u, v, t): everything on the left of M a + ... = 0.
  void force(const CVecRef& u, const CVecRef& v, double t, VecRef out, Stats& st) { force_into(u, v, t, out, st); }
  // The same on the steppers' own vectors (no Eigen::Ref temporaries: see acceleration()).
  void force(const Vector& u, const Vector& v, double t, Vector& out, Stats& st) { force_into(u, v, t, out, st); }

  // a = -M^{-1} (K u + C v + f(u, v, t))
  void acceleration(const CVecRef& u, const CVecRef& v, double t, VecRef a, Stats& st) {
    force_into(u, v, t, a, st);
    mass_.solve_negated_in_place(a);
  }
  // The same on the steppers' own vectors, without the two Eigen::Ref temporaries (and their
  // destructors) of the general form, which on a 6-DOF model cost as much as its mass solve.
  void acceleration(const Vector& u, const Vector& v, double t, Vector& a, Stats& st) {
    force_into(u, v, t, a, st);
    mass_.solve_negated_in_place(a);
  }

  // ---- the streamed explicit step ----
  // The acceleration of a lumped-mass model, block by block along the DOFs, between a scheme's update of
  // u (prepare(p, q): DOFs p .. q-1 of u, and of v where the forces read it, made ready) and of v
  // (finish(p, q): the force K u + C v + f of DOFs p .. q-1 is final in a, which the scheme divides by
  // the mass, a_i *= mass().negated_inverse()_i, as it uses it), so that an explicit step makes one pass over memory
  // instead of one per stage (update u, loads, each group of effects, K u + C v, mass, update v).
  // Possible where every effect reaches DOFs within a bounded distance of its index and K and C are
  // within a band (a chain, a shear building, arrays along the DOFs): can_stream(). The stages run
  // behind the prepared DOFs, each a block behind the one before it, so that every DOF receives its
  // forces in the order eval() adds them: the same bits as acceleration().
  static constexpr Index kStreamBlock = 2048;
  bool can_stream() const {
    if (!stream_allowed_) return false;
    if constexpr (traits::has_stream<Force>::value) {
      const std::int64_t h = f_.stream_halo();
      const Index reach = std::max<Index>(static_cast<Index>(h), lin_->product.reach());
      return mass_.is_diagonal() && h >= 0 && 4 * reach <= kStreamBlock && size() >= 4 * kStreamBlock;
    }
    return false;
  }
  // Off: the steppers made from this model take the stage-by-stage path (tests, benchmarks).
  void allow_stream(bool on) { stream_allowed_ = on; }

  template <class Prepare, class Finish>
  void stream_acceleration(const double* u, const double* v, double t, double* a, Stats& st, Prepare&& prepare,
                           Finish&& finish) {
    if constexpr (traits::has_stream<Force>::value) {
      ++st.num_force_evals;
      const Index n = size(), B = kStreamBlock;
      const Index reach = std::max<Index>(static_cast<Index>(f_.stream_halo()), lin_->product.reach());
      const std::size_t effect_stages = f_.stream_stages();
      const bool linear = has_K_ || has_C_;
      const std::size_t stages = effect_stages + (linear ? 1 : 0);
      Index prepared = 0, finished = 0;
      for (Index b = 0; finished < n; ++b) {
        const Index ready = std::min<Index>(n, (b + 1) * B + reach);
        if (ready > prepared) {
          prepare(prepared, ready);
          f_.stream_loads(t, a, prepared, ready);
          prepared = ready;
        }
        Index complete = prepared;  // the DOFs every stage is done with
        for (std::size_t s = 0; s < stages; ++s) {
          const Index blk = b - static_cast<Index>(s), size_s = s < effect_stages ? static_cast<Index>(f_.stage_size(s)) : n;
          const Index k0 = std::max<Index>(0, blk * B), k1 = std::min<Index>(size_s, std::max<Index>(0, (blk + 1) * B));
          if (k1 > k0) {
            if (s < effect_stages)
              f_.stream_stage(s, u, v, t, a, static_cast<std::size_t>(k0), static_cast<std::size_t>(k1));
            else
              lin_->product.add(u, v, a, k0, k1);
          }
          if (k1 < size_s) complete = std::min<Index>(complete, std::max<Index>(0, k1 - reach));
        }
        if (complete > finished) {
          finish(finished, complete);
          finished = complete;
        }
      }
    } else {
      (void)u, (void)v, (void)t, (void)a, (void)st, (void)prepare, (void)finish;
    }
  }

  // out_i = sum of |terms| of (K u + C v + f)_i: the scale of its round-off
  // (forces that cancel, as at a static preload, leave a residual of about
  // eps times this). A force without magnitude() counts as |f|.
  void force_magnitude(const CVecRef& u, const CVecRef& v, double t, VecRef out) {
    if constexpr (traits::has_magnitude<Force>::value) {
      f_.magnitude(u, v, t, out);
    } else {
      eval_f(u, v, t, out);
      out = out.cwiseAbs();
    }
    if (has_K_) add_abs_product(lin_->K, u, out);
    if (has_C_) add_abs_product(lin_->C, v, out);
  }
  // The same where the net force G = f + K u + C v at (u, v, t) is at hand: a force whose magnitude
  // would evaluate it again (a Python callable) is not, 2 (|G| + |K||u| + |C||v|) standing for it
  // (|f| <= |G| + |K||u| + |C||v|; the terms that cancel inside f itself are not seen, which only makes
  // the bound stricter).
  void force_magnitude(const CVecRef& u, const CVecRef& v, double t, const CVecRef& net, VecRef out) {
    if constexpr (traits::has_magnitude<Force>::value && !traits::magnitude_evaluates_force<Force>::value) {
      force_magnitude(u, v, t, out);
    } else {
      out = net.cwiseAbs();
      if (has_K_) add_abs_product(lin_->K, u, out);
      if (has_C_) add_abs_product(lin_->C, v, out);
      out *= 2.0;
    }
  }

  // ---- energy accounting ----
  // Whether every force in the model is accounted for: a force without
  // potential/power methods is not, nor one whose accounts_energy() says no.
  bool accounts_energy() const {
    if constexpr (traits::has_energy<Force>::value) return traits::accounts_energy(f_);
    return false;
  }
  double kinetic(const CVecRef& v) {
    work(v.size());
    mass_.apply(v, work_);
    return 0.5 * v.dot(work_);
  }
  double potential(const CVecRef& u, double t) {
    double e = 0.0;
    if (has_K_) {
      work(u.size());
      work_.noalias() = lin_->K * u;
      e += 0.5 * u.dot(work_);
    }
    if constexpr (traits::has_energy<Force>::value) e += f_.potential(u, t);
    return e;
  }
  // Whether input_power() can differ between the two sides of a step point (see below).
  bool power_jumps() const {
    if constexpr (traits::has_sided_power<Force>::value) return f_.power_jumps();
    return false;
  }
  // side: -1 the power as a step ends, +1 as the next one starts (they differ where a signal's rate jumps).
  double input_power(const CVecRef& u, const CVecRef& v, double t, int side = 0) {
    if constexpr (traits::has_sided_power<Force>::value) return f_.input_power(u, v, t, side);
    if constexpr (traits::has_energy<Force>::value) return f_.input_power(u, v, t);
    (void)side;
    return 0.0;
  }
  // The energy dissipated by the laws with memory so far (their committed states).
  double hysteretic_dissipation() const {
    if constexpr (traits::has_hysteresis<Force>::value) return f_.hysteretic_dissipation();
    return 0.0;
  }
  double dissipated_power(const CVecRef& v) {
    double p = 0.0;
    if (has_C_) {
      work(v.size());
      work_.noalias() = lin_->C * v;
      p += v.dot(work_);
    }
    if constexpr (traits::has_energy<Force>::value) p += f_.dissipated_power(v);
    return p;
  }

  // Kt = K + df/du, Ct = C + df/dv.  `finite_difference` forces the numerical tangent.
  void tangent(const CVecRef& u, const CVecRef& v, double t, MatRef Kt, MatRef Ct, Stats& st,
               bool finite_difference = false) {
    ++st.num_tangent_evals;
    if (!finite_difference && has_analytic_tangent()) {
      if constexpr (traits::has_tangent_method<Force>::value) f_.tangent(u, v, t, Kt, Ct);
    } else {
      fd_tangent(u, v, t, Kt, Ct, st);
    }
    if (has_K_) Kt += lin_->K;
    if (has_C_) Ct += lin_->C;
  }
  // The nonlinear force's tangent entries (K and C, in a fixed order) and their values at (u, v, t);
  // K() and C() hold the linear parts. Only where has_sparse_tangent().
  void tangent_entries(std::vector<Entry>& K, std::vector<Entry>& C) const {
    if constexpr (traits::has_sparse_tangent_method<Force>::value) f_.tangent_entries(K, C);
  }
  void tangent_values(const CVecRef& u, const CVecRef& v, double t, double* K, double* C, Stats& st) {
    ++st.num_tangent_evals;
    if constexpr (traits::has_sparse_tangent_method<Force>::value) f_.tangent_values(u, v, t, K, C);
  }
  // The same values into out.K and out.C (nk and nc of them), each also added into an iteration matrix's
  // storage at its position (TangentOut): in one pass where the force can, else listed
  // and then added. Returns the sum of x - x over the values (0 unless one is not finite).
  double tangent_add(const CVecRef& u, const CVecRef& v, double t, TangentOut out, std::size_t nk,
                     std::size_t nc, Stats& st) {
    ++st.num_tangent_evals;
    if constexpr (traits::has_tangent_add_method<Force>::value) {
      return f_.tangent_add(u, v, t, out, nk, nc);
    } else {
      if constexpr (traits::has_sparse_tangent_method<Force>::value) f_.tangent_values(u, v, t, out.K, out.C);
      return add_listed(out, nk, nc);
    }
  }

 private:
  void eval_f(const CVecRef& u, const CVecRef& v, double t, VecRef out) { f_(u, v, t, out); }

  // force() on any contiguous vectors: a force with eval() on pointers gets their data.
  template <class U, class W, class Out>
  void force_into(const U& u, const W& v, double t, Out& out, Stats& st) {
    ++st.num_force_evals;
    if constexpr (traits::has_pointer_eval<Force>::value)
      f_.eval(u.data(), v.data(), t, out.data());
    else
      f_(u, v, t, out);
    if (has_K_ || has_C_) add_linear(u.data(), v.data(), out.data());
  }
  // out += K u + C v in one pass by rows (linear_product.hpp), through the model's own scratch where
  // the product's form takes one (each run's stepper holds a copy of the model: the scratch is its own).
  void add_linear(const double* u, const double* v, double* out) const {
    const LinearProduct& p = lin_->product;
    if (!p.uses_scratch()) return p.add(u, v, out);
    if (product_scratch_.size() != size()) product_scratch_.resize(size());  // (the first evaluation, at a run's start)
    p.add(u, v, out, product_scratch_.data());
  }

  // Central differences, step cbrt(eps) * max(|x_j|, 1) (the usual choice for
  // a second-order difference); velocity columns only if f uses velocity.
  void fd_tangent(const CVecRef& u, const CVecRef& v, double t, MatRef Kt, MatRef Ct, Stats& st) {
    if (fp_.size() != size()) {  // allocated on first use: most models never need them
      fp_.resize(size());
      fm_.resize(size());
    }
    fu_ = u;
    fv_ = v;
    fd_columns(fu_, t, Kt, st);
    Ct.setZero();
    if (traits::uses_velocity(f_)) fd_columns(fv_, t, Ct, st);
  }

  // J(:, j) = df/dx_j where x is fu_ or fv_ (restored on return).
  void fd_columns(Vector& x, double t, MatRef J, Stats& st) {
    const double rel = std::cbrt(std::numeric_limits<double>::epsilon());
    for (Index j = 0; j < size(); ++j) {
      const double xj = x[j], hj = rel * std::max(std::abs(xj), 1.0);
      x[j] = xj + hj;
      eval_f(fu_, fv_, t, fp_);
      x[j] = xj - hj;
      eval_f(fu_, fv_, t, fm_);
      x[j] = xj;
      J.col(j) = (fp_ - fm_) / (2.0 * hj);
      st.num_fd_force_evals += 2;
    }
  }

  // Relative asymmetry below which a non-symmetric K or C is taken for a symmetric one with round-off.
  static constexpr double kNearlySymmetric = 1e-8;

  static bool check_linear_part(SparseMatrix& A, const char* name, Index n, std::vector<std::string>& warnings,
                                bool check_triangle) {
    if (A.rows() == 0 && A.cols() == 0) return false;
    NVIB_CHECK(A.rows() == n && A.cols() == n, name,
               "expected shape (" + std::to_string(n) + ", " + std::to_string(n) + "), got (" +
                   std::to_string(A.rows()) + ", " + std::to_string(A.cols()) + ")");
    A.makeCompressed();
    for (Index k = 0; k < A.nonZeros(); ++k)
      NVIB_CHECK(std::isfinite(A.valuePtr()[k]), name, "the matrix has non-finite entries");
    if (check_triangle) refuse_one_triangle(A, name);
    Index above = 0, below = 0;
    double largest = 0.0;
    for (Index j = 0; j < A.outerSize(); ++j)
      for (SparseMatrix::InnerIterator it(A, j); it; ++it)
        if (it.value() != 0.0) {
          above += it.row() < it.col();
          below += it.row() > it.col();
          largest = std::max(largest, std::abs(it.value()));
        }
    // Nearly symmetric but not quite: round-off in an assembly that meant a symmetric matrix.
    if (above > 0 && below > 0) {
      SparseMatrix D = A - SparseMatrix(A.transpose());
      double asym = 0.0;
      Index ai = 0, aj = 0;
      for (Index j = 0; j < D.outerSize(); ++j)
        for (SparseMatrix::InnerIterator it(D, j); it; ++it)
          if (std::abs(it.value()) > asym) asym = std::abs(it.value()), ai = it.row(), aj = j;
      if (asym > 0.0 && asym <= kNearlySymmetric * largest)
        warnings.push_back(std::string(name) + ": the matrix is symmetric only up to " + detail::fmt(asym / largest) +
                           " of its largest entry (|" + name + "[" + std::to_string(ai) + ", " + std::to_string(aj) +
                           "] - " + name + "[" + std::to_string(aj) + ", " + std::to_string(ai) +
                           "]| = " + detail::fmt(asym) +
                           "): probably round-off in its assembly; it is used as given (non-symmetric), "
                           "symmetrise it, (A + A.T) / 2, if it is meant to be symmetric");
    }
    return A.nonZeros() > 0;
  }
  static SparseMatrix to_sparse(const Matrix& A, const char* name) {
    if (A.size() == 0) return SparseMatrix();
    NVIB_CHECK(A.allFinite(), name, "the matrix has non-finite entries");
    return A.sparseView(1.0, 0.0);  // every nonzero kept
  }

  Mass mass_;
  // The linear parts, never changed after construction: shared by the copies of the model.
  struct Linear {
    SparseMatrix K, C;
    std::vector<std::string> warnings;  // see warnings()
    LinearProduct product;  // out += K u + C v, for the force
  };
  // out += |A| |x| (no stored |A|: it is only needed for round-off estimates)
  static void add_abs_product(const SparseMatrix& A, const CVecRef& x, VecRef out) {
    for (Index j = 0; j < A.outerSize(); ++j) {
      const double xj = std::abs(x[j]);
      for (SparseMatrix::InnerIterator it(A, j); it; ++it) out[it.row()] += std::abs(it.value()) * xj;
    }
  }
  std::shared_ptr<const Linear> lin_ = std::make_shared<const Linear>();
  Force f_{};
  bool has_K_ = false, has_C_ = false;
  bool uses_velocity_ = false, uses_time_ = false, is_linear_ = true;
  bool stream_allowed_ = true;
  Vector fu_, fv_, fp_, fm_;  // finite-difference workspace (sized on first use)
  Vector work_;               // energy accounting (sized on first use)
  mutable Vector product_scratch_;  // add_linear(): the product's scratch (sized on first use)
  void work(Index n) {
    if (work_.size() != n) work_.resize(n);
  }
};

// Deduction helpers.
template <class Force>
Model<Force> make_model(Mass mass, Force force, const Matrix& K = Matrix(), const Matrix& C = Matrix()) {
  return Model<Force>(std::move(mass), K, C, std::move(force));
}
template <class Force>
Model<Force> make_model(Mass mass, Force force, SparseMatrix K, SparseMatrix C = SparseMatrix()) {
  return Model<Force>(std::move(mass), std::move(K), std::move(C), std::move(force));
}
inline Model<NoForce> make_linear_model(Mass mass, const Matrix& K, const Matrix& C = Matrix()) {
  return Model<NoForce>(std::move(mass), K, C, NoForce{});
}
inline Model<NoForce> make_linear_model(Mass mass, SparseMatrix K, SparseMatrix C = SparseMatrix()) {
  return Model<NoForce>(std::move(mass), std::move(K), std::move(C), NoForce{});
}

}  // namespace nvib
