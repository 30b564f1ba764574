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
  py::array column(int k) const { return view(table->data() + k, table->rows(), 1, nvib::kEnergyColumns, owner, true); }
};
constexpr const char* kEnergyNames[] = {"kinetic", "potential", "work_in", "dissipated", "hysteretic", "balance_error"};

inline double relative_balance_error(const nvib::History& e) {
  using namespace nvib;
  double scale = 0.0, worst = 0.0;
  for (Index i = 0; i < e.rows(); ++i) {
    const double parts = std::abs(e(i, kinetic)) + std::abs(e(i, potential)) + std::abs(e(i, work_in)) +
                         std::abs(e(i, dissipated)) + std::abs(e(i, hysteretic));
    if (!std::isfinite(parts) || !std::isfinite(e(i, balance_error))) return std::numeric_limits<double>::infinity();
    scale = std::max(scale, parts);
    worst = std::max(worst, std::abs(e(i, balance_error)));
  }
  return scale > 0.0 ? worst / scale : 0.0;
}

// A recorded effect (solve(record=[...])): its histories as views of the Result's storage.
struct PyEffectRecord {
  py::object owner;  // the Result
  const nvib::EffectRecord* r;
  // (n_saved,) for a single effect, (n_saved, count) for several.
  py::array column_or_table(const nvib::History& h) const {
    return view(h.data(), h.rows(), h.cols(), h.cols(), owner, r->count == 1);
  }
};

