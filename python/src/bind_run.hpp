// Runs: the C++ solve() and a type-erased Stepper (one thread at a time), and
// the Result they return, whose histories NumPy reads without a copy.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <optional>
#include <stdexcept>

#include "bind_models.hpp"
#include "bind_result.hpp"

namespace nvib_py {

using nvib::Failure;
using nvib::SolveOptions;
using nvib::Status;

// Called about every 50 ms of work (the loop's clock): reports progress. Ctrl-C is checked by the
// interrupt hook (interruptible(), bind_types.hpp) at the same polls.
struct PyObserver {
  py::object callback;
  bool gil_released;

  void operator()(std::int64_t i, std::int64_t n) {
    if (callback.is_none()) return;
    if (gil_released) {
      py::gil_scoped_acquire gil;
      callback(i, n);
    } else {
      callback(i, n);
    }
  }
};

struct AnyStepper {
  virtual ~AnyStepper() = default;
  virtual void initialize(double t0, const Vector& u0, const Vector& v0) = 0;
  virtual Status step(Failure& failure) = 0;
  virtual double time() const = 0;
  virtual std::int64_t step_index() const = 0;
  virtual double dt() const = 0;
  virtual const Vector& u() const = 0;
  virtual const Vector& v() const = 0;
  virtual const Vector& a() const = 0;
  virtual nvib::Stats stats() const = 0;
  virtual Failure failure() const = 0;
  virtual std::vector<double> last_residuals() const = 0;
  virtual double accepted_residual() const = 0;
  virtual nvib::Result integrate(double t_end, const SolveOptions& opt, py::object observer) = 0;
  virtual Vector state() const = 0;
  virtual void set_state(double t, const Vector& x) = 0;

  py::object scheme;
  py::object dofs;  // the model's DOF names
  std::atomic<bool> busy{false};
};

// Holds the stepper for one thread; a second thread gets a RuntimeError instead of a corrupted state.
struct Exclusive {
  AnyStepper& s;
  explicit Exclusive(AnyStepper& st) : s(st) {
    if (s.busy.exchange(true))
      throw std::runtime_error("Stepper: used from two threads at once; a Stepper is not thread-safe (give each "
                               "thread its own, or serialise the calls)");
  }
  ~Exclusive() { s.busy = false; }
};

template <class S>
struct StepperImpl final : AnyStepper {
  template <class Scheme, class M>
  StepperImpl(const Scheme& sc, const M& model, double dt) : s(sc, model, dt) {}
  static constexpr bool python = std::is_same_v<std::decay_t<decltype(std::declval<S&>().model())>, HybridModel>;

  void initialize(double t0, const Vector& u0, const Vector& v0) override {
    interruptible(python, [&] { return (s.initialize(t0, u0, v0), 0); });
  }
  Status step(Failure& failure) override { return nvib::checked_step(s, failure); }
  double time() const override { return s.time(); }
  std::int64_t step_index() const override { return s.step_index(); }
  double dt() const override { return s.dt(); }
  const Vector& u() const override { return s.u(); }
  const Vector& v() const override { return s.v(); }
  const Vector& a() const override { return s.a(); }
  nvib::Stats stats() const override { return s.stats(); }
  Failure failure() const override { return s.failure(); }
  std::vector<double> last_residuals() const override {
    if constexpr (has_residuals<S>::value) return s.last_residuals();
    return {};
  }
  double accepted_residual() const override {
    if constexpr (nvib::has_accepted_residual<S>::value) return s.accepted_residual();
    return std::numeric_limits<double>::quiet_NaN();
  }
  Vector state() const override { return s.state(); }
  void set_state(double t, const Vector& x) override { s.set_state(t, x); }
  nvib::Result integrate(double t_end, const SolveOptions& opt, py::object observer) override {
    PyObserver obs{std::move(observer), !python};
    RunBound bound(std::isnan(opt.max_displacement)
                       ? nvib::default_max_displacement(s.u(), s.v(), t_end - s.time())
                       : opt.max_displacement);
    return interruptible(python, [&] { return nvib::integrate(s, t_end, opt, obs); });
  }

