// The Python adapters of nvib._core: a force given as Python callables
// (a vector force(u, v, t) with an optional tangent, and scalar laws on
// measures), as a force functor for Model. Every error names the callback.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <vector>

#include <nvib/nvib.hpp>

namespace nvib_py {

namespace py = pybind11;
using nvib::CVecRef;
using nvib::Index;
using nvib::MatRef;
using nvib::VecRef;
namespace detail = nvib::detail;

inline py::array_t<double> to_numpy(const CVecRef& x) {
  py::array_t<double> a(x.size());
  std::memcpy(a.mutable_data(), x.data(), sizeof(double) * static_cast<size_t>(x.size()));
  return a;
}

inline std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// Checks and converts what a callback returned; errors name the callback.
inline py::array_t<double> checked_array(const py::handle& obj, const char* who, Index n, int ndim, double t) {
  if (obj.is_none()) throw py::type_error(std::string(who) + " returned None at t = " + detail::fmt(t));
  py::array arr = py::array::ensure(obj);
  if (!arr) throw py::type_error(std::string(who) + " must return an array of floats, got " +
                                 std::string(py::str(py::type::of(obj).attr("__name__"))));
  const char kind = arr.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    throw py::type_error(std::string(who) + " must return real numbers, got dtype " +
                         std::string(py::str(arr.dtype())) + " at t = " + detail::fmt(t));
  const bool scalar_ok = ndim == 1 && n == 1 && arr.ndim() == 0;
  bool shape_ok = arr.ndim() == ndim;
  for (int i = 0; shape_ok && i < ndim; ++i) shape_ok = arr.shape(i) == n;
  if (!shape_ok && !scalar_ok)
    throw py::value_error(std::string(who) + " returned shape " + shape_of(arr) + ", expected " +
                          (ndim == 1 ? "(" + std::to_string(n) + ",)"
                                     : "(" + std::to_string(n) + ", " + std::to_string(n) + ")") +
                          " at t = " + detail::fmt(t));
  return py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(arr);
}

// A scalar law given as a Python callable on a measure d = g . u:
// law(d, d', t) -> f, acting as g^T f; tangent(d, d', t) -> (df/dd, df/dd') optional. A law with
// memory (state: its initial internal variables) is called law(d, d', t, state) -> (f, trial state)
// and tangent(d, d', t, state) -> (df/dd, df/dd'), state the committed one (a tuple of floats): a
// pure trial, committed once per accepted step like the built-in laws.
struct PyLaw {
  std::vector<Index> index;
  std::vector<double> coef;
  py::object law, tangent = py::none();
  std::string where;  // "effects[3]", for error messages
  bool velocity = true, time = true;
  std::vector<double> initial;  // the initial state (empty: no memory)
  size_t offset = 0;            // where its state sits in the state buffers

  double measure(const CVecRef& x) const {
    double d = 0.0;
    for (size_t k = 0; k < index.size(); ++k) d += coef[k] * x[index[k]];
    return d;
  }
};

// Many effects of one Python law at once (a vectorised law): d_k = u[i_k] - u[j_k] (j_k < 0: the ground),
// law(d, d', t) -> f with arrays of all the effects (one Python call per evaluation, not one per effect),
// acting as +f_k on DOF i_k and -f_k on j_k; tangent(d, d', t) -> (df/dd, df/dd') arrays (None for a zero
// df/dd'). With memory (width internal variables per effect): law(d, d', t, state) -> (f, trial state) and
// tangent(d, d', t, state), state the committed one as an array (effects, width).
struct PyArrayLaw {
  std::vector<Index> i, j;
  py::object law, tangent = py::none();
  std::string where;
  bool velocity = true, time = true;
  std::vector<double> initial;  // the initial states, effect by effect (empty: no memory)
  Index width = 0;              // internal variables per effect
  size_t offset = 0;            // where its states sit in the state buffers

