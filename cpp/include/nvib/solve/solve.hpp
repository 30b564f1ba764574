// The one loop shared by every scheme: step, save every k-th state, detect
// divergence, sum the counters, call an observer (progress) and poll for an
// interrupt about every 50 ms of work. It knows no scheme: a scheme names its
// stepper (Scheme::stepper<Model>).
#pragma once

#include <chrono>
#include <cstring>
#include <exception>
#include <limits>
#include <type_traits>
#include <utility>

#include "../base/interrupt.hpp"
#include "../base/memory.hpp"
#include "../schemes/stepper.hpp"

namespace nvib {

struct SolveOptions {
  double t0 = 0.0;
  std::int64_t save_every = 1;  // save steps 0, k, 2k, ... and always the last one
  std::vector<Index> dofs;      // DOFs to save; empty means all
  // |u_i| beyond this bound counts as divergence (non-finite states always do).
  // NaN (the default) means default_max_displacement() of the initial state;
  // infinity means no bound.
  double max_displacement = std::numeric_limits<double>::quiet_NaN();
  bool throw_on_failure = true;
  // Seconds of work between observer calls and interrupt polls (on a clock, not a count of steps).
  double observe_period = 0.05;
  // Record kinetic and potential energy, work of the loads, dissipated energy
  // and the balance error at every saved state (powers integrated every step
  // by the trapezoidal rule).
  bool energy = false;
  // With energy: a run whose energy balance error exceeds this fraction of the
  // energy scale (the largest |kinetic| + |potential| + |work in| + |dissipated|
  // so far) stops as diverged. Catches an instability that stays finite (a
  // vehicle launched off its rails) which no displacement bound sees.
  // Checked every step from the 10th on; infinity means no check; NaN (the
  // default) means kDefaultMaxEnergyError with energy, no check without.
  double max_energy_error = std::numeric_limits<double>::quiet_NaN();
  // An exception out of the step loop (an interrupt hook, a throwing force or observer) leaves as a
  // PartialRun carrying the history saved so far and the exception, instead of the exception alone.
  bool keep_partial = false;
  // The saved history may take at most this many bytes; NaN (the default): half the memory
  // available when the run starts; infinity: no limit. Checked before anything is allocated.
  double max_history_bytes = std::numeric_limits<double>::quiet_NaN();
};

// Bytes of the history a run saves: nsave states of t and (u, v, a) on m DOFs, plus 5 energy columns.
inline double history_bytes(std::int64_t nsave, Index m, bool energy) {
  return 8.0 * static_cast<double>(nsave) * (1.0 + 3.0 * static_cast<double>(m) + (energy ? 5.0 : 0.0));
}

// Columns of Result::energy.
enum EnergyColumn { kinetic = 0, potential = 1, work_in = 2, dissipated = 3, balance_error = 4 };

struct Result {
  Vector t;
  History u, v, a;  // (n_saved, n_saved_dofs), row-major
  History energy;   // (n_saved, 5) if requested: see EnergyColumn
  std::vector<Index> dofs;
  Stats stats;
  Status status = Status::success;
  Failure failure;
  std::int64_t num_steps_requested = 0;
  // Largest equilibrium residual of an accepted step relative to its force
  // scale (implicit schemes; NaN for the others and for linear models, whose
  // single solve is exact up to round-off). Newton keeps it below about rtol;
  // iteration = none reports here what it leaves unbalanced.
  double max_residual = std::numeric_limits<double>::quiet_NaN();
};

// The energy check's default limit: half the energy scale. A sound run's
// balance error is orders of magnitude below it; an unstable one reaches it.
constexpr double kDefaultMaxEnergyError = 0.5;

// First step at which SolveOptions::max_energy_error is checked.
constexpr std::int64_t kEnergyCheckFrom = 10;

// Scale factor of the default divergence bound.
constexpr double kBoundFactor = 1e10;

// The default bound on |u_i|: 1e10 x max(1, max|u|, max|v| T) for a run of
// duration T from (u, v). Far beyond any physical response of a model started
// there, yet reached long before a diverging state overflows, so such a run
// stops naming the DOF instead of running on with inf or NaN.
inline double default_max_displacement(const Vector& u, const Vector& v, double duration) {
  double scale = 1.0;
  if (u.size() > 0) scale = std::max(scale, u.cwiseAbs().maxCoeff());
  if (v.size() > 0) scale = std::max(scale, v.cwiseAbs().maxCoeff() * std::abs(duration));
  return kBoundFactor * scale;
}

// Number of steps to reach t_end: t_end/dt rounded when it is an integer up
// to round-off, else rounded up (the run then ends at the first multiple of dt past t_end).
inline std::int64_t steps_to_reach(double t0, double t_end, double dt) {
  NVIB_CHECK(std::isfinite(t_end), "t_end", "must be finite");
  NVIB_CHECK(std::isfinite(dt) && dt > 0.0, "dt", "the time step must be finite and > 0, got " + detail::fmt(dt));
  NVIB_CHECK(t_end > t0, "t_end", "must be > t0 (" + detail::fmt(t0) + "), got " + detail::fmt(t_end));
  const double r = (t_end - t0) / dt;
  NVIB_CHECK(r < 9.0e15, "dt", "too many steps (t_end - t0)/dt = " + detail::fmt(r));
  const double nearest = std::round(r);
  if (std::abs(r - nearest) <= 1e-9 * std::max(1.0, r)) return std::max<std::int64_t>(1, static_cast<std::int64_t>(nearest));
  return static_cast<std::int64_t>(std::ceil(r));
}

// Names the first offending quantity: u beyond the bound or non-finite, then v, then a.
template <class Stepper>
Failure divergence(const Stepper& st, std::int64_t step, double bound) {
  Failure f;
  f.status = Status::diverged;
  f.step = step;
  f.t = st.time();
  const char* what = "u";
  double value = 0.0;
  const Vector* vecs[3] = {&st.u(), &st.v(), &st.a()};
  const char* names[3] = {"u", "v", "a"};
  for (int q = 0; q < 3 && f.dof < 0; ++q)
    for (Index d = 0; d < vecs[q]->size(); ++d) {
      const double x = (*vecs[q])[d];
      if (!std::isfinite(x) || (q == 0 && !(std::abs(x) <= bound))) {
        f.dof = d;
        what = names[q];
        value = x;
        break;
      }
    }
  const bool beyond = std::isfinite(value);
  f.message = "diverged at t = " + detail::fmt(f.t) + " (step " + std::to_string(step) + "): " + what + "[" +
              std::to_string(f.dof) + "] = " + detail::fmt(value) +
              (beyond ? " beyond the bound " + detail::fmt(bound) : std::string(", not finite"));
  return f;
}

// Integer tests on the bits of the state, with no floating-point dependency
// chain: a double is not finite exactly when its exponent bits are all ones,
// and the bits of non-negative doubles (NaN above +inf) order like the numbers.
namespace detail {
constexpr std::uint64_t kExpBits = 0x7FF0000000000000ull, kAbsBits = 0x7FFFFFFFFFFFFFFFull;
constexpr std::uint64_t kExpOne = 0x0010000000000000ull;  // all-ones exponent + this sets bit 63
inline std::uint64_t bits_of(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}
// Bit 63 set when some entry is not finite.
inline std::uint64_t nonfinite_bits(const Vector& x) {
  std::uint64_t bad = 0;
  const double* p = x.data();
  for (Index i = 0, n = x.size(); i < n; ++i) bad |= (bits_of(p[i]) & kExpBits) + kExpOne;
  return bad;
}
}  // namespace detail

// Every |u_i| <= bound and finite.
// A comparison with NaN is false and |inf| exceeds every finite bound (an infinite bound is taken as
// the largest finite double), so one branch-free conjunction of comparisons, two per SSE2
// instruction, also catches the non-finite entries.
inline bool displacement_ok(const Vector& u, double bound) {
  const double* p = u.data();
  const double finite_bound = std::min(bound, std::numeric_limits<double>::max());
  bool ok = true;
  detail::for_each_index(u.size(), [&ok, p, finite_bound](Index i) { ok &= std::abs(p[i]) <= finite_bound; });
  return ok;
}
// Every entry of v and a finite.
inline bool rates_ok(const Vector& v, const Vector& a) {
  return !((detail::nonfinite_bits(v) | detail::nonfinite_bits(a)) >> 63);
}

// Steppers that measure the equilibrium residual of each accepted step (the implicit ones).
template <class S, class = void>
struct has_accepted_residual : std::false_type {};
template <class S>
struct has_accepted_residual<S, std::void_t<decltype(std::declval<const S&>().accepted_residual())>>
    : std::true_type {};

template <class Stepper>
Failure energy_failure(const Stepper& st, std::int64_t step, double balance, double scale, double limit) {
  Failure f;
  f.status = Status::diverged;
  f.step = step;
  f.t = st.time();
  f.message = "diverged at t = " + detail::fmt(f.t) + " (step " + std::to_string(step) +
              "): the energy balance error " + detail::fmt(balance) + " is " + detail::fmt(std::abs(balance) / scale) +
              " of the energy scale " + detail::fmt(scale) + ", beyond max_energy_error = " + detail::fmt(limit) +
              ": the scheme created or destroyed that energy (unstable, or the step is far too coarse)";
  return f;
}

// One step with the loop's divergence test (every entry of u, v and a
// finite), for stepping by hand: the failure, if any, in `failure`.
template <class Stepper>
Status checked_step(Stepper& st, Failure& failure) {
  const Status s = st.step();
  if (s != Status::success) {
    failure = st.failure();
    return s;
  }
  if (!displacement_ok(st.u(), std::numeric_limits<double>::infinity()) || !rates_ok(st.v(), st.a())) {
    failure = divergence(st, st.step_index(), std::numeric_limits<double>::infinity());
    return Status::diverged;
  }
  return s;
}

struct NoObserver {
  void operator()(std::int64_t, std::int64_t) const {}
};

// What leaves integrate() and solve() with SolveOptions::keep_partial when the step loop throws: the
// history saved before the exception (counters of the steps taken) and the exception itself.
struct PartialRun {
  Result partial;
  std::exception_ptr cause;
};

template <class Stepper, class Observer = NoObserver>
Result integrate(Stepper& st, double t_end, const SolveOptions& opt, Observer&& observe = Observer{}) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  const Index n = st.size();
  NVIB_CHECK(opt.save_every >= 1, "save_every", "must be >= 1, got " + std::to_string(opt.save_every));
  NVIB_CHECK(opt.observe_period > 0.0, "observe_period", "must be > 0");
  NVIB_CHECK(std::isnan(opt.max_displacement) || opt.max_displacement > 0.0, "max_displacement",
                  "must be > 0 (infinity for no bound, NaN for the default)");
  for (Index d : opt.dofs)
    NVIB_CHECK(d >= 0 && d < n, "dofs", "index " + std::to_string(d) + " is out of range for " +
                                         std::to_string(n) + " degrees of freedom");
  const std::int64_t nsteps = steps_to_reach(st.time(), t_end, st.dt());
  const std::int64_t k = opt.save_every;
  const std::int64_t nsave = nsteps / k + 1 + (nsteps % k != 0 ? 1 : 0);
  {
    const Index m = opt.dofs.empty() ? n : static_cast<Index>(opt.dofs.size());
    const double bytes = history_bytes(nsave, m, opt.energy);
    const double limit = std::isnan(opt.max_history_bytes) ? 0.5 * available_memory_bytes() : opt.max_history_bytes;
    NVIB_CHECK(limit <= 0.0 || bytes <= limit, "save_every, dofs",
               "the saved history would need " + detail::fmt(bytes / 1e9) + " GB (" + std::to_string(nsave) +
                   " states of " + std::to_string(m) + " DOFs: t, u, v, a" + (opt.energy ? ", energy" : "") +
                   "), more than the limit of " + detail::fmt(limit / 1e9) + " GB" +
                   (std::isnan(opt.max_history_bytes) ? " (half the memory available)" : "") +
                   "; save fewer states (a larger save_every) or fewer DOFs (dofs)");
    NVIB_CHECK(static_cast<double>(nsave) * static_cast<double>(std::max<Index>(m, 1)) <= 9.0e15, "save_every",
               "the run would save " + std::to_string(nsave) + " states; raise save_every");
  }

