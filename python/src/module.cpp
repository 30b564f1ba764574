// nvib._core: the pybind11 binding. Type erasure happens here only: a
// stepper is a template on (scheme, model); Python sees one Stepper type.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <cstring>
#include <memory>

#include <nvib/nvib.hpp>

namespace py = pybind11;
using namespace nvib;

namespace {

// ---- a force given as Python callables ------------------------------------------
py::array_t<double> to_numpy(const CVecRef& x) {
  py::array_t<double> a(x.size());
  std::memcpy(a.mutable_data(), x.data(), sizeof(double) * static_cast<size_t>(x.size()));
  return a;
}

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

// Checks and converts what a callback returned; errors name the callback.
py::array_t<double> checked_array(const py::handle& obj, const char* who, Index n, int ndim, double t) {
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
// law(d, d', t) -> f, acting as g^T f; tangent(d, d', t) -> (df/dd, df/dd') optional.
struct PyLaw {
  std::vector<Index> index;
  std::vector<double> coef;
  py::object law, tangent = py::none();
  std::string where;  // "effects[3]", for error messages
  bool velocity = true, time = true;

  double measure(const CVecRef& x) const {
    double d = 0.0;
    for (size_t k = 0; k < index.size(); ++k) d += coef[k] * x[index[k]];
    return d;
  }
};

// A real number returned by a callback (a Python number or a 0-d/1-element array).
double checked_scalar(const py::handle& obj, const std::string& who, double t) {
  auto arr = checked_array(obj, who.c_str(), 1, 1, t);
  return arr.data()[0];
}

// All Python callables of a model: a vector force(u, v, t) and scalar laws on measures.
struct PyForce {
  py::object force = py::none();    // force(u, v, t) -> (n,) or None
  py::object tangent_ = py::none();  // tangent(u, v, t) -> (K, C)
  std::vector<PyLaw> laws;
  Index n = 0;
  bool velocity = true, time = true;  // of `force`

  bool empty() const { return force.is_none() && laws.empty(); }

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
      const double f = checked_scalar(l.law(d, dd, t), l.where + ".law", t);
      if (!std::isfinite(f)) nonfinite(u, v, t, l.where + ".law");
      for (size_t k = 0; k < l.index.size(); ++k) out[l.index[k]] += l.coef[k] * f;
    }
  }
  // Overflow of a diverging run is reported as divergence by the solver; a
  // non-finite value at a moderate state is a bug in the callback.
  static void nonfinite(const CVecRef& u, const CVecRef& v, double t, const std::string& who) {
    const double scale = std::max(u.cwiseAbs().maxCoeff(), v.cwiseAbs().maxCoeff());
    if (u.allFinite() && v.allFinite() && scale < 1e30)
      throw py::value_error(who + " returned a non-finite value at t = " + detail::fmt(t) +
                            " for a finite state (max |u|, |v| = " + detail::fmt(scale) + ")");
  }
  bool has_tangent() const {
    if (!force.is_none() && tangent_.is_none()) return false;
    for (const PyLaw& l : laws)
      if (l.tangent.is_none()) return false;
    return true;
  }
  void tangent(const CVecRef& u, const CVecRef& v, double t, MatRef K, MatRef C) {
    K.setZero();
    C.setZero();
    if (!force.is_none()) force_tangent(u, v, t, K, C);
    for (const PyLaw& l : laws) {
      const double d = l.measure(u), dd = l.velocity ? l.measure(v) : 0.0;
      py::object r = l.tangent(d, dd, t);
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
    return any;
  }
  bool uses_time() const {
    bool any = !force.is_none() && time;
    for (const PyLaw& l : laws) any = any || l.time;
    return any;
  }
  bool is_linear() const { return empty(); }
  // Energy: the energy of a user callable is unknown.
  bool accounts_energy() const { return empty(); }
  double potential(const CVecRef&, double) const { return 0.0; }
  double input_power(const CVecRef&, const CVecRef&, double) const { return 0.0; }
  double dissipated_power(const CVecRef&) const { return 0.0; }
};

using EffectModel = Model<effects::EffectSet>;
using HybridModel = Model<effects::EffectsPlus<PyForce>>;

const effects::EffectSet& effect_set(const EffectModel& md) { return md.nonlinear_force(); }
const effects::EffectSet& effect_set(const HybridModel& md) { return md.nonlinear_force().effects(); }

Mass make_mass(const py::array_t<double, py::array::c_style | py::array::forcecast>& m) {
  if (m.ndim() == 1) return Mass::diagonal(Eigen::Map<const Vector>(m.data(), m.shape(0)));
  if (m.ndim() == 2) {
    Matrix M = Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
        m.data(), m.shape(0), m.shape(1));
    if (M.rows() == M.cols()) {
      Matrix off = M;
      off.diagonal().setZero();
      if (off.allFinite() && off.cwiseAbs().maxCoeff() == 0.0) return Mass::diagonal(M.diagonal());
    }
    return Mass::dense(M);
  }
  throw py::value_error("mass: expected a 1-D array (diagonal) or a 2-D matrix");
}