  Index size() const { return static_cast<Index>(i.size()); }
  py::array_t<double> measure(const CVecRef& x) const {
    py::array_t<double> d(size());
    double* p = d.mutable_data();
    for (Index k = 0; k < size(); ++k) p[k] = x[i[k]] - (j[k] >= 0 ? x[j[k]] : 0.0);
    return d;
  }
  // d' of every effect: the measure of v, or zeros for a law declared without velocity.
  py::array_t<double> rates(const CVecRef& v) const {
    if (velocity) return measure(v);
    py::array_t<double> dd(size());
    std::fill_n(dd.mutable_data(), size(), 0.0);
    return dd;
  }
};

// A real number returned by a callback (a Python number or a 0-d/1-element array).
inline double checked_scalar(const py::handle& obj, const std::string& who, double t) {
  auto arr = checked_array(obj, who.c_str(), 1, 1, t);
  return arr.data()[0];
}

// All Python callables of a model: a vector force(u, v, t) and scalar laws on measures.
// The divergence bound on |u_i| of the run in progress on this thread (NaN: none known, as in
// Stepper.step); Python callbacks run on the thread of their run.
inline thread_local double run_bound = std::numeric_limits<double>::quiet_NaN();
constexpr double kOverflowScale = 1e30;

struct RunBound {
  double saved;
  explicit RunBound(double bound) : saved(run_bound) { run_bound = bound; }
  ~RunBound() { run_bound = saved; }
  RunBound(const RunBound&) = delete;
  RunBound& operator=(const RunBound&) = delete;
};

struct PyForce {
  py::object force = py::none();    // force(u, v, t) -> (n,) or None
  py::object tangent_ = py::none();  // tangent(u, v, t) -> (K, C)
  std::vector<PyLaw> laws;
  std::vector<PyArrayLaw> arrays;
  Index n = 0;
  bool velocity = true, time = true;  // of `force`
  std::vector<double> committed, trial;  // the states of the laws with memory (theirs, one after the other)

  bool empty() const { return force.is_none() && laws.empty() && arrays.empty(); }
  // After the laws are set: their places in the state buffers.
  void place_states() {
    committed.clear();
    for (PyLaw& l : laws) {
      l.offset = committed.size();
      committed.insert(committed.end(), l.initial.begin(), l.initial.end());
    }
    for (PyArrayLaw& a : arrays) {
      a.offset = committed.size();
      committed.insert(committed.end(), a.initial.begin(), a.initial.end());
    }
    trial = committed;
  }

  void operator()(const CVecRef& u, const CVecRef& v, double t, VecRef out) {
    if (force.is_none()) {
      out.setZero();
    } else {
      py::object r = force(to_numpy(u), to_numpy(v), t);
      auto arr = checked_array(r, "force", n, 1, t);
      std::memcpy(out.data(), arr.data(), sizeof(double) * static_cast<size_t>(n));
      if (!out.allFinite()) nonfinite(u, v, t, "force");
    }
    for (const PyLaw& l : laws) {
      const double d = l.measure(u), dd = l.velocity ? l.measure(v) : 0.0;
      const double f = l.initial.empty() ? checked_scalar(l.law(d, dd, t), l.where + ".law", t)
                                         : respond(l, d, dd, t, trial.data() + l.offset);
      if (!std::isfinite(f)) nonfinite(u, v, t, l.where + ".law");
      for (size_t k = 0; k < l.index.size(); ++k) out[l.index[k]] += l.coef[k] * f;
    }
    for (const PyArrayLaw& a : arrays) {
      auto f = respond(a, u, v, t, trial.data() + a.offset);
      const double* fp = f.data();
      for (Index k = 0; k < a.size(); ++k) {
        if (!std::isfinite(fp[k])) nonfinite(u, v, t, a.where + ".law (effect " + std::to_string(k) + ")");
        out[a.i[k]] += fp[k];
        if (a.j[k] >= 0) out[a.j[k]] -= fp[k];
      }
    }
  }
  // A vectorised law at (u, v, t) from its committed states: its forces; with memory, its trial states
  // written to `next`.
  py::array_t<double> respond(const PyArrayLaw& a, const CVecRef& u, const CVecRef& v, double t, double* next) const {
    const std::string who = a.where + ".law";
    py::array_t<double> d = a.measure(u), dd = a.rates(v);
    if (a.width == 0) return checked_array(a.law(d, dd, t), who.c_str(), a.size(), 1, t);
    py::object r = a.law(d, dd, t, state_array(a));
    if (!py::isinstance<py::tuple>(r) && !py::isinstance<py::list>(r))
      throw py::type_error(who + " of a law with state must return (forces, states), got " +
                           std::string(py::str(py::type::of(r).attr("__name__"))));
    py::sequence fs = r;
    if (py::len(fs) != 2) throw py::type_error(who + " of a law with state must return (forces, states), a pair");
    auto f = checked_array(fs[0], (who + " (forces)").c_str(), a.size(), 1, t);
    py::array s = py::array::ensure(fs[1]);
    if (!s || s.ndim() != 2 || s.shape(0) != a.size() || s.shape(1) != a.width)
      throw py::value_error(who + " returned states of shape " + (s ? shape_of(s) : std::string("?")) +
                            ", expected (" + std::to_string(a.size()) + ", " + std::to_string(a.width) + ") at t = " +
                            detail::fmt(t));
    auto sd = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(s);
    const double* sp = sd.data();
    for (Index k = 0; k < a.size() * a.width; ++k) {
      if (!std::isfinite(sp[k]))
        throw py::value_error(who + " returned a non-finite state at t = " + detail::fmt(t));
      next[k] = sp[k];
    }
    return f;
  }
  py::array_t<double> state_array(const PyArrayLaw& a) const {
    py::array_t<double> s({a.size(), a.width});
    std::copy_n(committed.data() + a.offset, static_cast<size_t>(a.size() * a.width), s.mutable_data());
    return s;
  }
  // A law with memory at (d, d', t) from its committed state: its force, its trial state written to `next`.
  double respond(const PyLaw& l, double d, double dd, double t, double* next) const {
    py::object r = l.law(d, dd, t, state_tuple(l));
    const std::string who = l.where + ".law";
    if (!py::isinstance<py::tuple>(r) && !py::isinstance<py::list>(r))
      throw py::type_error(who + " of a law with state must return (force, state), got " +
                           std::string(py::str(py::type::of(r).attr("__name__"))));
    py::sequence fs = r;
    if (py::len(fs) != 2) throw py::type_error(who + " of a law with state must return (force, state), a pair");
    const double f = checked_scalar(fs[0], who + " (force)", t);
    py::sequence st = fs[1].cast<py::sequence>();
    if (py::len(st) != l.initial.size())
      throw py::value_error(who + " returned a state of " + std::to_string(py::len(st)) + " values, expected " +
                            std::to_string(l.initial.size()) + " at t = " + detail::fmt(t));
    for (size_t k = 0; k < l.initial.size(); ++k) {
      next[k] = checked_scalar(st[k], who + " (state[" + std::to_string(k) + "])", t);
      if (!std::isfinite(next[k]))
        throw py::value_error(who + " returned a non-finite state[" + std::to_string(k) + "] at t = " + detail::fmt(t));
    }
    return f;
  }
  py::tuple state_tuple(const PyLaw& l) const {
    py::tuple s(l.initial.size());
    for (size_t k = 0; k < l.initial.size(); ++k) s[k] = py::float_(committed[l.offset + k]);
    return s;
  }