  Result res;
  res.num_steps_requested = nsteps;
  if (opt.dofs.empty()) {
    res.dofs.resize(static_cast<size_t>(n));
    for (Index i = 0; i < n; ++i) res.dofs[static_cast<size_t>(i)] = i;
  } else {
    res.dofs = opt.dofs;
  }
  const Index m = static_cast<Index>(res.dofs.size());
  res.t.resize(nsave);
  res.u.resize(nsave, m);
  res.v.resize(nsave, m);
  res.a.resize(nsave, m);
  const double energy_limit = std::isnan(opt.max_energy_error)
                                 ? (opt.energy ? kDefaultMaxEnergyError : std::numeric_limits<double>::infinity())
                                 : opt.max_energy_error;
  NVIB_CHECK(energy_limit > 0.0, "max_energy_error", "must be > 0 (infinity for no check)");
  const bool energy_check = energy_limit < std::numeric_limits<double>::infinity();
  NVIB_CHECK(!energy_check || opt.energy, "max_energy_error", "needs the energy accounting (energy = true)");
  if (opt.energy) {
    NVIB_CHECK(st.model().accounts_energy(), "energy",
                    "the model has a force whose energy is unknown (a user callable); "
                    "energy accounting needs built-in effects");
    res.energy.resize(nsave, 5);
  }
  // Energy: powers at the last state, integrals so far, initial total.
  double p_in = 0.0, p_diss = 0.0, work = 0.0, diss = 0.0, e0 = 0.0, escale = 0.0;
  auto& model = st.model();
  const bool sided = opt.energy && model.power_jumps();  // else one input power serves both sides of a step point
  if (opt.energy) {
    p_in = model.input_power(st.u(), st.v(), st.time(), +1);
    p_diss = model.dissipated_power(st.v());
    const double ek = model.kinetic(st.v()), ep = model.potential(st.u(), st.time());
    e0 = ek + ep;
    escale = std::abs(ek) + std::abs(ep);
  }
  Index row = 0;
  const bool all_dofs = opt.dofs.empty();
  double ek = 0.0, ep = 0.0;  // kinetic and potential energy of the current state, when have_energy
  bool have_energy = false;
  auto save = [&]() {
    res.t[row] = st.time();
    double* pu = res.u.data() + row * m;  // rows are contiguous (row-major)
    double* pv = res.v.data() + row * m;
    double* pa = res.a.data() + row * m;
    const double *su = st.u().data(), *sv = st.v().data(), *sa = st.a().data();
    if (all_dofs) {
      for (Index j = 0; j < m; ++j) {
        pu[j] = su[j];
        pv[j] = sv[j];
        pa[j] = sa[j];
      }
    } else {
      for (Index j = 0; j < m; ++j) {
        const Index d = res.dofs[static_cast<size_t>(j)];
        pu[j] = su[d];
        pv[j] = sv[d];
        pa[j] = sa[d];
      }
    }
    if (opt.energy) {
      // the energy check may have computed them for this state already
      if (!have_energy) {
        ek = model.kinetic(st.v());
        ep = model.potential(st.u(), st.time());
      }
      res.energy(row, kinetic) = ek;
      res.energy(row, potential) = ep;
      res.energy(row, work_in) = work;
      res.energy(row, dissipated) = diss;
      res.energy(row, balance_error) = ek + ep + diss - work - e0;
    }
    ++row;
  };
  save();
  const double h = st.dt();