inline void bind_result(py::module_& m) {
  py::class_<PyEnergy>(m, "Energy",
                       "Energy accounting at the saved states: kinetic, potential (conservative effects and K, and "
                       "the energy the laws with memory store), work_in (work of loads and moving supports since t0), "
                       "dissipated (by dampers since t0), hysteretic (dissipated by the laws with memory since t0) and "
                       "balance_error = kinetic + potential + dissipated + hysteretic - work_in - (kinetic + potential "
                       "at t0).")
      .def_property_readonly("kinetic", [](const PyEnergy& e) { return e.column(nvib::kinetic); })
      .def_property_readonly("potential", [](const PyEnergy& e) { return e.column(nvib::potential); })
      .def_property_readonly("work_in", [](const PyEnergy& e) { return e.column(nvib::work_in); })
      .def_property_readonly("dissipated", [](const PyEnergy& e) { return e.column(nvib::dissipated); })
      .def_property_readonly("hysteretic", [](const PyEnergy& e) { return e.column(nvib::hysteretic); })
      .def_property_readonly("balance_error", [](const PyEnergy& e) { return e.column(nvib::balance_error); })
      .def_property_readonly("total", [](const PyEnergy& e) {
        py::array_t<double> out(e.table->rows());
        for (Index i = 0; i < e.table->rows(); ++i)
          out.mutable_data()[i] = (*e.table)(i, nvib::kinetic) + (*e.table)(i, nvib::potential);
        return out;
      })
      .def("relative_balance_error", [](const PyEnergy& e) { return relative_balance_error(*e.table); },
           "max |balance error| over the largest energy magnitude seen in the run (inf for a run that blew up)")
      .def("as_dict", [](const PyEnergy& e) {
        py::dict d;
        for (int k = 0; k < nvib::kEnergyColumns; ++k) d[kEnergyNames[k]] = e.column(k);
        return d;
      });

  py::class_<PyEffectRecord>(m, "EffectRecord",
                             "A recorded effect at the saved states: measure d, rate d', force f (arrays of the saved "
                             "states, or (states, count) for several effects of one name) and state, a dict of its "
                             "internal variables (plastic deformation, z, dissipated energy, ...).")
      .def_property_readonly("name", [](const PyEffectRecord& e) { return e.r->name; })
      .def_property_readonly("type", [](const PyEffectRecord& e) { return e.r->type; })
      .def_property_readonly("count", [](const PyEffectRecord& e) { return e.r->count; })
      .def_property_readonly("measure", [](const PyEffectRecord& e) { return e.column_or_table(e.r->measure); })
      .def_property_readonly("rate", [](const PyEffectRecord& e) { return e.column_or_table(e.r->rate); })
      .def_property_readonly("force", [](const PyEffectRecord& e) { return e.column_or_table(e.r->force); })
      .def_property_readonly("state_names", [](const PyEffectRecord& e) { return e.r->state_names; })
      .def_property_readonly("state", [](const PyEffectRecord& e) {
        py::dict d;
        const Index W = static_cast<Index>(e.r->state_names.size()), stride = e.r->state.cols();
        for (Index w = 0; w < W; ++w) {
          const double* first = e.r->state.data() + w;
          const auto dsize = static_cast<py::ssize_t>(sizeof(double));
          d[py::str(e.r->state_names[static_cast<size_t>(w)])] =
              e.r->count == 1 ? py::array_t<double>({e.r->state.rows()}, {stride * dsize}, first, e.owner)
                              : py::array_t<double>({e.r->state.rows(), e.r->count}, {stride * dsize, W * dsize}, first,
                                                    e.owner);
        }
        return d;
      })
      .def("__repr__", [](const PyEffectRecord& e) {
        return "EffectRecord('" + e.r->name + "', " + e.r->type + (e.r->count == 1 ? "" : ", " + std::to_string(e.r->count) + " effects") +
               ", " + std::to_string(e.r->measure.rows()) + " states)";
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
      .def_property_readonly("effects",
                             [](py::object self) {
                               py::dict d;
                               for (const nvib::EffectRecord& r : self.cast<PyResult&>().r.effects)
                                 d[py::str(r.name)] = py::cast(PyEffectRecord{self, &r});
                               return d;
                             },
                             "the recorded effects by name (solve(record=[...])): EffectRecord")
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
      .def_property_readonly("_peaks", [](const PyResult& p) -> py::object {
        if (p.r.peak_u.size() == 0 && p.r.peak_measures.size() == 0) return py::none();
        const double e = p.r.peak_energy_error;
        return py::make_tuple(nvib::Vector(p.r.peak_u), nvib::Vector(p.r.peak_measures),
                              std::isnan(e) ? py::object(py::none()) : py::object(py::float_(e)));
      }, "(max |u_i| per DOF, max |D u| per row of D, the relative energy balance error or None) over every step "
         "of a run made with peaks=D; else None")
      .def_property_readonly("_error_estimate", [](const PyResult& p) -> py::object {
        if (p.r.error_estimate.size() == 0) return py::none();
        return py::cast(nvib::Vector(p.r.error_estimate));
      }, "every DOF's estimated error relative to its peak (SolveOptions::error_estimate), or None")
      .def_readonly("scheme", &PyResult::scheme)
      .def_readonly("dt", &PyResult::dt)
      .def_readwrite("_extras", &PyResult::extras, "what the Python layer adds: a dict (ground, units, warnings)")
      .def(py::pickle(
          [](const PyResult& p) {
            const nvib::Result& r = p.r;
            py::list effects;
            for (const nvib::EffectRecord& e : r.effects)
              effects.append(py::make_tuple(e.name, e.type, e.state_names, e.count, e.measure, e.rate, e.force, e.state));
            return py::make_tuple(r.t, r.u, r.v, r.a, r.energy, r.dofs, r.stats, r.status, r.failure,
                                  r.num_steps_requested, r.max_residual, p.scheme, p.dt, p.names, p.extras, effects,
                                  r.peak_u, r.peak_measures, r.peak_energy_error, r.error_estimate);
          },
          [](const py::tuple& x) {
            if (x.size() != 16 && x.size() != 19 && x.size() != 20) raise_value_error("state", "not a pickled Result");
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
            for (auto item : x[15].cast<py::list>()) {
              const py::tuple e = item.cast<py::tuple>();
              nvib::EffectRecord rec;
              rec.name = e[0].cast<std::string>();
              rec.type = e[1].cast<std::string>();
              rec.state_names = e[2].cast<std::vector<std::string>>();
              rec.count = e[3].cast<Index>();
              rec.measure = e[4].cast<nvib::History>();
              rec.rate = e[5].cast<nvib::History>();
              rec.force = e[6].cast<nvib::History>();
              rec.state = e[7].cast<nvib::History>();
              r.effects.push_back(std::move(rec));
            }
            if (x.size() == 19) {
              r.peak_u = x[16].cast<nvib::Vector>();
              r.peak_measures = x[17].cast<nvib::Vector>();
              r.peak_energy_error = x[18].cast<double>();
            }
            if (x.size() == 20) r.error_estimate = x[19].cast<nvib::Vector>();
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