Iteration parse_iteration(const std::string& s) {
  if (s == "newton") return Iteration::newton;
  if (s == "modified") return Iteration::modified;
  if (s == "none") return Iteration::none;
  throw py::value_error("iteration: expected 'newton', 'modified' or 'none', got '" + s + "'");
}
Jacobian parse_jacobian(const std::string& s) {
  if (s == "analytic") return Jacobian::analytic;
  if (s == "finite_difference") return Jacobian::finite_difference;
  throw py::value_error("jacobian: expected 'analytic' or 'finite_difference', got '" + s + "'");
}
NewtonOptions newton_options(int max_iter, double rtol, double atol, const std::string& jac) {
  NewtonOptions o;
  o.max_iter = max_iter;
  o.rtol = rtol;
  o.atol = atol;
  o.jacobian = parse_jacobian(jac);
  o.validate();
  return o;
}
const char* jacobian_name(Jacobian j) { return j == Jacobian::analytic ? "analytic" : "finite_difference"; }

py::dict failure_dict(const Failure& f) {
  py::dict d;
  d["status"] = to_string(f.status);
  d["step"] = f.step;
  d["t"] = f.t;
  d["dof"] = f.dof;
  d["residuals"] = f.residuals;
  d["message"] = f.message;
  return d;
}

// ---- type-erased stepper ----------------------------------------------------------
struct AnyStepper {
  virtual ~AnyStepper() = default;
  virtual void initialize(double t0, const Vector& u0, const Vector& v0) = 0;
  virtual Status step() = 0;
  virtual double time() const = 0;
  virtual std::int64_t step_index() const = 0;
  virtual double dt() const = 0;
  virtual Index size() const = 0;
  virtual const Vector& u() const = 0;
  virtual const Vector& v() const = 0;
  virtual const Vector& a() const = 0;
  virtual Stats stats() const = 0;
  virtual Failure failure() const = 0;
  virtual std::string scheme_name() const = 0;
  virtual std::vector<double> last_residuals() const { return {}; }
  virtual double accepted_residual() const { return std::numeric_limits<double>::quiet_NaN(); }
  virtual Result integrate(double t_end, const SolveOptions& opt, py::object observer) = 0;
  virtual Vector state() const = 0;
  virtual void set_state(double t, const Vector& x) = 0;
};

// Called every few thousand steps: lets Ctrl-C through and reports progress.
// Taking the GIL back costs up to the interpreter's switch interval when
// another Python thread is busy, so after the first call it is done at most
// every 0.1 s.
struct PyObserver {
  py::object callback;
  bool gil_released;
  bool first = true;
  std::chrono::steady_clock::time_point last{};

  void operator()(std::int64_t i, std::int64_t n) {
    const auto now = std::chrono::steady_clock::now();
    if (!first && now - last < std::chrono::milliseconds(100)) return;
    first = false;
    last = now;
    auto body = [&]() {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      if (!callback.is_none()) callback(i, n);
    };
    if (gil_released) {
      py::gil_scoped_acquire gil;
      body();
    } else {
      body();
    }
  }
};