  // ---- memory ----
  bool has_state() const { return !committed.empty(); }
  Index state_size() const { return static_cast<Index>(committed.size()); }
  void get_state(double* out) const { std::copy(committed.begin(), committed.end(), out); }
  void set_state(const double* x) { std::copy(x, x + committed.size(), committed.begin()); }
  void reset_state() {
    for (const PyLaw& l : laws) std::copy(l.initial.begin(), l.initial.end(), committed.begin() + static_cast<long>(l.offset));
    for (const PyArrayLaw& a : arrays)
      std::copy(a.initial.begin(), a.initial.end(), committed.begin() + static_cast<long>(a.offset));
  }
  void commit_last_trial(const double*, const double*, double) { committed.swap(trial); }
  void commit_at(const double* u, const double* v, double t) {
    for (const PyLaw& l : laws) {
      if (l.initial.empty()) continue;
      double d = 0.0, dd = 0.0;
      for (size_t k = 0; k < l.index.size(); ++k) {
        d += l.coef[k] * u[l.index[k]];
        if (l.velocity) dd += l.coef[k] * v[l.index[k]];
      }
      respond(l, d, dd, t, trial.data() + l.offset);
    }
    for (const PyArrayLaw& a : arrays) {
      if (a.width == 0) continue;
      Eigen::Map<const Eigen::VectorXd> um(u, n), vm(v, n);
      respond(a, um, vm, t, trial.data() + a.offset);
    }
    for (const PyLaw& l : laws)
      std::copy(trial.begin() + static_cast<long>(l.offset), trial.begin() + static_cast<long>(l.offset + l.initial.size()),
                committed.begin() + static_cast<long>(l.offset));
    for (const PyArrayLaw& a : arrays)
      std::copy(trial.begin() + static_cast<long>(a.offset),
                trial.begin() + static_cast<long>(a.offset + a.initial.size()), committed.begin() + static_cast<long>(a.offset));
  }
  // Overflow of a diverging run is reported as divergence by the solver: a
  // state beyond the run's divergence bound (RunBound) or of size 1e30 or more
  // is left to its divergence test, which stops the run with its partial
  // history. A non-finite value at a moderate state is a bug in the callback.
  static void nonfinite(const CVecRef& u, const CVecRef& v, double t, const std::string& who) {
    const double bound = std::isnan(run_bound) ? kOverflowScale : std::min(run_bound, kOverflowScale);
    const double umax = u.cwiseAbs().maxCoeff(), vmax = v.cwiseAbs().maxCoeff();
    if (u.allFinite() && v.allFinite() && umax <= bound && vmax < kOverflowScale)
      throw py::value_error(who + " returned a non-finite value at t = " + detail::fmt(t) +
                            " for a finite state (max |u|, |v| = " + detail::fmt(std::max(umax, vmax)) + ")");
  }
  bool has_tangent() const {
    if (!force.is_none() && tangent_.is_none()) return false;
    for (const PyLaw& l : laws)
      if (l.tangent.is_none()) return false;
    for (const PyArrayLaw& a : arrays)
      if (a.tangent.is_none()) return false;
    return true;
  }
  void tangent(const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) {
    K.setZero();
    C.setZero();
    if (!force.is_none()) force_tangent(u, v, t, K, C);
    for (const PyLaw& l : laws) {
      const double d = l.measure(u), dd = l.velocity ? l.measure(v) : 0.0;
      py::object r = l.initial.empty() ? l.tangent(d, dd, t) : l.tangent(d, dd, t, state_tuple(l));
      py::tuple kc = as_pair(r, l.where + ".tangent");
      const double kd = checked_scalar(kc[0], l.where + ".tangent (df/dd)", t);
      const double cd = kc[1].is_none() ? 0.0 : checked_scalar(kc[1], l.where + ".tangent (df/dd')", t);
      if (!std::isfinite(kd) || !std::isfinite(cd))
        throw py::value_error(l.where + ".tangent returned non-finite values at t = " + detail::fmt(t));
      for (size_t i = 0; i < l.index.size(); ++i)
        for (size_t j = 0; j < l.index.size(); ++j) {
          K(l.index[i], l.index[j]) += kd * l.coef[i] * l.coef[j];
          C(l.index[i], l.index[j]) += cd * l.coef[i] * l.coef[j];
        }
    }
    for (const PyArrayLaw& a : arrays) array_tangent(a, u, v, t, K, C);
  }
  // A vectorised law's slopes, each effect's as kd (g g^T) with g = e_i - e_j.
  void array_tangent(const PyArrayLaw& a, const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) const {
    const std::string who = a.where + ".tangent";
    py::array_t<double> d = a.measure(u), dd = a.rates(v);
    py::tuple kc = as_pair(a.width == 0 ? a.tangent(d, dd, t) : a.tangent(d, dd, t, state_array(a)), who);
    auto kd = checked_array(kc[0], (who + " (df/dd)").c_str(), a.size(), 1, t);
    py::array_t<double> cd;
    if (!kc[1].is_none()) cd = checked_array(kc[1], (who + " (df/dd')").c_str(), a.size(), 1, t);
    for (Index k = 0; k < a.size(); ++k) {
      const double x = kd.data()[k], y = kc[1].is_none() ? 0.0 : cd.data()[k];
      if (!std::isfinite(x) || !std::isfinite(y))
        throw py::value_error(who + " returned non-finite values at t = " + detail::fmt(t));
      const Index i = a.i[k], j = a.j[k];
      K(i, i) += x;
      C(i, i) += y;
      if (j >= 0) {
        K(j, j) += x;
        K(i, j) -= x;
        K(j, i) -= x;
        C(j, j) += y;
        C(i, j) -= y;
        C(j, i) -= y;
      }
    }
  }
  static py::tuple as_pair(const py::object& r, const std::string& who) {
    if (!py::isinstance<py::tuple>(r) && !py::isinstance<py::list>(r))
      throw py::type_error(who + " must return a tuple (K, C), got " +
                           std::string(py::str(py::type::of(r).attr("__name__"))));
    py::tuple kc(r);
    if (kc.size() != 2) throw py::type_error(who + " must return a tuple (K, C) of length 2");
    return kc;
  }
  void force_tangent(const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) {
    py::tuple kc = as_pair(tangent_(to_numpy(u), to_numpy(v), t), "tangent");
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    auto Ka = checked_array(kc[0], "tangent (K)", n, 2, t);
    K = Eigen::Map<const RowMajor>(Ka.data(), n, n);
    if (!kc[1].is_none()) {
      auto Ca = checked_array(kc[1], "tangent (C)", n, 2, t);
      C = Eigen::Map<const RowMajor>(Ca.data(), n, n);
    }
    if (!K.allFinite() || !C.allFinite())
      throw py::value_error("tangent returned non-finite values at t = " + detail::fmt(t));
  }
  bool uses_velocity() const {
    bool any = !force.is_none() && velocity;
    for (const PyLaw& l : laws) any = any || l.velocity;
    for (const PyArrayLaw& a : arrays) any = any || a.velocity;
    return any;
  }
  bool uses_time() const {
    bool any = !force.is_none() && time;
    for (const PyLaw& l : laws) any = any || l.time;
    for (const PyArrayLaw& a : arrays) any = any || a.time;
    return any;
  }
  bool is_linear() const { return empty(); }  // (a model with memory is never linear: Model checks)
  // Energy: the energy of a user callable is unknown.
  bool accounts_energy() const { return empty(); }
  double potential(const CVecRef&, double) const { return 0.0; }
  double input_power(const CVecRef&, const CVecRef&, double) const { return 0.0; }
  double dissipated_power(const CVecRef&) const { return 0.0; }
};

}  // namespace nvib_py