  const Stats before = st.stats();
  const double bound = std::isnan(opt.max_displacement)
                           ? default_max_displacement(st.u(), st.v(), t_end - st.time())
                           : opt.max_displacement;
  double max_residual = std::numeric_limits<double>::quiet_NaN();
  // Countdowns instead of i % k: an integer division per step costs as much as a small model's force.
  std::int64_t to_save = k, done = 0;
  ClockPoll poll(opt.observe_period);
  // The history up to the last saved state, the counters of this call and the wall time.
  auto finish = [&] {
    if (row < nsave) {
      res.t.conservativeResize(row);
      res.u.conservativeResize(row, m);
      res.v.conservativeResize(row, m);
      res.a.conservativeResize(row, m);
      if (opt.energy) res.energy.conservativeResize(row, 5);
    }
    res.max_residual = max_residual;
    res.stats = st.stats();
    res.stats -= before;  // counters of this call only (the stepper's own are cumulative)
    res.stats.wall_time = std::chrono::duration<double>(clock::now() - start).count();
  };
  try {
    for (std::int64_t i = 1; i <= nsteps; ++i) {
      Status s = st.step();
      const bool saving = --to_save == 0 || i == nsteps;
      if (s == Status::success) {
        // u every step; v and a where a state is saved. A non-finite v_n or a_n
        // makes u_{n+1} non-finite in every scheme, so a run still stops within
        // one step, and no saved row holds a non-finite value.
        if (!displacement_ok(st.u(), bound) || (saving && !rates_ok(st.v(), st.a()))) {
          res.failure = divergence(st, i, bound);
          s = Status::diverged;
        }
      } else {
        res.failure = st.failure();
      }
      if (s != Status::success) {
        res.status = s;
        break;
      }
      if constexpr (has_accepted_residual<Stepper>::value) {
        const double r = st.accepted_residual();
        if (r > max_residual || (std::isnan(max_residual) && !std::isnan(r))) max_residual = r;
      }
      if (opt.energy) {
        // the input power as this step ends and as the next starts: they differ where a signal's rate jumps
        const double q_in = model.input_power(st.u(), st.v(), st.time(), -1), q_diss = model.dissipated_power(st.v());
        work += 0.5 * h * (p_in + q_in);
        diss += 0.5 * h * (p_diss + q_diss);
        p_in = sided ? model.input_power(st.u(), st.v(), st.time(), +1) : q_in;
        p_diss = q_diss;
        // From the 10th step: a run forced from rest starts with a tiny energy of which
        // the start-up balance error is a large fraction (about 1/n^2: 0.9 at step 1,
        // 0.005 at step 10 on the building); an unstable run stays near 1.
        if (energy_check && i >= kEnergyCheckFrom) {
          ek = model.kinetic(st.v());
          ep = model.potential(st.u(), st.time());
          have_energy = true;
          escale = std::max(escale, std::abs(ek) + std::abs(ep) + std::abs(work) + std::abs(diss));
          const double balance = ek + ep + diss - work - e0;
          if (std::abs(balance) > energy_limit * escale) {
            res.failure = energy_failure(st, i, balance, escale, energy_limit);
            res.status = Status::diverged;
            break;
          }
        }
      }
      done = i;
      if (saving) {
        save();
        to_save = k;
      }
      have_energy = false;
      if (poll.tick()) {
        observe(i, nsteps);
        poll_interrupt();
      }
    }
  } catch (...) {
    if (!opt.keep_partial) throw;
    finish();
    res.status = Status::interrupted;
    res.failure = Failure{};
    res.failure.status = Status::interrupted;
    res.failure.step = done + 1;  // the step under way (a step the interrupt hook stopped after is complete)
    res.failure.t = row > 0 ? res.t[row - 1] : st.time();
    res.failure.message = "interrupted after step " + std::to_string(done) + " of " + std::to_string(nsteps) +
                          "; the history is saved up to t = " +
                          (row > 0 ? detail::fmt(res.t[row - 1]) : std::string("the start"));
    throw PartialRun{std::move(res), std::current_exception()};
  }
  observe(done, nsteps);  // once at the end too, however short the run
  finish();
  if (res.status != Status::success && opt.throw_on_failure) throw_failure(res.failure);
  return res;
}