  template <class T, class = void>
  struct has_residuals : std::false_type {};
  template <class T>
  struct has_residuals<T, std::void_t<decltype(std::declval<const T&>().last_residuals())>> : std::true_type {};
  S s;
};

inline std::unique_ptr<AnyStepper> make_stepper(PyModel& model, py::object scheme, double dt) {
  std::unique_ptr<AnyStepper> out;
  with_scheme(scheme, "scheme", [&](const auto& sc) {
    using Scheme = std::decay_t<decltype(sc)>;
    model.visit([&](auto& md) {
      using M = std::decay_t<decltype(md)>;
      out = std::make_unique<StepperImpl<typename Scheme::template stepper<M>>>(sc, md, dt);
    });
    return py::none();
  });
  out->scheme = scheme;
  out->dofs = model.dofs;
  return out;
}

// Runs f, which returns the nvib::Result of a run, into out->r. When the run stops on an exception
// (Ctrl-C, an error raised by a Python callback) the history saved before it is not lost: it becomes
// the exception's `result` attribute (a Result like any other, its counters those of the steps taken).
template <class F>
void keeping_partial(std::unique_ptr<PyResult>& out, F&& f) {
  try {
    out->r = f();
  } catch (nvib::PartialRun& p) {
    out->r = std::move(p.partial);
    const std::exception_ptr cause = p.cause;
    py::object partial = py::cast(std::move(out));
    try {
      std::rethrow_exception(cause);
    } catch (py::error_already_set& e) {
      py::setattr(e.value(), "result", partial);
      throw;
    }
  }
}

// A run's options from the keywords Python passes (nvib._solve.RunOptions): SolveOptions' own defaults
// for those not given, so that each default is written once, in SolveOptions. Values are converted here;
// the loop checks them.
inline SolveOptions solve_options(const py::dict& given) {
  SolveOptions opt;
  for (auto item : given) {
    const std::string key = py::str(item.first);
    const py::handle v = item.second;
    if (key == "save_every") opt.save_every = v.cast<std::int64_t>();
    else if (key == "dofs") opt.dofs = v.cast<std::vector<Index>>();
    else if (key == "max_displacement") opt.max_displacement = v.cast<double>();
    else if (key == "energy") opt.energy = v.cast<bool>();
    else if (key == "max_energy_error") opt.max_energy_error = v.cast<double>();
    else if (key == "record") opt.record = v.cast<std::vector<std::string>>();
    else if (key == "collapse_deformation") opt.collapse_deformation = v.cast<double>();
    else if (key == "stop_at_collapse") opt.stop_at_collapse = v.cast<bool>();
    else if (key == "error_estimate") opt.error_estimate = v.cast<bool>();
    else if (key == "tol") opt.tol = v.cast<double>();
    else if (key == "max_dt") opt.max_dt = v.cast<double>();
    else if (key == "min_dt") opt.min_dt = v.cast<double>();
    else if (key == "reject_every") opt.reject_every = v.cast<std::int64_t>();
    else if (key == "peaks") {  // internal (solve_many's keep="peaks"): an (m, n) sparse D, or None
      opt.peaks = !v.is_none();
      if (opt.peaks) opt.peak_measures = v.cast<nvib::SparseMatrix>();
    } else raise_type_error(key, "not an option of a run");
  }
  opt.throw_on_failure = false;  // Python raises from the failure, with the partial result
  opt.keep_partial = true;
  return opt;
}

// The defaults of the options a Python caller may give (None: the loop's own default, NaN in C++).
inline py::dict run_defaults() {
  const SolveOptions d;
  auto none_if_nan = [](double x) { return std::isnan(x) ? py::object(py::none()) : py::object(py::float_(x)); };
  py::dict out;
  out["save_every"] = d.save_every;
  out["max_displacement"] = none_if_nan(d.max_displacement);
  out["energy"] = d.energy;
  out["max_energy_error"] = none_if_nan(d.max_energy_error);
  out["collapse_deformation"] = none_if_nan(d.collapse_deformation);
  out["stop_at_collapse"] = d.stop_at_collapse;
  out["error_estimate"] = d.error_estimate;
  return out;
}

inline void bind_run(py::module_& m) {
  m.attr("DEFAULT_MAX_ENERGY_ERROR") = nvib::kDefaultMaxEnergyError;
  m.attr("RUN_DEFAULTS") = run_defaults();
  m.def("available_memory", &nvib::available_memory_bytes, "bytes of memory available now (0 if unknown)");
  m.def("history_bytes", &nvib::history_bytes, py::arg("states"), py::arg("dofs"), py::arg("energy"),
        "bytes of a saved history of that many states and DOFs");
  m.attr("PIM_MAX_DOFS") = nvib::kPimMaxDofs;
  m.def("steps_to_reach", &nvib::steps_to_reach, py::arg("t0"), py::arg("t_end"), py::arg("dt"),
        "the number of steps of a run (t_end - t0)/dt, rounded up unless an integer to round-off");
  m.def("check_time_step", &nvib::check_time_step, py::arg("dt"), "the one check of a time step (ArgumentError naming dt)");
  m.def(
      "ordering_cache",
      [](bool clear) {
        auto& c = nvib::supernodal_detail::ordering_cache();
        if (clear) c.clear();
        const auto [kept, hits] = c.counts();
        return py::make_tuple(kept, hits);
      },
      py::arg("clear") = false,
      "(patterns kept, orderings reused so far) of the sparse factorisations' ordering cache; clear=True "
      "forgets the patterns first (a benchmark of cold runs)");
  m.def("run_steps", &nvib::run_steps, py::arg("t0"), py::arg("t_end"), py::arg("dt"),
        "steps_to_reach for a whole run (solve): a step longer than the run is refused naming dt");
  m.def(
      "solve",
      [](PyModel& model, py::object scheme, double dt, double t_end, double t0, const Vector& u0, const Vector& v0,
         const py::dict& options, py::object progress) {
        SolveOptions opt = solve_options(options);
        opt.t0 = t0;
        auto result = std::make_unique<PyResult>();
        result->scheme = scheme;
        result->dt = dt;
        result->names = model.dofs;
        with_scheme(scheme, "scheme", [&](const auto& sc) {
          model.visit([&](auto& md) {
            PyObserver obs{progress, !model.python()};
            RunBound bound(std::isnan(opt.max_displacement) ? nvib::default_max_displacement(u0, v0, t_end - t0)
                                                            : opt.max_displacement);
            keeping_partial(result, [&] {
              return interruptible(model.python(), [&] { return nvib::solve(md, sc, dt, t_end, u0, v0, opt, obs); });
            });
          });
          return py::none();
        });
        return result;
      },
      py::arg("model"), py::arg("scheme"), py::arg("dt"), py::arg("t_end"), py::arg("t0"), py::arg("u0"),
      py::arg("v0"), py::arg("options"), py::arg("progress"),
      "The one loop (C++): integrate model with scheme from (t0, u0, v0) to t_end with the options given (the "
      "others SolveOptions' defaults; NaN limits mean the defaults). options['peaks']: None, or an (m, n) sparse "
      "matrix D: Result._peaks is then (max |u_i|, max |D u|) over every step.");

  py::class_<AnyStepper>(m, "Stepper", "Step-by-step integration; one thread at a time.")
      .def(py::init(&make_stepper), py::arg("model"), py::arg("scheme"), py::arg("dt"))
      .def("initialize",
           [](AnyStepper& s, double t0, const Vector& u0, const Vector& v0) {
             Exclusive x(s);
             s.initialize(t0, u0, v0);
           },
           py::arg("t0"), py::arg("u0"), py::arg("v0"))
      .def("step",
           [](AnyStepper& s) {
             Exclusive x(s);
             Failure f;
             const Status st = s.step(f);
             return py::make_tuple(st, st == Status::success ? py::object(py::none()) : py::cast(f));
           },
           "one step with the divergence test: (status, failure or None)")
      .def_property_readonly("t", [](AnyStepper& s) { return (Exclusive(s), s.time()); })
      .def_property_readonly("step_index", [](AnyStepper& s) { return (Exclusive(s), s.step_index()); })
      .def_property_readonly("dt", &AnyStepper::dt)
      .def_property_readonly("u", [](AnyStepper& s) { return (Exclusive(s), Vector(s.u())); })
      .def_property_readonly("v", [](AnyStepper& s) { return (Exclusive(s), Vector(s.v())); })
      .def_property_readonly("a", [](AnyStepper& s) { return (Exclusive(s), Vector(s.a())); })
      .def_property_readonly("stats", [](AnyStepper& s) { return (Exclusive(s), s.stats()); })
      .def_property_readonly("failure", [](AnyStepper& s) { return (Exclusive(s), s.failure()); })
      .def_property_readonly("last_residuals", [](AnyStepper& s) { return (Exclusive(s), s.last_residuals()); })
      .def_property_readonly("accepted_residual", [](AnyStepper& s) {
        Exclusive x(s);
        const double r = s.accepted_residual();
        return std::isnan(r) ? py::object(py::none()) : py::object(py::float_(r));
      })
      .def("state", [](AnyStepper& s) { return (Exclusive(s), s.state()); }, "the carried state [u; v; a; history...]")
      .def("set_state",
           [](AnyStepper& s, double t, const Vector& x) {
             Exclusive g(s);
             s.set_state(t, x);
           },
           py::arg("t"), py::arg("x"))
      .def(
          "integrate",
          [](AnyStepper& s, double t_end, const py::dict& options, py::object progress) {
            Exclusive x(s);
            auto result = std::make_unique<PyResult>();
            result->scheme = s.scheme;
            result->dt = s.dt();
            result->names = s.dofs;
            keeping_partial(result, [&] {
              return s.integrate(t_end, solve_options(options), std::move(progress));
            });
            return result;
          },
          py::arg("t_end"), py::arg("options"), py::arg("progress"));

  m.def("expm", &nvib::expm, py::arg("A"), py::arg("squarings") = 20,
        "Matrix exponential by the 2^N algorithm of the precise integration method.");
  m.def("default_max_displacement",
        [](const Vector& u, const Vector& v, double duration) { return nvib::default_max_displacement(u, v, duration); },
        py::arg("u"), py::arg("v"), py::arg("duration"));
}

}  // namespace nvib_py