template <class S, class = void>
struct has_residuals : std::false_type {};
template <class S>
struct has_residuals<S, std::void_t<decltype(std::declval<const S&>().last_residuals())>> : std::true_type {};

template <class S>
struct StepperImpl final : AnyStepper {
  template <class Scheme, class M>
  StepperImpl(const Scheme& scheme, const M& model, double dt) : s(scheme, model, dt), name(scheme.name()) {}
  // A model with Python callables keeps the GIL; a C++-only model releases it.
  static constexpr bool releases_gil = !std::is_same_v<typename std::decay_t<decltype(std::declval<S&>().model())>, HybridModel>;

  void initialize(double t0, const Vector& u0, const Vector& v0) override { s.initialize(t0, u0, v0); }
  Status step() override { return s.step(); }
  double time() const override { return s.time(); }
  std::int64_t step_index() const override { return s.step_index(); }
  double dt() const override { return s.dt(); }
  Index size() const override { return s.size(); }
  const Vector& u() const override { return s.u(); }
  const Vector& v() const override { return s.v(); }
  const Vector& a() const override { return s.a(); }
  Stats stats() const override { return s.stats(); }
  Failure failure() const override { return s.failure(); }
  std::string scheme_name() const override { return name; }
  std::vector<double> last_residuals() const override {
    if constexpr (has_residuals<S>::value)
      return s.last_residuals();
    else
      return {};
  }
  double accepted_residual() const override {
    if constexpr (has_accepted_residual<S>::value)
      return s.accepted_residual();
    else
      return std::numeric_limits<double>::quiet_NaN();
  }
  Vector state() const override { return s.state(); }
  void set_state(double t, const Vector& x) override { s.set_state(t, x); }
  Result integrate(double t_end, const SolveOptions& opt, py::object observer) override {
    PyObserver obs{std::move(observer), releases_gil};
    if constexpr (releases_gil) {
      py::gil_scoped_release nogil;
      return nvib::integrate(s, t_end, opt, obs);
    } else {
      return nvib::integrate(s, t_end, opt, obs);
    }
  }
  S s;
  std::string name;
};

template <class M, class Scheme>
void def_make_stepper(py::module_& m) {
  m.def(
      "make_stepper",
      [](const M& model, const Scheme& scheme, double dt) -> std::unique_ptr<AnyStepper> {
        using S = typename stepper_for<Scheme, M>::type;
        return std::make_unique<StepperImpl<S>>(scheme, model, dt);
      },
      py::arg("model"), py::arg("scheme"), py::arg("dt"));
}

template <class M>
void def_all_schemes(py::module_& m) {
  def_make_stepper<M, CentralDifference>(m);
  def_make_stepper<M, Zhai>(m);
  def_make_stepper<M, CEMDTS>(m);
  def_make_stepper<M, Newmark>(m);
  def_make_stepper<M, GeneralizedAlpha>(m);
  def_make_stepper<M, PreciseIntegration>(m);
}

py::dict result_dict(Result&& r) {
  py::dict d;
  d["t"] = py::cast(std::move(r.t));
  d["u"] = py::cast(std::move(r.u));
  d["v"] = py::cast(std::move(r.v));
  d["a"] = py::cast(std::move(r.a));
  d["dofs"] = r.dofs;
  d["stats"] = r.stats;
  d["status"] = to_string(r.status);
  d["failure"] = failure_dict(r.failure);
  d["num_steps_requested"] = r.num_steps_requested;
  d["max_residual"] = r.max_residual;
  if (r.energy.size() > 0) d["energy"] = py::cast(std::move(r.energy));
  return d;
}

effects::Law parse_law(const std::string& s) {
  for (effects::Law l : effects::all_laws())
    if (s == effects::to_string(l)) return l;
  throw py::value_error("type: unknown effect type '" + s + "'");
}

effects::Signal make_signal(const std::string& kind, double amplitude, double omega, double phase,
                            std::vector<double> t, std::vector<double> values) {
  if (kind == "none") return {};
  if (kind == "sine") return effects::Signal::sine(amplitude, omega, phase);
  if (kind == "table") return effects::Signal::table(std::move(t), std::move(values));
  throw py::value_error("signal.kind: expected 'sine' or 'table', got '" + kind + "'");
}