template <class Scheme, class ModelT>
typename Scheme::template stepper<ModelT> make_stepper(const Scheme& scheme, ModelT model, double dt) {
  return typename Scheme::template stepper<ModelT>(scheme, std::move(model), dt);
}

// Integrates from (t0, u0, v0) to t_end. Counters include the start-up
// (initial acceleration, PIM's exponential).
template <class Scheme, class ModelT, class Observer = NoObserver>
Result solve(const ModelT& model, const Scheme& scheme, double dt, double t_end, const Vector& u0,
             const Vector& v0, const SolveOptions& opt = {}, Observer&& observe = Observer{}) {
  using clock = std::chrono::steady_clock;
  const auto start = clock::now();
  steps_to_reach(opt.t0, t_end, dt);  // validate before any work
  auto st = make_stepper(scheme, model, dt);
  st.initialize(opt.t0, u0, v0);
  const Stats init = st.stats();
  SolveOptions inner = opt;
  inner.throw_on_failure = false;
  Result res;
  try {
    res = integrate(st, t_end, inner, std::forward<Observer>(observe));
  } catch (PartialRun& p) {
    p.partial.stats += init;
    p.partial.stats.wall_time = std::chrono::duration<double>(clock::now() - start).count();
    throw;
  }
  const double wall = std::chrono::duration<double>(clock::now() - start).count();
  res.stats += init;
  res.stats.wall_time = wall;
  if (res.status != Status::success && opt.throw_on_failure) throw_failure(res.failure);
  return res;
}

}  // namespace nvib
