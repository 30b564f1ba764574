// Result: a run's saved history, counters, status and failure. Histories are
// NumPy views of the C++ storage (no copy), kept alive by the Result.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cmath>
#include <string>
#include <vector>

#include <nvib/nvib.hpp>

#include "bind_types.hpp"

namespace nvib_py {

struct PyResult {
  nvib::Result r;
  py::object scheme = py::none();
  double dt = 0.0;
  py::object names = py::none();      // the model's DOF names (a list, or names made on demand)
  py::object dof_names = py::none();  // of the saved DOFs, made on first use
  py::object extras = py::none();     // what the Python layer adds (ground motions, units, warnings): a dict

  // The names of the saved DOFs: the model's own sequence when all are saved in order (names made on
  // demand stay so), else a list.
  py::object saved_names() {
    if (!dof_names.is_none()) return dof_names;
    const size_t m = r.dofs.size();
    bool all = m == py::len(names);
    for (size_t k = 0; all && k < m; ++k) all = r.dofs[k] == static_cast<Index>(k);
    if (all && !py::isinstance<py::list>(names)) {
      dof_names = names;
    } else {
      py::list out(m);
      for (size_t k = 0; k < m; ++k) out[k] = names[py::int_(r.dofs[k])];
      dof_names = out;
    }
    return dof_names;
  }
};

// An (rows, cols) view of row-major storage with the given column stride, owned by `owner`.
inline py::array view(const double* data, Index rows, Index cols, Index row_stride, py::handle owner, bool column) {
  const auto d = static_cast<py::ssize_t>(sizeof(double));
  if (column) return py::array_t<double>({rows}, {row_stride * d}, data, owner);
  return py::array_t<double>({rows, cols}, {row_stride * d, d}, data, owner);
}

// The energy accounting at the saved states (columns of Result::energy).
struct PyEnergy {
  py::object owner;  // the Result
  const nvib::History* table;
  py::array column(int k) const { return view(table->data() + k, table->rows(), 1, 5, owner, true); }
};

inline double relative_balance_error(const nvib::History& e) {
  double scale = 0.0, worst = 0.0;
  for (Index i = 0; i < e.rows(); ++i) {
    const double parts = std::abs(e(i, 0)) + std::abs(e(i, 1)) + std::abs(e(i, 2)) + std::abs(e(i, 3));
    if (!std::isfinite(parts) || !std::isfinite(e(i, 4))) return std::numeric_limits<double>::infinity();
    scale = std::max(scale, parts);
    worst = std::max(worst, std::abs(e(i, 4)));
  }
  return scale > 0.0 ? worst / scale : 0.0;
}

inline void bind_result(py::module_& m) {
  py::class_<PyEnergy>(m, "Energy",
                       "Energy accounting at the saved states: kinetic, potential (conservative effects and K), "
                       "work_in (work of loads and moving supports since t0), dissipated (by dampers since t0) and "
                       "balance_error = kinetic + potential + dissipated - work_in - (kinetic + potential at t0).")
      .def_property_readonly("kinetic", [](const PyEnergy& e) { return e.column(0); })
      .def_property_readonly("potential", [](const PyEnergy& e) { return e.column(1); })
      .def_property_readonly("work_in", [](const PyEnergy& e) { return e.column(2); })
      .def_property_readonly("dissipated", [](const PyEnergy& e) { return e.column(3); })
      .def_property_readonly("balance_error", [](const PyEnergy& e) { return e.column(4); })
      .def_property_readonly("total", [](const PyEnergy& e) {
        py::array_t<double> out(e.table->rows());
        for (Index i = 0; i < e.table->rows(); ++i) out.mutable_data()[i] = (*e.table)(i, 0) + (*e.table)(i, 1);
        return out;
      })
      .def("relative_balance_error", [](const PyEnergy& e) { return relative_balance_error(*e.table); },
           "max |balance error| over the largest energy magnitude seen in the run (inf for a run that blew up)")
      .def("as_dict", [](const PyEnergy& e) {
        py::dict d;
        const char* names[] = {"kinetic", "potential", "work_in", "dissipated", "balance_error"};
        for (int k = 0; k < 5; ++k) d[names[k]] = e.column(k);
        return d;
      });

  py::class_<PyResult>(m, "Result",
                       "A run: times t (n_saved,), histories u, v, a (n_saved, n_saved_dofs) with the saved DOF "
                       "names in dofs, counters stats, status, failure (None on success). max_residual: for the "
                       "implicit schemes, the largest equilibrium residual of an accepted step relative to its force "
                       "scale (below about rtol with Newton; what the incremental and one_iteration modes leave); "
                       "None for the explicit schemes and for linear models.")
      .def_property_readonly("t", [](py::object self) {
        const auto& r = self.cast<PyResult&>().r;
        return view(r.t.data(), r.t.size(), 1, 1, self, true);
      })
      .def_property_readonly("u", [](py::object self) {
        const auto& h = self.cast<PyResult&>().r.u;
        return view(h.data(), h.rows(), h.cols(), h.cols(), self, false);
      })
      .def_property_readonly("v", [](py::object self) {
        const auto& h = self.cast<PyResult&>().r.v;
        return view(h.data(), h.rows(), h.cols(), h.cols(), self, false);
      })
      .def_property_readonly("a", [](py::object self) {
        const auto& h = self.cast<PyResult&>().r.a;
        return view(h.data(), h.rows(), h.cols(), h.cols(), self, false);
      })
      .def_property_readonly("energy",
                             [](py::object self) -> py::object {
                               const auto& r = self.cast<PyResult&>().r;
                               if (r.energy.size() == 0) return py::none();
                               return py::cast(PyEnergy{self, &r.energy});
                             })
      .def_property_readonly("dofs", &PyResult::saved_names, "the names of the saved DOFs")
      .def_property_readonly("dof_indices", [](const PyResult& p) { return p.r.dofs; })
      .def_property_readonly("stats", [](const PyResult& p) { return p.r.stats; })
      .def_property_readonly("status", [](const PyResult& p) { return p.r.status; })
      .def_property_readonly("success", [](const PyResult& p) { return p.r.status == nvib::Status::success; })
      .def_property_readonly("failure", [](const PyResult& p) -> py::object {
        if (p.r.status == nvib::Status::success) return py::none();
        return py::cast(p.r.failure);
      })
      .def_property_readonly("num_steps_requested", [](const PyResult& p) { return p.r.num_steps_requested; })
      .def_property_readonly("max_residual", [](const PyResult& p) -> py::object {
        if (std::isnan(p.r.max_residual)) return py::none();
        return py::float_(p.r.max_residual);
      })
      .def_readonly("scheme", &PyResult::scheme)
      .def_readonly("dt", &PyResult::dt)
      .def_readwrite("_extras", &PyResult::extras, "what the Python layer adds: a dict (ground, units, warnings)")
      .def(py::pickle(
          [](const PyResult& p) {
            const nvib::Result& r = p.r;
            return py::make_tuple(r.t, r.u, r.v, r.a, r.energy, r.dofs, r.stats, r.status, r.failure,
                                  r.num_steps_requested, r.max_residual, p.scheme, p.dt, p.names, p.extras);
          },
          [](const py::tuple& x) {
            if (x.size() != 15) raise_value_error("state", "not a pickled Result");
            auto p = std::make_unique<PyResult>();
            nvib::Result& r = p->r;
            r.t = x[0].cast<nvib::Vector>();
            r.u = x[1].cast<nvib::History>();
            r.v = x[2].cast<nvib::History>();
            r.a = x[3].cast<nvib::History>();
            r.energy = x[4].cast<nvib::History>();
            r.dofs = x[5].cast<std::vector<nvib::Index>>();
            r.stats = x[6].cast<nvib::Stats>();
            r.status = x[7].cast<nvib::Status>();
            r.failure = x[8].cast<nvib::Failure>();
            r.num_steps_requested = x[9].cast<std::int64_t>();
            r.max_residual = x[10].cast<double>();
            p->scheme = x[11];
            p->dt = x[12].cast<double>();
            p->names = x[13];
            p->extras = x[14];
            return p;
          }))
      .def("__repr__", [](const PyResult& p) {
        char wall[32];
        std::snprintf(wall, sizeof wall, "%.3g", p.r.stats.wall_time);
        return "Result(" + std::string(py::repr(p.scheme)) + ", status=" +
               std::string(py::str(py::cast(p.r.status).attr("name"))) + ", saved=" + std::to_string(p.r.t.size()) +
               ", steps=" + std::to_string(p.r.stats.num_steps) + ", wall_time=" + wall + "s)";
      });
}

}  // namespace nvib_py
