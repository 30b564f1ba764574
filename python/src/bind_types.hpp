// The small bound types: argument errors (with .argument), Stats, Status, Failure.
#pragma once

#include <pybind11/native_enum.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <atomic>
#include <memory>
#include <string>
#include <vector>

#include <nvib/nvib.hpp>

namespace nvib_py {

namespace py = pybind11;

// Sets the Python error `type_name` of nvib._core (ArgumentError or ArgumentTypeError), whose message
// is "<argument>: <reason>", with .argument and .reason (so that a caller naming the argument otherwise,
// such as effects[2].k for k, keeps the reason without taking the message apart).
inline void set_argument_error(const char* type_name, const std::string& argument, const std::string& reason) {
  py::object cls = py::module_::import("nvib._core").attr(type_name);
  py::object exc = cls(argument + ": " + reason);
  exc.attr("argument") = argument;
  exc.attr("reason") = reason;
  PyErr_SetObject(cls.ptr(), exc.ptr());
}
// Raises ArgumentTypeError: "<argument>: <what>".
[[noreturn]] inline void raise_type_error(const std::string& argument, const std::string& what) {
  set_argument_error("ArgumentTypeError", argument, what);
  throw py::error_already_set();
}
// Raises ArgumentError (a ValueError): "<argument>: <what>".
[[noreturn]] inline void raise_value_error(const std::string& argument, const std::string& what) {
  set_argument_error("ArgumentError", argument, what);
  throw py::error_already_set();
}

// A request to stop, shared by the runs of a batch. Python runs its signal handlers in the main thread
// only, and PyErr_CheckSignals() does nothing in any other: a run on a worker thread (solve_many on
// threads, a Dask worker) learns of Ctrl-C through a token the main thread sets. A thread takes a
// token as its current one for the length of a `with token:` block.
struct StopToken {
  std::atomic<bool> requested{false};
};

inline std::shared_ptr<StopToken>& current_stop_token() {
  thread_local std::shared_ptr<StopToken> token;
  return token;
}
// The tokens a thread's enclosing `with` blocks made current, restored as the blocks end.
inline std::vector<std::shared_ptr<StopToken>>& outer_stop_tokens() {
  thread_local std::vector<std::shared_ptr<StopToken>> stack;
  return stack;
}

// Ctrl-C during C++ work: nvib::poll_interrupt() checks Python's signals (taking the GIL if the work
// released it) and the thread's stop token, and raises KeyboardInterrupt there. Installed for the C++
// work of each call.
struct PythonInterrupt {
  bool gil_released;
  static void poll(void* self) {
    auto check = [] {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      // after the signal handlers: a worker process's handler sets its token (nvib._batch)
      const std::shared_ptr<StopToken>& token = current_stop_token();
      if (token && token->requested.load(std::memory_order_relaxed)) {
        PyErr_SetString(PyExc_KeyboardInterrupt, "the run was stopped: its batch was interrupted");
        throw py::error_already_set();
      }
    };
    if (static_cast<PythonInterrupt*>(self)->gil_released) {
      py::gil_scoped_acquire gil;
      check();
    } else {
      check();
    }
  }
};

// Runs f with Ctrl-C checked at the C++ polls, and with the GIL released when no Python is called.
template <class F>
auto interruptible(bool calls_python, F&& f) {
  PythonInterrupt hook{!calls_python};
  nvib::ScopedInterruptHook scope(&PythonInterrupt::poll, &hook);
  if (calls_python) return f();
  py::gil_scoped_release nogil;
  return f();
}

inline py::dict stats_dict(const nvib::Stats& s) {
  py::dict d;
  nvib::Stats::counters(s, [&](const char* name, std::int64_t c, const char*) { d[name] = c; });
  d["wall_time"] = s.wall_time;
  d["linear_solver"] = std::string(s.linear_solver);
  return d;
}

// Stats::linear_solver points at a static name: the one a pickled name stands for.
inline const char* linear_solver_name(const std::string& s) {
  for (const char* known : nvib::kLinearSolverNames)
    if (s == known) return known;
  if (s.empty()) return "";
  raise_value_error("linear_solver", "unknown linear solver '" + s + "'");
}

inline void bind_types(py::module_& m) {
  py::class_<StopToken, std::shared_ptr<StopToken>>(
      m, "StopToken",
      "A request to stop shared by runs on several threads: `with token:` makes it the current thread's, "
      "and a run there raises KeyboardInterrupt at its next poll (about every 50 ms of work) once set.")
      .def(py::init<>())
      .def("set", [](StopToken& t) { t.requested.store(true); }, "request every run under this token to stop")
      .def_property_readonly("is_set", [](const StopToken& t) { return t.requested.load(); })
      .def("__enter__",
           [](std::shared_ptr<StopToken> self) {
             outer_stop_tokens().push_back(current_stop_token());
             current_stop_token() = self;
             return self;
           })
      .def("__exit__", [](std::shared_ptr<StopToken>, py::object, py::object, py::object) {
        current_stop_token() = outer_stop_tokens().empty() ? nullptr : outer_stop_tokens().back();
        if (!outer_stop_tokens().empty()) outer_stop_tokens().pop_back();
        return false;
      });
  using nvib::Failure;
  using nvib::Stats;
  using nvib::Status;
  for (auto [name, base, doc] :
       {std::tuple{"ArgumentError", PyExc_ValueError, "A bad argument (a ValueError); .argument names it."},
        std::tuple{"ArgumentTypeError", PyExc_TypeError, "An argument of the wrong type (a TypeError); .argument names it."}}) {
    py::object cls = py::reinterpret_steal<py::object>(
        PyErr_NewExceptionWithDoc((std::string("nvib._core.") + name).c_str(), doc, base, nullptr));
    cls.attr("argument") = py::none();
    cls.attr("reason") = py::none();
    m.attr(name) = cls;
  }
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const nvib::ArgumentError& e) {
      set_argument_error("ArgumentError", e.argument(), e.reason());
    }
  });

  py::native_enum<Status>(m, "Status", "enum.Enum",
                          "How a run ended: success, diverged (non-finite or unbounded state, or energy created), "
                          "newton_failed (the equilibrium iteration did not converge), singular_matrix, interrupted "
                          "(Ctrl-C or an exception from a callback stopped it; the partial result travels with it), or "
                          "collapsed (a law with memory lost its strength, or an effect deformed beyond the collapse "
                          "limit: a result of the model, returned, never raised).")
      .value("success", Status::success)
      .value("diverged", Status::diverged)
      .value("newton_failed", Status::newton_failed)
      .value("singular_matrix", Status::singular_matrix)
      .value("interrupted", Status::interrupted)
      .value("collapsed", Status::collapsed)
      .finalize();

  py::class_<Stats> stats(m, "Stats", "Counters summed over a run (never reset per step).");
  stats.def(py::init<>());
  Stats probe;
  Stats::counters(probe, [&](const char* name, std::int64_t& c, const char* doc) {
    const std::ptrdiff_t offset = reinterpret_cast<char*>(&c) - reinterpret_cast<char*>(&probe);
    stats.def_property_readonly(
        name, [offset](const Stats& s) { return *reinterpret_cast<const std::int64_t*>(reinterpret_cast<const char*>(&s) + offset); },
        doc);
  });
  stats.def_readonly("wall_time", &Stats::wall_time, "seconds")
      .def_property_readonly("linear_solver", [](const Stats& s) { return std::string(s.linear_solver); },
                             "the implicit schemes' linear solver: 'dense LU', 'banded LDLT', 'sparse LDLT' (simplicial), 'supernodal LDLT' or 'sparse LU', each also '... + low-rank update' (the linear part factorised once, the effects' tangent as a low-rank update) ('' if none)")
      .def("as_dict", &stats_dict)
      .def(py::pickle(
          [](const Stats& s) {  // the counters in order, then wall_time and linear_solver
            py::list x;
            Stats::counters(s, [&](const char*, std::int64_t c, const char*) { x.append(c); });
            x.append(s.wall_time);
            x.append(std::string(s.linear_solver));
            return py::tuple(x);
          },
          [](const py::tuple& x) {
            Stats s;
            size_t k = 0;
            Stats::counters(s, [&](const char*, std::int64_t&, const char*) { ++k; });
            if (x.size() != k + 2) raise_value_error("state", "not a pickled Stats");
            k = 0;
            Stats::counters(s, [&](const char*, std::int64_t& c, const char*) { c = x[k++].cast<std::int64_t>(); });
            s.wall_time = x[k].cast<double>();
            s.linear_solver = linear_solver_name(x[k + 1].cast<std::string>());
            return s;
          }))
      .def("__repr__", [](const Stats& s) {
        std::string out;
        for (auto item : stats_dict(s))
          out += (out.empty() ? "" : ", ") + std::string(py::str(item.first)) + "=" + std::string(py::repr(item.second));
        return "Stats(" + out + ")";
      });

  py::class_<Failure>(m, "Failure", "Where and why a run stopped early.")
      .def_readonly("status", &Failure::status)
      .def_readonly("step", &Failure::step, "index of the step that failed (1 = the first step)")
      .def_readonly("t", &Failure::t, "time the failed step was heading for")
      .def_readonly("dof", &Failure::dof, "offending DOF for divergence, -1 if not applicable")
      .def_readonly("residuals", &Failure::residuals, "Newton residual norms of the failed step")
      .def_readonly("message", &Failure::message)
      .def(py::pickle(
          [](const Failure& f) { return py::make_tuple(f.status, f.step, f.t, f.dof, f.residuals, f.message); },
          [](const py::tuple& x) {
            if (x.size() != 6) raise_value_error("state", "not a pickled Failure");
            Failure f;
            f.status = x[0].cast<Status>();
            f.step = x[1].cast<std::int64_t>();
            f.t = x[2].cast<double>();
            f.dof = x[3].cast<nvib::Index>();
            f.residuals = x[4].cast<std::vector<double>>();
            f.message = x[5].cast<std::string>();
            return f;
          }))
      .def("__repr__", [](const Failure& f) { return "Failure(" + std::string(py::repr(py::str(f.message))) + ")"; });
}

}  // namespace nvib_py
