// Models: the declared effects (Effect, and the laws they may use) and one
// Model type holding either a C++-only model or one with Python callables.
#pragma once

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <cstring>
#include <string>
#include <tuple>
#include <variant>
#include <vector>

#include <nvib/nvib.hpp>

#include "bind_schemes.hpp"
#include "py_force.hpp"

namespace nvib_py {

namespace fx = nvib::effects;
using nvib::Matrix;
using nvib::Vector;
using EffectModel = nvib::Model<fx::EffectSet>;
using HybridModel = nvib::Model<fx::EffectsPlus<PyForce>>;
using MassArray = py::array_t<double, py::array::c_style | py::array::forcecast>;

// A model: declared effects only (no Python in the loop: the GIL is released),
// or with Python callables (the GIL is kept); its DOF names.
struct PyModel {
  std::variant<EffectModel, HybridModel> m;
  py::object dofs;  // the DOF names: a list, or names made on demand (nvib._names)
  bool python() const { return m.index() == 1; }
  template <class F>
  decltype(auto) visit(F&& f) {
    return std::visit(std::forward<F>(f), m);
  }
  template <class F>
  decltype(auto) visit(F&& f) const {
    return std::visit(std::forward<F>(f), m);
  }
  const fx::EffectSet& effects() const {
    return python() ? std::get<1>(m).nonlinear_force().effects() : std::get<0>(m).nonlinear_force();
  }
  fx::EffectSet& effects() {
    return python() ? std::get<1>(m).nonlinear_force().effects() : std::get<0>(m).nonlinear_force();
  }
};

inline nvib::Mass make_mass(const MassArray& m, const nvib::Mass::DofName& name = {}) {
  if (m.ndim() == 1) return nvib::Mass::diagonal(Eigen::Map<const Vector>(m.data(), m.shape(0)), name);
  if (m.ndim() == 2) {
    Matrix M = Eigen::Map<const nvib::History>(m.data(), m.shape(0), m.shape(1));
    if (M.rows() == M.cols()) {
      Matrix off = M;
      off.diagonal().setZero();
      if (off.allFinite() && off.cwiseAbs().maxCoeff() == 0.0) return nvib::Mass::diagonal(M.diagonal(), name);
    }
    return nvib::Mass::dense(M, name);
  }
  raise_value_error("mass", "expected a 1-D array (diagonal) or a 2-D matrix");
}

// A scipy.sparse mass: sparse (or lumped, if only its diagonal is stored).
inline nvib::Mass make_mass(const py::object& mass, const nvib::Mass::DofName& name = {}) {
  if (py::module_::import("scipy.sparse").attr("issparse")(mass).cast<bool>())
    return nvib::Mass::sparse(mass.cast<nvib::SparseMatrix>(), name);
  return make_mass(mass.cast<MassArray>(), name);
}

// "DOF i (its name)" for the mass's messages; the index alone where the name cannot be had.
inline nvib::Mass::DofName dof_namer(const py::object& dofs) {
  return [dofs](Index i) {
    std::string out = "DOF " + std::to_string(i);
    try {
      out += " (" + py::str(dofs[py::int_(i)]).cast<std::string>() + ")";
    } catch (const py::error_already_set&) {
    }
    return out;
  };
}

inline fx::LawId parse_law(const std::string& s) { return fx::law_of(s); }

inline fx::Signal make_signal(const std::string& kind, double amplitude, double omega, double phase,
                              std::vector<double> t, std::vector<double> values) {
  if (kind == "none") return {};
  if (kind == "sine") return fx::Signal::sine(amplitude, omega, phase);
  if (kind == "table") return fx::Signal::table(std::move(t), std::move(values));
  raise_value_error("signal.kind", "expected 'sine' or 'table', got '" + kind + "'");
}

// {type: {doc, source, parameters: [(name, default or None, doc, may be unset, choices or None)], signal,
//  signal_required, uses_displacement, uses_velocity, is_load, knows_energy (its stored energy is known),
//  state: [names of the internal variables]}}
inline py::dict laws() {
  py::dict out;
  fx::AllLaws::for_each([&](auto L) {
    using Lw = decltype(L);
    py::list params;
    for (const auto& p : Lw::parameters)
      params.append(py::make_tuple(p.name, std::isnan(p.fallback) ? py::object(py::none()) : py::float_(p.fallback),
                                   p.doc, p.may_be_unset,
                                   p.choices ? py::object(py::str(p.choices)) : py::object(py::none())));
    py::list state;
    for (const char* name : Lw::state_names) state.append(name);
    py::dict d;
    d["doc"] = Lw::doc;
    d["source"] = Lw::source;
    d["parameters"] = params;
    d["signal"] = Lw::signal ? py::object(py::str(Lw::signal)) : py::object(py::none());
    d["signal_required"] = Lw::signal_required;
    d["uses_displacement"] = Lw::uses_displacement;
    d["uses_velocity"] = Lw::uses_velocity;
    d["is_load"] = Lw::is_load;
    d["knows_energy"] = Lw::knows_energy;
    d["state"] = state;
    out[Lw::key] = d;
  });
  return out;
}

// A parameter's value as Python shows it: the word of a choice, else the number.
inline py::object parameter_value(const fx::Parameter& p, double x) {
  if (!p.choices) return py::float_(x);
  std::string words = p.choices;
  for (int k = 0; k < static_cast<int>(x); ++k) words = words.substr(words.find('|') + 1);
  return py::str(words.substr(0, words.find('|')));
}

// The declared parameters by name (those left unset are absent).
inline py::dict effect_parameters(const fx::Effect& e) {
  py::dict d;
  fx::dispatch(e.law, [&](auto L) {
    using Lw = decltype(L);
    for (size_t k = 0; k < Lw::parameters.size(); ++k)
      if (!fx::is_unset(e.values[k])) d[Lw::parameters[k].name] = parameter_value(Lw::parameters[k], e.values[k]);
  });
  return d;
}

// laws: (index, coef, law, tangent or None, where, uses_velocity, uses_time, initial state) per scalar Python law.
using LawSpec = std::tuple<std::vector<Index>, std::vector<double>, py::object, py::object, std::string, bool, bool,
                           std::vector<double>>;

// vector_laws: (i, j (-1: the ground), law, tangent or None, where, uses_velocity, uses_time, initial states
// (effect by effect), internal variables per effect) per vectorised Python law.
using ArrayLawSpec = std::tuple<std::vector<Index>, std::vector<Index>, py::object, py::object, std::string, bool, bool,
                                std::vector<double>, Index>;

inline PyModel make_model(const py::object& mass, std::vector<fx::Effect> list, const nvib::SparseMatrix& K,
                          const nvib::SparseMatrix& C,
                          py::object dofs, py::object force, py::object tangent, bool uses_velocity,
                          bool uses_time, std::vector<LawSpec> laws, std::vector<fx::EffectArray> arrays,
                          std::vector<ArrayLawSpec> vector_laws, const py::object& mass_of) {
  // mass_of: a model whose mass this one has (a model rebuilt with other effects or C: its mass, factorised,
  // is shared instead of factorised again; `mass` is then not read)
  nvib::Mass ms = mass_of.is_none() ? make_mass(mass, dof_namer(dofs))
                                    : mass_of.cast<const PyModel&>().visit([](const auto& md) { return md.mass(); });
  if (static_cast<Index>(py::len(dofs)) != ms.size())
    raise_value_error("dofs", "expected " + std::to_string(ms.size()) + " names, got " + std::to_string(py::len(dofs)));
  for (const fx::EffectArray& a : arrays)
    for (size_t k = 0; k < a.size(); ++k)
      if (a.i[k] >= ms.size() || a.j[k] >= ms.size())
        raise_value_error("arrays", "an effect array refers to DOF " + std::to_string(std::max(a.i[k], a.j[k])) +
                                        " of a model of " + std::to_string(ms.size()));
  if (force.is_none() && laws.empty() && vector_laws.empty())  // assembly and compilation, C++ only: no GIL
    return interruptible(false, [&] {
      return PyModel{fx::make_effect_model(std::move(ms), std::move(list), std::move(arrays), K, C), std::move(dofs)};
    });
  PyForce f;
  f.force = std::move(force);
  f.tangent_ = std::move(tangent);
  f.n = ms.size();
  f.velocity = uses_velocity;
  f.time = uses_time;
  for (auto& [index, coef, law, tan, where, vel, time, initial] : laws) {
    if (index.size() != coef.size() || index.empty())
      raise_value_error(where + ".measure", "index and coef must be non-empty and equally long");
    for (Index i : index)
      if (i < 0 || i >= ms.size()) raise_value_error(where + ".measure", "DOF index " + std::to_string(i) + " is out of range");
    f.laws.push_back(PyLaw{index, coef, law, tan, where, vel, time, initial, 0});
  }
  for (auto& [i, j, law, tan, where, vel, time, initial, width] : vector_laws) {
    if (i.size() != j.size() || i.empty()) raise_value_error(where + ".i", "i and j must be non-empty and equally long");
    for (size_t k = 0; k < i.size(); ++k)
      if (i[k] < 0 || i[k] >= ms.size() || j[k] < -1 || j[k] >= ms.size())
        raise_value_error(where + ".i", "DOF index out of range at effect " + std::to_string(k));
    if (initial.size() != i.size() * static_cast<size_t>(width))
      raise_value_error(where + ".state", "expected " + std::to_string(width) + " internal variables per effect");
    f.arrays.push_back(PyArrayLaw{i, j, law, tan, where, vel, time, initial, width, 0});
  }
  f.place_states();
  return PyModel{fx::make_effect_model_plus(std::move(ms), std::move(list), std::move(arrays), std::move(f), K, C),
                 std::move(dofs)};
}

// An effect array from Python: i, j as integer arrays, each parameter one value or an array.
inline fx::EffectArray make_array(const std::string& type, const py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>& i,
                                  const py::array_t<std::int32_t, py::array::c_style | py::array::forcecast>& j,
                                  const py::dict& parameters, Index n, const std::string& name, const std::string& signal,
                                  double amplitude, double omega, double phase, std::vector<double> t,
                                  std::vector<double> values) {
  std::vector<std::pair<std::string, std::vector<double>>> named;
  for (auto item : parameters) {
    const std::string key = item.first.cast<std::string>();
    auto arr = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(item.second);
    if (!arr) raise_type_error(key, "expected a real number or an array of them");
    named.emplace_back(key, std::vector<double>(arr.data(), arr.data() + arr.size()));
  }
  std::vector<std::int32_t> vi(i.data(), i.data() + i.size()), vj(j.data(), j.data() + j.size());
  fx::Signal sig = make_signal(signal, amplitude, omega, phase, std::move(t), std::move(values));
  py::gil_scoped_release nogil;
  return fx::make_effect_array(parse_law(type), std::move(vi), std::move(vj), named, n, std::move(sig), name);
}

// The model's K (stiffness) or C with the linear arrays' entries added in.
inline nvib::SparseMatrix linear_matrix(const PyModel& p, bool stiffness) {
  return p.visit([&](auto& md) {
    const nvib::SparseMatrix& A = stiffness ? md.K() : md.C();
    std::vector<Eigen::Triplet<double, int>> all;
    p.effects().add_linear_array_entries(stiffness, all);
    if (all.empty()) return A.rows() ? A : nvib::SparseMatrix(md.size(), md.size());
    for (Index j = 0; j < A.outerSize(); ++j)
      for (nvib::SparseMatrix::InnerIterator it(A, j); it; ++it) all.emplace_back(it.row(), int(j), it.value());
    nvib::SparseMatrix out(md.size(), md.size());
    out.setFromTriplets(all.begin(), all.end());
    return out;
  });
}

// (K_t, C_t) as sparse matrices: the linear parts plus the force's entries.
template <class ModelT>
py::tuple sparse_tangent(ModelT& md, const Vector& u, const Vector& v, double t) {
  if (!md.has_sparse_tangent())
    raise_value_error("model", "its force gives its tangent only as a dense matrix (a Python force callable)");
  std::vector<nvib::Entry> ke, ce;
  md.tangent_entries(ke, ce);
  std::vector<double> kv(ke.size()), cv(ce.size());
  nvib::Stats st;
  md.tangent_values(u, v, t, kv.data(), cv.data(), st);
  auto build = [&](const nvib::SparseMatrix& lin, const std::vector<nvib::Entry>& e, const std::vector<double>& x) {
    std::vector<Eigen::Triplet<double, int>> all;
    for (size_t k = 0; k < e.size(); ++k) all.emplace_back(e[k].row, e[k].col, x[k]);
    for (Index j = 0; j < lin.outerSize(); ++j)
      for (nvib::SparseMatrix::InnerIterator it(lin, j); it; ++it) all.emplace_back(it.row(), int(j), it.value());
    nvib::SparseMatrix A(md.size(), md.size());
    A.setFromTriplets(all.begin(), all.end());
    return A;
  };
  return py::make_tuple(build(md.K(), ke, kv), build(md.C(), ce, cv));
}

// A law driven along a path of (d, d', t), each point a trial from the committed state and then a
// commit (as OpenSees' testUniaxialMaterial drives a material): forces, both slopes and the internal
// variables after each point.
inline py::tuple drive(const fx::Effect& e, const std::vector<double>& d, const std::vector<double>& dd,
                       const std::vector<double>& t) {
  const size_t n = d.size();
  if (dd.size() != n) raise_value_error("rate", "expected " + std::to_string(n) + " values (as many as d), got " + std::to_string(dd.size()));
  if (t.size() != n) raise_value_error("t", "expected " + std::to_string(n) + " values (as many as d), got " + std::to_string(t.size()));
  return fx::dispatch(e.law, [&](auto L) {
    using Lw = decltype(L);
    constexpr size_t W = fx::law::state_width<Lw>();
    std::vector<double> f(n), kd(n), kv(n), state(n * W);
    {
      py::gil_scoped_release nogil;
      const auto p = e.template params<Lw>();
      auto s = fx::law::initial<Lw>(p);
      for (size_t k = 0; k < n; ++k) {
        if constexpr (fx::law::has_state<Lw>) {
          const auto r = Lw::trial(p, s, d[k], dd[k], t[k]);
          f[k] = r.f;
          kd[k] = r.kd;
          kv[k] = r.kv;
          s = r.state;
          std::memcpy(state.data() + k * W, &s, sizeof s);
        } else {
          f[k] = Lw::value(p, d[k], dd[k], t[k]);
          const fx::Slopes sl = Lw::slopes(p, d[k], dd[k], t[k]);
          kd[k] = sl.kd;
          kv[k] = sl.kv;
        }
      }
    }
    py::dict st;
    for (size_t w = 0; w < W; ++w) {
      py::array_t<double> col(n);
      for (size_t k = 0; k < n; ++k) col.mutable_data()[k] = state[k * W + w];
      st[Lw::state_names[w]] = col;
    }
    return py::make_tuple(py::array_t<double>(n, f.data()), py::array_t<double>(n, kd.data()),
                          py::array_t<double>(n, kv.data()), st);
  });
}

inline void bind_models(py::module_& m) {
  using fx::Effect;
  m.def("drive", &drive, py::arg("effect"), py::arg("d"), py::arg("rate"), py::arg("t"),
        "a law along a path of (d, d', t), committed point by point: (force, df/dd, df/dd', state dict)");
  m.def("laws", &laws, "the built-in effect types: their parameters, signal and flags");
  py::class_<Effect>(m, "Effect", "One declared effect: a law on its measure d = g . u.")
      .def(py::init([](const std::string& type, std::vector<Index> index, std::vector<double> coef,
                       const py::dict& parameters, const std::string& name, const std::string& signal,
                       double amplitude, double omega, double phase, std::vector<double> t, std::vector<double> values) {
             if (index.size() != coef.size()) raise_value_error("measure", "index and coef lengths differ");
             fx::Measure g;
             for (size_t i = 0; i < index.size(); ++i) g.emplace_back(index[i], coef[i]);
             std::vector<std::pair<std::string, double>> named;
             for (auto item : parameters) {
               const std::string key = item.first.cast<std::string>();
               named.emplace_back(key, to_real(item.second, key));
             }
             return fx::make_effect(parse_law(type), std::move(g), named,
                                    make_signal(signal, amplitude, omega, phase, std::move(t), std::move(values)), name);
           }),
           py::arg("type"), py::arg("index"), py::arg("coef"), py::arg("parameters") = py::dict(), py::kw_only(),
           py::arg("name") = "", py::arg("signal") = "none", py::arg("amplitude") = 0.0, py::arg("omega") = 0.0,
           py::arg("phase") = 0.0, py::arg("t") = std::vector<double>{}, py::arg("values") = std::vector<double>{})
      .def_property_readonly("type", [](const Effect& e) { return e.key(); })
      .def_readonly("name", &Effect::name)
      .def_readonly("index", &Effect::index)
      .def_readonly("coef", &Effect::coef)
      .def_property_readonly("parameters", &effect_parameters, "the declared parameters by name")
      .def_property_readonly("uses_velocity", &Effect::uses_velocity)
      .def_property_readonly("uses_time", &Effect::uses_time)
      .def_property_readonly("is_linear", &Effect::is_linear)
      .def_property_readonly("is_load", &Effect::is_load)
      .def_property_readonly("has_state", &Effect::has_state, "the law has memory (internal variables)")
      .def("value", &Effect::value, py::arg("d"), py::arg("dd"), py::arg("t"),
           "the law f(d, d', t) (from its initial state, for a law with memory)")
      .def("__repr__", [](const Effect& e) {
        return std::string("Effect(") + e.key() + (e.name.empty() ? "" : ", name='" + e.name + "'") + ")";
      });

  py::class_<fx::EffectArray>(m, "EffectArray",
                              "Many effects of one law: d_k = u[i_k] - u[j_k] (j_k < 0: the ground), each "
                              "parameter one value or one per effect.")
      .def(py::init(&make_array), py::arg("type"), py::arg("i"), py::arg("j"), py::arg("parameters"), py::arg("n"),
           py::kw_only(), py::arg("name") = "", py::arg("signal") = "none", py::arg("amplitude") = 0.0,
           py::arg("omega") = 0.0, py::arg("phase") = 0.0, py::arg("t") = std::vector<double>{},
           py::arg("values") = std::vector<double>{})
      .def_property_readonly("type", [](const fx::EffectArray& a) { return a.key(); })
      .def_readonly("name", &fx::EffectArray::name)
      .def_property_readonly("size", &fx::EffectArray::size)
      .def("__len__", &fx::EffectArray::size)
      .def_property_readonly("i", [](const fx::EffectArray& a) { return py::array_t<std::int32_t>(a.i.size(), a.i.data()); })
      .def_property_readonly("j", [](const fx::EffectArray& a) { return py::array_t<std::int32_t>(a.j.size(), a.j.data()); })
      .def_property_readonly("parameters", [](const fx::EffectArray& a) {
        py::dict d;
        fx::dispatch(a.law, [&](auto L) {
          using Lw = decltype(L);
          for (size_t k = 0; k < Lw::parameters.size(); ++k) {
            const auto& v = a.values[k];
            if (v.size() == 1 && fx::is_unset(v[0])) continue;
            d[Lw::parameters[k].name] = v.size() == 1 ? parameter_value(Lw::parameters[k], v[0])
                                                      : py::object(py::array_t<double>(v.size(), v.data()));
          }
        });
        return d;
      }, "the declared parameters by name: one value, or an array of one per effect")
      .def_property_readonly("uses_velocity", &fx::EffectArray::uses_velocity)
      .def_property_readonly("uses_time", &fx::EffectArray::uses_time)
      .def_property_readonly("is_linear", &fx::EffectArray::is_linear)
      .def_property_readonly("is_load", &fx::EffectArray::is_load)
      .def_property_readonly("has_state", &fx::EffectArray::has_state, "the law has memory (internal variables)")
      .def("__repr__", [](const fx::EffectArray& a) {
        return std::string("EffectArray(") + a.key() + ", " + std::to_string(a.size()) + " effects" +
               (a.name.empty() ? "" : ", name='" + a.name + "'") + ")";
      });

  py::class_<PyModel>(m, "Model", "M a + K u + C v + F(u, v, t) = 0: a mass and the declared effects (C++ only), "
                                  "optionally with Python callables (then the GIL is kept during runs).")
      .def(py::init(&make_model), py::arg("mass"), py::arg("effects"), py::arg("K"), py::arg("C"), py::arg("dofs"),
           py::arg("force") = py::none(), py::arg("tangent") = py::none(), py::arg("uses_velocity") = true,
           py::arg("uses_time") = true, py::arg("laws") = std::vector<LawSpec>{},
           py::arg("arrays") = std::vector<fx::EffectArray>{}, py::arg("vector_laws") = std::vector<ArrayLawSpec>{},
           py::arg("mass_of") = py::none())
      .def_readonly("dofs", &PyModel::dofs)
      .def_property_readonly("has_python", &PyModel::python, "the model calls Python (the GIL is kept)")
      .def_property_readonly("size", [](const PyModel& p) { return p.visit([](auto& md) { return md.size(); }); })
      .def_property_readonly("uses_velocity", [](const PyModel& p) { return p.visit([](auto& md) { return md.uses_velocity(); }); })
      .def_property_readonly("uses_time", [](const PyModel& p) { return p.visit([](auto& md) { return md.uses_time(); }); })
      .def_property_readonly("is_linear", [](const PyModel& p) { return p.visit([](auto& md) { return md.is_linear(); }); })
      .def_property_readonly("accounts_energy",
                             [](const PyModel& p) { return p.visit([](auto& md) { return md.accounts_energy(); }); })
      .def_property_readonly("num_evaluated_effects", [](const PyModel& p) { return p.effects().num_evaluated(); })
      .def_property_readonly("effects", [](const PyModel& p) { return p.effects().effects(); })
      .def_property_readonly("effect_arrays", [](const PyModel& p) { return p.effects().arrays(); })
      .def_property_readonly("warnings", [](const PyModel& p) { return p.visit([](auto& md) { return md.warnings(); }); },
                             "what the accepted model still wants said (a nearly singular mass, a nearly symmetric K)")
      .def_property_readonly("mass_kind", [](const PyModel& p) {
        return p.visit([](auto& md) {
          const auto k = md.mass().kind();
          return k == nvib::Mass::Kind::diagonal ? "diagonal" : k == nvib::Mass::Kind::sparse ? "sparse" : "dense";
        });
      })
      .def_property_readonly("mass_matrix", [](const PyModel& p) { return p.visit([](auto& md) { return md.mass().matrix(); }); })
      .def_property_readonly("mass_sparse", [](const PyModel& p) { return p.visit([](auto& md) { return md.mass().sparse_matrix(); }); })
      .def_property_readonly("K", [](const PyModel& p) { return linear_matrix(p, true); },
                             "the linear stiffness: K given, linear springs (those of arrays included)")
      .def_property_readonly("C", [](const PyModel& p) { return linear_matrix(p, false); },
                             "the linear damping: C given, linear dampers (those of arrays included)")
      .def("same_linear_parts", [](const PyModel& p, const PyModel& q) {
        // K and C (springs and dampers of arrays included) equal, entry by entry (the same pattern, equal
        // values): what was computed from one model's linear part holds for the other
        auto same = [](const nvib::SparseMatrix& a, const nvib::SparseMatrix& b) {
          if (a.rows() != b.rows() || a.cols() != b.cols() || a.nonZeros() != b.nonZeros()) return false;
          for (Index j = 0; j < a.outerSize(); ++j) {
            nvib::SparseMatrix::InnerIterator x(a, j), y(b, j);
            for (; x && y; ++x, ++y)
              if (x.row() != y.row() || !(x.value() == y.value())) return false;
            if (x || y) return false;
          }
          return true;
        };
        return same(linear_matrix(p, true), linear_matrix(q, true)) && same(linear_matrix(p, false), linear_matrix(q, false));
      }, py::arg("other"), "K and C equal to the other model's, entry by entry (the stability check's modes hold for both)")
      .def_property_readonly("linear_product", [](const PyModel& p) {
        return p.visit([](auto& md) { return std::string(md.linear_product().form_name()); }); },
                             "how K u + C v is taken: band, rayleigh (C = alpha m + beta K, lumped m), shared "
                             "(C on K's pattern), rows or none")
      .def_property_readonly("linear_product_block", [](const PyModel& p) {
        return p.visit([](auto& md) { return md.linear_product().node_block(); }); },
                             "the rayleigh or shared product's node blocks: 3 or 2 where K (and C) are held by blocks of that many DOFs, else 0")
      .def_property_readonly("has_state", [](const PyModel& p) { return p.visit([](auto& md) { return md.has_state(); }); },
                             "some law has memory (internal variables)")
      .def_property_readonly("state_size", [](const PyModel& p) { return p.visit([](auto& md) { return md.state_size(); }); })
      .def("_verify_commits", [](PyModel& p, bool on) { p.effects().verify_commits(on); }, py::arg("on"),
           "tests: check every commit of a last trial against a new trial at the accepted state")
      .def_property_readonly("has_sparse_tangent", [](const PyModel& p) {
        return p.visit([](auto& md) { return md.has_sparse_tangent(); });
      })
      .def("potential", [](PyModel& p, const Vector& u, double t) { return p.visit([&](auto& md) { return md.potential(u, t); }); },
           py::arg("u"), py::arg("t") = 0.0)
      .def("kinetic", [](PyModel& p, const Vector& v) { return p.visit([&](auto& md) { return md.kinetic(v); }); },
           py::arg("v"))
      .def("force",
           [](PyModel& p, const Vector& u, const Vector& v, double t) {
             return p.visit([&](auto& md) {
               nvib::Stats st;
               Vector out(md.size());
               md.force(u, v, t, out, st);
               return out;
             });
           },
           py::arg("u"), py::arg("v"), py::arg("t"), "K u + C v + F(u, v, t)")
      .def("tangent",
           [](PyModel& p, const Vector& u, const Vector& v, double t) {
             return p.visit([&](auto& md) {
               nvib::Stats st;
               Matrix K(md.size(), md.size()), C(md.size(), md.size());
               md.tangent(u, v, t, K, C, st);
               return py::make_tuple(K, C);
             });
           },
           py::arg("u"), py::arg("v"), py::arg("t"), "(K_t, C_t), dense")
      .def("tangent_sparse",
           [](PyModel& p, const Vector& u, const Vector& v, double t) {
             return p.visit([&](auto& md) { return sparse_tangent(md, u, v, t); });
           },
           py::arg("u"), py::arg("v"), py::arg("t"), "(K_t, C_t), sparse (models whose tangent is known entry by entry)")
      .def("static_equilibrium",
           [](PyModel& p, double t, const Vector& guess, double rtol, int max_iter) {
             return p.visit([&](auto& md) { return nvib::static_equilibrium(md, t, guess, rtol, max_iter); });
           },
           py::arg("t"), py::arg("u_guess"), py::arg("rtol"), py::arg("max_iter"),
           "u with K u + F(u, 0, t) = 0, by the Newton component");
}

}  // namespace nvib_py