template <class M>
py::tuple tangent_of(M& md, const Vector& u, const Vector& v, double t) {
  Stats st;
  Matrix K(md.size(), md.size()), C(md.size(), md.size());
  md.tangent(u, v, t, K, C, st);
  return py::make_tuple(K, C);
}

template <class M>
Vector force_of(M& md, const Vector& u, const Vector& v, double t) {
  Stats st;
  Vector out(md.size());
  md.force(u, v, t, out, st);
  return out;
}

// What both model classes show to Python.
template <class M>
py::class_<M> def_model(py::module_& m, const char* name, const char* doc) {
  py::class_<M> c(m, name, doc);
  c.def_property_readonly("size", &M::size)
      .def_property_readonly("uses_velocity", &M::uses_velocity)
      .def_property_readonly("uses_time", &M::uses_time)
      .def_property_readonly("is_linear", &M::is_linear)
      .def_property_readonly("accounts_energy", &M::accounts_energy)
      .def_property_readonly("num_evaluated_effects", [](const M& md) { return effect_set(md).evaluated().size(); })
      .def_property_readonly("mass_matrix", [](const M& md) { return md.mass().matrix(); })
      .def_property_readonly("K", [](const M& md) { return md.has_K() ? md.K() : Matrix::Zero(md.size(), md.size()).eval(); })
      .def_property_readonly("C", [](const M& md) { return md.has_C() ? md.C() : Matrix::Zero(md.size(), md.size()).eval(); })
      .def_property_readonly("effects", [](const M& md) { return effect_set(md).effects(); })
      .def("potential", [](M& md, const Vector& u, double t) { return md.potential(u, t); }, py::arg("u"),
           py::arg("t") = 0.0)
      .def("kinetic", [](M& md, const Vector& v) { return md.kinetic(v); })
      .def("force", &force_of<M>, py::arg("u"), py::arg("v"), py::arg("t"))
      .def("tangent", &tangent_of<M>, py::arg("u"), py::arg("v"), py::arg("t"));
  return c;
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "nvib C++ core (header-only library bound with pybind11)";

  py::class_<Stats>(m, "Stats")
      .def(py::init<>())
      .def_readonly("num_steps", &Stats::num_steps)
      .def_readonly("num_force_evals", &Stats::num_force_evals)
      .def_readonly("num_fd_force_evals", &Stats::num_fd_force_evals)
      .def_readonly("num_tangent_evals", &Stats::num_tangent_evals)
      .def_readonly("num_newton_iters", &Stats::num_newton_iters)
      .def_readonly("num_factorizations", &Stats::num_factorizations)
      .def_readonly("num_linear_solves", &Stats::num_linear_solves)
      .def_readonly("num_expm", &Stats::num_expm)
      .def_readonly("wall_time", &Stats::wall_time)
      .def("as_dict",
           [](const Stats& s) {
             py::dict d;
             d["num_steps"] = s.num_steps;
             d["num_force_evals"] = s.num_force_evals;
             d["num_fd_force_evals"] = s.num_fd_force_evals;
             d["num_tangent_evals"] = s.num_tangent_evals;
             d["num_newton_iters"] = s.num_newton_iters;
             d["num_factorizations"] = s.num_factorizations;
             d["num_linear_solves"] = s.num_linear_solves;
             d["num_expm"] = s.num_expm;
             d["wall_time"] = s.wall_time;
             return d;
           })
      .def("__repr__", [](const Stats& s) {
        return "Stats(num_steps=" + std::to_string(s.num_steps) + ", num_force_evals=" +
               std::to_string(s.num_force_evals) + ", num_fd_force_evals=" + std::to_string(s.num_fd_force_evals) +
               ", num_tangent_evals=" + std::to_string(s.num_tangent_evals) + ", num_newton_iters=" +
               std::to_string(s.num_newton_iters) + ", num_factorizations=" + std::to_string(s.num_factorizations) +
               ", num_linear_solves=" + std::to_string(s.num_linear_solves) + ", num_expm=" +
               std::to_string(s.num_expm) + ", wall_time=" + detail::fmt(s.wall_time) + ")";
      });

  // ---- schemes ----------------------------------------------------------------------
  py::class_<CentralDifference>(m, "CentralDifference",
                                "Leapfrog central difference method (LCDM). velocity='synchronized' or 'half_step'.")
      .def(py::init([](const std::string& velocity) {
             if (velocity == "synchronized") return CentralDifference(CentralDifference::Velocity::synchronized);
             if (velocity == "half_step") return CentralDifference(CentralDifference::Velocity::half_step);
             throw py::value_error("velocity: expected 'synchronized' or 'half_step', got '" + velocity + "'");
           }),
           py::kw_only(), py::arg("velocity") = "synchronized")
      .def_property_readonly("velocity",
                             [](const CentralDifference& s) {
                               return s.velocity == CentralDifference::Velocity::synchronized ? "synchronized"
                                                                                                : "half_step";
                             })
      .def_property_readonly("name", &CentralDifference::name)
      .def_property_readonly("is_explicit", [](const CentralDifference&) { return true; })
      .def_property_readonly("order", [](const CentralDifference&) { return 2; })
      .def("__repr__", &CentralDifference::name);

  py::class_<Zhai>(m, "Zhai", "Zhai's explicit two-step method (Zhai 1996).")
      .def(py::init<double, double>(), py::arg("psi") = 0.5, py::arg("phi") = 0.5)
      .def_readonly("psi", &Zhai::psi)
      .def_readonly("phi", &Zhai::phi)
      .def_property_readonly("name", &Zhai::name)
      .def_property_readonly("is_explicit", [](const Zhai&) { return true; })
      .def_property_readonly("order", [](const Zhai&) { return 2; })
      .def("__repr__", &Zhai::name);

  py::class_<CEMDTS>(m, "CEMDTS",
                     "Corrected explicit method of double time steps, as reconstructed from the properties stated in "
                     "Yang et al. 2017.")
      .def(py::init<double>(), py::arg("eta") = 0.45)
      .def_readonly("eta", &CEMDTS::eta)
      .def_property_readonly("name", &CEMDTS::name)
      .def_property_readonly("is_explicit", [](const CEMDTS&) { return true; })
      .def_property_readonly("order", [](const CEMDTS&) { return 2; })
      .def("__repr__", &CEMDTS::name);

  py::class_<Newmark>(m, "Newmark", "Newmark's method with Newton ('newton'), modified Newton ('modified') or the "
                                    "incremental format ('none': one linearised solve per step, accepted without an "
                                    "equilibrium check; the residual it leaves is reported in Result.max_residual).")
      .def(py::init([](double beta, double gamma, const std::string& it, int max_iter, double rtol, double atol,
                       const std::string& jac) {
             return Newmark(beta, gamma, parse_iteration(it), newton_options(max_iter, rtol, atol, jac));
           }),
           py::arg("beta") = 0.25, py::arg("gamma") = 0.5, py::kw_only(), py::arg("iteration") = "newton",
           py::arg("max_iter") = 20, py::arg("rtol") = 1e-10, py::arg("atol") = 1e-12,
           py::arg("jacobian") = "analytic")
      .def_readonly("beta", &Newmark::beta)
      .def_readonly("gamma", &Newmark::gamma)
      .def_property_readonly("iteration", [](const Newmark& s) { return to_string(s.iteration); })
      .def_property_readonly("max_iter", [](const Newmark& s) { return s.newton.max_iter; })
      .def_property_readonly("rtol", [](const Newmark& s) { return s.newton.rtol; })
      .def_property_readonly("atol", [](const Newmark& s) { return s.newton.atol; })
      .def_property_readonly("jacobian", [](const Newmark& s) { return jacobian_name(s.newton.jacobian); })
      .def_property_readonly("name", &Newmark::name)
      .def_property_readonly("is_explicit", [](const Newmark&) { return false; })
      .def_property_readonly("order", &Newmark::order)
      .def("__repr__", &Newmark::name);

  auto ga_factory = [](double am, double af, double b, double g, const std::string& it, int max_iter, double rtol,
                       double atol, const std::string& jac) {
    return GeneralizedAlpha(am, af, b, g, parse_iteration(it), newton_options(max_iter, rtol, atol, jac));
  };
  py::class_<GeneralizedAlpha>(m, "GeneralizedAlpha",
                               "Generalized-alpha (Chung & Hulbert 1993, alpha on the old level). Defaults are the "
                               "paper's alpha_m = alpha_f = 1/2, beta = 1/4, gamma = 1/2 (= from_rho_inf(1)). "
                               "iteration: 'newton', 'modified' or 'none' (the incremental format: one linearised "
                               "solve per step, accepted without an equilibrium check; the residual it leaves is "
                               "reported in Result.max_residual).")
      .def(py::init(ga_factory), py::arg("alpha_m") = 0.5, py::arg("alpha_f") = 0.5, py::arg("beta") = 0.25,
           py::arg("gamma") = 0.5, py::kw_only(), py::arg("iteration") = "newton", py::arg("max_iter") = 20,
           py::arg("rtol") = 1e-10, py::arg("atol") = 1e-12, py::arg("jacobian") = "analytic")
      .def_static(
          "from_rho_inf",
          [](double rho, const std::string& it, int max_iter, double rtol, double atol, const std::string& jac) {
            return GeneralizedAlpha::from_rho_inf(rho, parse_iteration(it), newton_options(max_iter, rtol, atol, jac));
          },
          py::arg("rho_inf"), py::kw_only(), py::arg("iteration") = "newton", py::arg("max_iter") = 20,
          py::arg("rtol") = 1e-10, py::arg("atol") = 1e-12, py::arg("jacobian") = "analytic")
      .def_static(
          "hht",
          [](double alpha, const std::string& it, int max_iter, double rtol, double atol, const std::string& jac) {
            return GeneralizedAlpha::hht(alpha, parse_iteration(it), newton_options(max_iter, rtol, atol, jac));
          },
          py::arg("alpha"), py::kw_only(), py::arg("iteration") = "newton", py::arg("max_iter") = 20,
          py::arg("rtol") = 1e-10, py::arg("atol") = 1e-12, py::arg("jacobian") = "analytic")
      .def_static(
          "wbz",
          [](double alpha, const std::string& it, int max_iter, double rtol, double atol, const std::string& jac) {
            return GeneralizedAlpha::wbz(alpha, parse_iteration(it), newton_options(max_iter, rtol, atol, jac));
          },
          py::arg("alpha"), py::kw_only(), py::arg("iteration") = "newton", py::arg("max_iter") = 20,
          py::arg("rtol") = 1e-10, py::arg("atol") = 1e-12, py::arg("jacobian") = "analytic")
      .def_readonly("alpha_m", &GeneralizedAlpha::alpha_m)
      .def_readonly("alpha_f", &GeneralizedAlpha::alpha_f)
      .def_readonly("beta", &GeneralizedAlpha::beta)
      .def_readonly("gamma", &GeneralizedAlpha::gamma)
      .def_property_readonly("iteration", [](const GeneralizedAlpha& s) { return to_string(s.iteration); })
      .def_property_readonly("max_iter", [](const GeneralizedAlpha& s) { return s.newton.max_iter; })
      .def_property_readonly("rtol", [](const GeneralizedAlpha& s) { return s.newton.rtol; })
      .def_property_readonly("atol", [](const GeneralizedAlpha& s) { return s.newton.atol; })
      .def_property_readonly("jacobian", [](const GeneralizedAlpha& s) { return jacobian_name(s.newton.jacobian); })
      .def_property_readonly("name", &GeneralizedAlpha::name)
      .def_property_readonly("is_explicit", [](const GeneralizedAlpha&) { return false; })
      .def_property_readonly("order", &GeneralizedAlpha::order)
      .def("__repr__", &GeneralizedAlpha::name);

  py::class_<PreciseIntegration>(m, "PreciseIntegration",
                                 "Precise integration method (Zhong & Williams 1994): 2^N exponential of the linear "
                                 "part, Lagrange predictor-corrector for the nonlinear remainder.")
      .def(py::init<int, int, int>(), py::kw_only(), py::arg("squarings") = 20, py::arg("order") = 2,
           py::arg("corrections") = 1)
      .def_readonly("squarings", &PreciseIntegration::squarings)
      .def_readonly("order", &PreciseIntegration::order)
      .def_readonly("corrections", &PreciseIntegration::corrections)
      .def_property_readonly("name", &PreciseIntegration::name)
      .def_property_readonly("is_explicit", [](const PreciseIntegration&) { return true; })
      .def("__repr__", &PreciseIntegration::name);

  // ---- models -----------------------------------------------------------------------
  py::class_<effects::Effect>(m, "Effect")
      .def(py::init([](const std::string& type, std::vector<Index> index, std::vector<double> coef, double p0,
                       double p1, double p2, const std::string& name, const std::string& signal,
                       double amplitude, double omega, double phase, std::vector<double> t,
                       std::vector<double> values) {
             if (index.size() != coef.size()) throw py::value_error("measure: index and coef lengths differ");
             effects::Measure g;
             for (size_t i = 0; i < index.size(); ++i) g.emplace_back(index[i], coef[i]);
             effects::Effect e = effects::detail_::make(parse_law(type), std::move(g), p0, p1, p2,
                                                        make_signal(signal, amplitude, omega, phase, std::move(t),
                                                                    std::move(values)));
             e.name = name;
             return e;
           }),
           py::arg("type"), py::arg("index"), py::arg("coef"), py::arg("p0") = 0.0, py::arg("p1") = 0.0,
           py::arg("p2") = 0.0, py::kw_only(), py::arg("name") = "", py::arg("signal") = "none",
           py::arg("amplitude") = 0.0, py::arg("omega") = 0.0, py::arg("phase") = 0.0,
           py::arg("t") = std::vector<double>{}, py::arg("values") = std::vector<double>{})
      .def_property_readonly("type", [](const effects::Effect& e) { return effects::to_string(e.law); })
      .def_readonly("name", &effects::Effect::name)
      .def_readonly("index", &effects::Effect::index)
      .def_readonly("coef", &effects::Effect::coef)
      .def_property_readonly("uses_velocity", &effects::Effect::uses_velocity)
      .def_property_readonly("uses_time", &effects::Effect::uses_time)
      .def_property_readonly("is_linear", &effects::Effect::is_linear)
      .def_property_readonly("is_load", &effects::Effect::is_load)
      .def("value", [](const effects::Effect& e, double d, double dd, double t) { return e.value(d, dd, t); },
           py::arg("d"), py::arg("dd"), py::arg("t"))
      .def("__repr__", [](const effects::Effect& e) {
        return std::string("Effect(") + effects::to_string(e.law) + (e.name.empty() ? "" : ", name='" + e.name + "'") + ")";
      });

  auto effect_model = def_model<EffectModel>(m, "EffectModel", "declared effects only: no Python in the loop");
  effect_model.def(py::init([](const py::array_t<double, py::array::c_style | py::array::forcecast>& mass,
                               std::vector<effects::Effect> list, const Matrix& K, const Matrix& C) {
                     return effects::make_effect_model(make_mass(mass), std::move(list), K, C);
                   }),
                   py::arg("mass"), py::arg("effects"), py::arg("K"), py::arg("C"));
  auto hybrid_model = def_model<HybridModel>(m, "HybridModel",
                                             "declared effects plus a Python force callable (the GIL is kept)");
  // laws: (index, coef, law, tangent or None, where, uses_velocity, uses_time) per scalar Python law.
  using LawSpec = std::tuple<std::vector<Index>, std::vector<double>, py::object, py::object, std::string, bool, bool>;
  hybrid_model.def(py::init([](const py::array_t<double, py::array::c_style | py::array::forcecast>& mass,
                               std::vector<effects::Effect> list, const Matrix& K, const Matrix& C, py::object force,
                               py::object tangent, bool uses_velocity, bool uses_time, std::vector<LawSpec> laws) {
                     Mass ms = make_mass(mass);
                     PyForce f;
                     f.force = std::move(force);
                     f.tangent_ = std::move(tangent);
                     f.n = ms.size();
                     f.velocity = uses_velocity;
                     f.time = uses_time;
                     for (auto& [index, coef, law, tan, where, vel, time] : laws) {
                       if (index.size() != coef.size() || index.empty())
                         throw py::value_error(where + ".measure: index and coef must be non-empty and equally long");
                       for (Index i : index)
                         if (i < 0 || i >= ms.size())
                           throw py::value_error(where + ".measure: DOF index " + std::to_string(i) + " is out of range");
                       f.laws.push_back(PyLaw{index, coef, law, tan, where, vel, time});
                     }
                     return effects::make_effect_model(std::move(ms), std::move(list), std::move(f), K, C);
                   }),
                   py::arg("mass"), py::arg("effects"), py::arg("K"), py::arg("C"), py::arg("force"),
                   py::arg("tangent"), py::arg("uses_velocity"), py::arg("uses_time"),
                   py::arg("laws") = std::vector<LawSpec>{});

  // ---- steppers ---------------------------------------------------------------------
  py::class_<AnyStepper>(m, "Stepper")
      .def("initialize", &AnyStepper::initialize, py::arg("t0"), py::arg("u0"), py::arg("v0"))
      .def("step", [](AnyStepper& s) { return std::string(to_string(s.step())); })
      .def_property_readonly("t", &AnyStepper::time)
      .def_property_readonly("step_index", &AnyStepper::step_index)
      .def_property_readonly("dt", &AnyStepper::dt)
      .def_property_readonly("size", &AnyStepper::size)
      .def_property_readonly("u", [](const AnyStepper& s) { return Vector(s.u()); })
      .def_property_readonly("v", [](const AnyStepper& s) { return Vector(s.v()); })
      .def_property_readonly("a", [](const AnyStepper& s) { return Vector(s.a()); })
      .def_property_readonly("stats", &AnyStepper::stats)
      .def_property_readonly("failure", [](const AnyStepper& s) { return failure_dict(s.failure()); })
      .def_property_readonly("scheme_name", &AnyStepper::scheme_name)
      .def_property_readonly("last_residuals", &AnyStepper::last_residuals)
      .def_property_readonly("accepted_residual", &AnyStepper::accepted_residual)
      .def("state", &AnyStepper::state, "the carried state [u; v; a; history...]")
      .def("set_state", &AnyStepper::set_state, py::arg("t"), py::arg("x"))
      .def(
          "integrate",
          [](AnyStepper& s, double t_end, std::int64_t save_every, std::vector<Index> dofs, double max_displacement,
             std::int64_t observe_every, py::object observer, bool energy, double max_energy_error) {
            SolveOptions opt;
            opt.energy = energy;
            opt.max_energy_error = max_energy_error;
            opt.save_every = save_every;
            opt.dofs = std::move(dofs);
            opt.max_displacement = max_displacement;
            opt.throw_on_failure = false;
            opt.observe_every = observe_every;
            return result_dict(s.integrate(t_end, opt, std::move(observer)));
          },
          py::arg("t_end"), py::arg("save_every") = 1, py::arg("dofs") = std::vector<Index>{},
          py::arg("max_displacement") = std::numeric_limits<double>::quiet_NaN(), py::arg("observe_every") = 4096,
          py::arg("observer") = py::none(), py::arg("energy") = false,
          py::arg("max_energy_error") = std::numeric_limits<double>::infinity());

  def_all_schemes<HybridModel>(m);
  def_all_schemes<EffectModel>(m);

  m.def("expm", &nvib::expm, py::arg("A"), py::arg("squarings") = 20,
        "Matrix exponential by the 2^N algorithm of the precise integration method.");
  m.def("steps_to_reach", &steps_to_reach, py::arg("t0"), py::arg("t_end"), py::arg("dt"));
  m.def("default_max_displacement", &nvib::default_max_displacement, py::arg("u"), py::arg("v"),
        py::arg("duration"));
}
